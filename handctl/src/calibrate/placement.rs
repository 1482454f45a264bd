//! Placing a trial on the recording from its cue times, taking the reaction time into account.
//!
//! The cue says HOLD at `hold_start`, but the patient starts contracting a reaction time later
//! (a few hundred ms) and keeps contracting a reaction time after RELAX. A trial placed at the
//! cue times would begin with windows of rest EMG labelled +1 or -1: the quality gates average
//! a trial's RMS over its windows, so those windows dilute its contrast against rest (a good
//! contraction could fail the contrast gate, a weak one hide behind the mean), and training
//! would learn "rest EMG means full flexion". So the onset is measured from the EMG itself:
//!
//! - the plateau is the median level (mean channel RMS, the monitor's 10 Hz trace) over the
//!   hold after `MAX_REACTION_US`;
//! - the onset is the first trace point after the HOLD cue whose level reaches halfway from
//!   the rest level to the plateau, bounded to `MAX_REACTION_US` after the cue (no onset found
//!   within it: the bound, and the trial's check judges what it holds);
//! - the trial runs from the onset to the RELAX cue (the patient is still contracting then).
//!
//! A rest trial has no onset: it runs from its HOLD cue to its RELAX cue.

use decoder::session::TrialKind;

use super::sequencer::HoldTimes;

/// Longest reaction accepted, µs: a later onset is clamped to this.
pub const MAX_REACTION_US: u64 = 1_000_000;

/// The trial's (start, end) on the recording's time base, µs, and the measured reaction, µs.
pub fn place(
    hold: &HoldTimes,
    kind: TrialKind,
    trace: &[(u64, f64)],
    rest_level: Option<f64>,
) -> (u64, u64, Option<u64>) {
    let (start, end) = (hold.hold_start_us, hold.hold_end_us);
    if kind == TrialKind::Rest {
        return (start, end, None);
    }
    let bound = (start + MAX_REACTION_US).min(end.saturating_sub(1));
    let mut plateau: Vec<f64> = trace
        .iter()
        .filter(|&&(t, _)| t >= bound && t < end)
        .map(|&(_, l)| l)
        .collect();
    plateau.sort_by(f64::total_cmp);
    let Some(&plateau) = plateau.get(plateau.len() / 2) else {
        return (bound, end, None);
    };
    let rest = rest_level.unwrap_or(0.0);
    if plateau <= rest {
        return (bound, end, None);
    }
    let half = rest + 0.5 * (plateau - rest);
    let onset = trace
        .iter()
        .find(|&&(t, l)| t >= start && t <= bound && l >= half)
        .map(|&(t, _)| t);
    match onset {
        Some(t) => (t, end, Some(t - start)),
        None => (bound, end, None),
    }
}

/// The mean level over `[start, end)` of the trace, if it has points there.
pub fn mean_level(trace: &[(u64, f64)], start: u64, end: u64) -> Option<f64> {
    let (s, n) = trace
        .iter()
        .filter(|&&(t, _)| t >= start && t < end)
        .fold((0.0, 0usize), |(s, n), &(_, l)| (s + l, n + 1));
    (n > 0).then(|| s / n as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_onset_is_where_the_level_reaches_halfway_and_is_bounded() {
        let hold = HoldTimes {
            trial: 1,
            attempt: 0,
            hold_start_us: 1_000_000,
            hold_end_us: 4_000_000,
        };
        // Rest 10 µV until 1.3 s, 100 µV after.
        let trace: Vec<(u64, f64)> = (0..50)
            .map(|i| {
                let t = i * 100_000;
                (t, if t < 1_300_000 { 10.0 } else { 100.0 })
            })
            .collect();
        let (s, e, r) = place(&hold, TrialKind::Flexion, &trace, Some(10.0));
        assert_eq!((s, e, r), (1_300_000, 4_000_000, Some(300_000)));
        // Never contracting: the bound.
        let flat: Vec<(u64, f64)> = trace.iter().map(|&(t, _)| (t, 10.0)).collect();
        let (s, _, r) = place(&hold, TrialKind::Extension, &flat, Some(10.0));
        assert_eq!((s, r), (2_000_000, None));
        assert_eq!(
            place(&hold, TrialKind::Rest, &trace, None),
            (1_000_000, 4_000_000, None)
        );
        assert_eq!(mean_level(&trace, 1_300_000, 1_500_000), Some(100.0));
    }
}
