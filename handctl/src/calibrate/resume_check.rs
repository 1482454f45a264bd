//! What `--resume` checks before the next cue: that the session is recent enough to belong to
//! this fitting ([`check_age`]), and that the patient's rest, measured live for
//! [`REST_CHECK_US`], has the pattern across channels of the session's kept rest trials
//! (the comparison `handd` makes at `arm`, [`driver::rest_check`]).
//!
//! The age limit: a calibration takes minutes (the default protocol about nine); a break of an
//! hour with the electrodes left on is still the same fitting, but gel electrodes dry and the
//! skin's impedance drifts over hours, and a session older than that was very likely recorded
//! with the electrodes put on again. [`DEFAULT_MAX_RESUME_AGE_MIN`] is two hours; the age is
//! counted from the session's first recorded sample, on the bus's clock.

use decoder::session::{Recording, Session, SessionMeta, Trial, TrialKind, WindowOptions};
use driver::rest_check::compare;

use super::check::{stretches, WARMUP_US};
use super::error::CalibrateError;

/// `--max-resume-age-min`'s default: see the module docs.
pub const DEFAULT_MAX_RESUME_AGE_MIN: u64 = 120;
/// The longest `--max-resume-age-min` accepted (a day).
pub const MAX_RESUME_AGE_MIN: u64 = 24 * 60;
/// The live rest measured at `--resume` before the first cue, µs: the filters' warm-up
/// ([`WARMUP_US`]) and two seconds measured.
pub const REST_CHECK_US: u64 = WARMUP_US + 2_000_000;

/// Refuses to resume a session that started (its first sample at `started_us`) more than
/// `max_min` minutes before `now_us`, naming its age; a session with no sample yet has no age.
pub fn check_age(started_us: Option<u64>, now_us: u64, max_min: u64) -> Result<(), CalibrateError> {
    let Some(started) = started_us else {
        return Ok(());
    };
    let age_s = now_us.saturating_sub(started) / 1_000_000;
    if age_s > max_min * 60 {
        return Err(CalibrateError::Resume(format!(
            "the session started {} h {:02} min ago, more than --max-resume-age-min {max_min}: \
             electrodes and skin change over hours, so its trials and today's would not be one \
             fitting; start a new calibration in another --out",
            age_s / 3600,
            (age_s % 3600) / 60
        )));
    }
    Ok(())
}

/// The rest level per channel (the mean RMS feature of the rest windows, as a model file keeps
/// it) of `trials` on `recording`, each measured from its own stretch with the filters' warm-up
/// before it. None when no window falls inside them.
pub fn rest_levels(
    recording: &Recording,
    base: &SessionMeta,
    trials: &[Trial],
) -> Result<Option<Vec<f64>>, CalibrateError> {
    if trials.is_empty() {
        return Ok(None);
    }
    let mut meta = base.clone();
    meta.trials = trials.to_vec();
    let (segments, part) = stretches(recording, &meta.trials);
    meta.segments = segments;
    let session = Session::from_parts("(this calibration)".into(), meta, part)?;
    match session.windows(&WindowOptions::default()) {
        Ok(w) => Ok(w.rest_rms(&session.meta.trials)),
        Err(_) => Ok(None),
    }
}

/// Compares the live rest over `live` (a span of `recording` recorded just now, the patient
/// relaxed) with the rest trials kept in `base`. Ok with a line for the technician when they
/// match, when there is nothing to compare, or when `force` overrides a mismatch; a refusal
/// naming the channels otherwise.
pub fn check_rest(
    recording: &Recording,
    base: &SessionMeta,
    live: (u64, u64),
    force: bool,
) -> Result<String, CalibrateError> {
    let kept: Vec<Trial> = base
        .trials
        .iter()
        .filter(|t| t.kind == TrialKind::Rest)
        .copied()
        .collect();
    let Some(session) = rest_levels(recording, base, &kept)? else {
        return Ok(
            "no rest trial kept yet: the live rest was not compared with the session".into(),
        );
    };
    let trial = Trial {
        id: base.trials.iter().map(|t| t.id).max().unwrap_or(0) + 1,
        finger: None,
        kind: TrialKind::Rest,
        repetition: 1,
        start_us: live.0,
        end_us: live.1,
    };
    let Some(now) = rest_levels(recording, base, &[trial])? else {
        return Err(CalibrateError::Resume(
            "no EMG arrived while the rest level was measured: is the amplifier on the bus?".into(),
        ));
    };
    let c = compare(&session, &now).map_err(|e| CalibrateError::Resume(e.to_string()))?;
    if c.matches() {
        return Ok(format!(
            "the live rest pattern matches the session's rest trials ({})",
            c.summary()
        ));
    }
    if force {
        return Ok(format!(
            "WARNING: resuming although the live rest pattern differs from the session's: {} ({})",
            c.differences(),
            c.summary()
        ));
    }
    Err(CalibrateError::Resume(format!(
        "the live rest pattern differs from the session's rest trials: {} ({}). Swapped or \
         shifted electrodes, or a session from another fitting, look like this; so does a \
         patient who is not relaxed. Put the electrodes back where they were, or start a new \
         calibration in another --out; --force-rest-mismatch resumes anyway",
        c.differences(),
        c.summary()
    )))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A session's recording at 1 kHz: 12 channels of white noise, channel c at `levels[c]`
    /// RMS for the first 10 s (the session's rest trial at 3..8 s) and at `later[c]` from
    /// 10 s on (the live rest at 11..13 s).
    fn recording(levels: &[f64; 12], later: &[f64; 12]) -> (Recording, SessionMeta) {
        let mut state = 0x2545_f491_4f6c_dd1d_u64;
        let mut noise = || {
            // xorshift, then a sum of uniforms: near-Gaussian, unit variance.
            (0..12)
                .map(|_| {
                    state ^= state << 13;
                    state ^= state >> 7;
                    state ^= state << 17;
                    (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
                })
                .sum::<f64>()
        };
        let mut samples = Vec::new();
        for i in 0..14_000 {
            let l = if i < 10_000 { levels } else { later };
            samples.extend(l.iter().map(|a| a * noise()));
        }
        let r = Recording::from_samples(12, samples, 1000.0).expect("recording");
        let rest = Trial {
            id: 1,
            finger: None,
            kind: TrialKind::Rest,
            repetition: 1,
            start_us: 3_000_000,
            end_us: 8_000_000,
        };
        let meta = SessionMeta::candump(super::super::chain(50), "frames.log", 2047.0, vec![rest]);
        (r, meta)
    }

    const LEVELS: [f64; 12] = [3.0, 4.0, 9.0, 2.5, 3.0, 6.0, 12.0, 4.0, 3.5, 5.0, 2.0, 3.0];

    #[test]
    fn the_live_rest_at_resume_is_compared_with_the_sessions_rest_trials() {
        let live = (11_000_000, 13_000_000);
        // The same fitting, the level a little lower: resumed.
        let same = LEVELS.map(|a| a * 0.8);
        let (r, meta) = recording(&LEVELS, &same);
        let said = check_rest(&r, &meta, live, false).expect("the same pattern");
        assert!(said.contains("matches") && said.contains("0.8"), "{said}");
        // Channels 6 and 10 swapped since (12 and 2 µV): refused, both named.
        let mut swapped = LEVELS;
        swapped.swap(6, 10);
        let (r, meta) = recording(&LEVELS, &swapped);
        let e = check_rest(&r, &meta, live, false).unwrap_err().to_string();
        assert!(
            e.contains("channel 6 at 0.") && e.contains("channel 10 at ") && e.contains("--force"),
            "{e}"
        );
        let said = check_rest(&r, &meta, live, true).expect("forced");
        assert!(
            said.starts_with("WARNING") && said.contains("channel 6"),
            "{said}"
        );
        // No rest trial kept yet: nothing to compare with.
        let mut none = meta.clone();
        none.trials[0].kind = TrialKind::Flexion;
        none.trials[0].finger = Some(1);
        let said = check_rest(&r, &none, live, false).expect("nothing to compare");
        assert!(said.contains("no rest trial kept"), "{said}");
    }

    #[test]
    fn a_session_older_than_the_limit_is_refused_naming_its_age() {
        let h = 3_600_000_000;
        assert!(check_age(None, 10 * h, 120).is_ok(), "no sample: no age");
        assert!(
            check_age(Some(h), 3 * h, 120).is_ok(),
            "two hours: still resumed"
        );
        let e = check_age(Some(h), 3 * h + 150 * 60_000_000, 120)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("started 4 h 30 min ago") && e.contains("--max-resume-age-min 120"),
            "{e}"
        );
        assert!(check_age(Some(h), 3 * h + 150 * 60_000_000, 300).is_ok());
    }
}
