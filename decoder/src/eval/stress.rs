//! Robustness beyond the calibration (issue 25 item 6): a model's test windows replayed
//! stronger than the calibration, and with one electrode's transient.
//!
//! - **Gain**: the test recording's signal times `g` (a stronger contraction). The chain is
//!   linear and every feature is homogeneous in the signal, so this is the windows' amplitude
//!   features times `g` and VAR times `g²` ([`scale_features`], the effort ray's scaling),
//!   exactly what decoding the scaled recording gives.
//! - **Transient**: one channel at [`TRANSIENT_GAIN`] times its level, the others as they are
//!   (P7's electrode transient: one channel about ten times its usual level for about 200 ms).
//!   Every window is taken as inside such a transient, channel by channel: the worst case of a
//!   transient that may come at any time, reported for the worst channel.
//!
//! - **Transient in the signal** ([`stress_transients`], needs the session itself): one
//!   channel's raw samples at [`TRANSIENT_GAIN`] times for [`TRANSIENT_MS`] in the middle of
//!   every movement trial, the recording then run through the signal chain as recorded (the
//!   filters' own response to the step included), and only the windows that overlap a burst
//!   counted: P7's transient as it would reach the decoder.
//!
//! Each condition runs through the model's [`crate::model::Predictor`] (envelope, plausibility
//! check, output stage: the daemon's path) and counts the movement finger-windows pointing the
//! wrong way (a finger whose trial moves it, output clamped to [-1, 1] beyond
//! [`WRONG_WAY`] against the trial's direction), the largest raw |y|, the windows the envelope
//! moved back and those it found implausible (output rest).

use super::interpolation::scale_features;
use crate::dsp::FEATURES_PER_CHANNEL;
use crate::model::{hand_label, TrainedModel, N_FINGERS};
use crate::session::{LabelledWindows, Session, SessionError, TrialKind, WindowOptions};

/// The gains replayed: x1 (the recording as it is) to x5.
pub const STRESS_GAINS: [f64; 5] = [1.0, 1.5, 2.0, 3.0, 5.0];
/// One channel's level in a transient, times its own.
pub const TRANSIENT_GAIN: f64 = 10.0;
/// Length of a transient injected in the signal, ms (P7's last about 200 ms).
pub const TRANSIENT_MS: f64 = 200.0;
/// A finger points the wrong way beyond this much against its trial's direction.
pub const WRONG_WAY: f64 = 0.2;

/// What a model did under one condition.
#[derive(Debug, Clone, PartialEq)]
pub struct StressRow {
    /// The condition, e.g. "x1.5" or "channel 4 at x10".
    pub condition: String,
    /// Movement finger-windows (a finger its trial moves).
    pub movement: usize,
    /// Of those, pointing the wrong way.
    pub wrong: usize,
    /// The largest raw |y| over every window and finger.
    pub max_abs: f64,
    /// The raw output's range over every window and finger: lowest, highest.
    pub range: (f64, f64),
    /// Windows the envelope moved back into the calibration.
    pub beyond: usize,
    /// Windows found implausible (output rest).
    pub implausible: usize,
    /// Windows replayed.
    pub windows: usize,
}

impl StressRow {
    /// Wrong-way finger-windows as a share of the movement ones, in percent.
    pub fn wrong_percent(&self) -> f64 {
        100.0 * self.wrong as f64 / self.movement.max(1) as f64
    }
}

/// A model's rows: every gain of [`STRESS_GAINS`], then the transient on the worst channel
/// (most wrong-way windows; the first of equals).
#[derive(Debug, Clone, PartialEq)]
pub struct StressReport {
    /// One row per gain, in order.
    pub gains: Vec<StressRow>,
    /// The transient on the channel that fared worst.
    pub worst_transient: StressRow,
}

/// Replays `rows` (row-major, `windows.n_features` each) through `model` under `condition`.
fn replay(
    model: &TrainedModel,
    windows: &LabelledWindows,
    rows: &[f64],
    condition: String,
) -> StressRow {
    let mut p = model.predictor();
    let mut r = StressRow {
        condition,
        movement: 0,
        wrong: 0,
        max_abs: 0.0,
        range: (f64::INFINITY, f64::NEG_INFINITY),
        beyond: 0,
        implausible: 0,
        windows: windows.len(),
    };
    for (row, l) in rows.chunks_exact(windows.n_features).zip(&windows.labels) {
        let y = p.run(row);
        r.max_abs = y.iter().fold(r.max_abs, |m, v| m.max(v.abs()));
        for v in y {
            r.range = (r.range.0.min(v), r.range.1.max(v));
        }
        r.implausible += usize::from(p.last_implausible());
        r.beyond += usize::from(p.last_scale() < 1.0 && !p.last_implausible());
        for f in (0..N_FINGERS).filter(|&f| l.mask[f] && l.targets[f] != 0.0) {
            r.movement += 1;
            let s = l.targets[f].signum();
            r.wrong += usize::from(s * hand_label(y[f]) < -WRONG_WAY);
        }
    }
    r
}

/// `model` on `windows` under every condition (see the module docs). Panics if the windows do
/// not have the model's feature count (the caller checked the chain).
pub fn stress(model: &TrainedModel, windows: &LabelledWindows) -> StressReport {
    let n = windows.n_features;
    assert_eq!(n, model.normalizer().len(), "feature count");
    let mut rows = windows.features.clone();
    let gains = STRESS_GAINS
        .iter()
        .map(|&g| {
            for (out, x) in rows
                .chunks_exact_mut(n)
                .zip(windows.features.chunks_exact(n))
            {
                scale_features(x, g, out);
            }
            replay(model, windows, &rows, format!("x{g}"))
        })
        .collect();
    let mut worst: Option<StressRow> = None;
    let var = super::VAR_INDEX;
    for c in 0..n / FEATURES_PER_CHANNEL {
        rows.copy_from_slice(&windows.features);
        for row in rows.chunks_exact_mut(n) {
            for (j, v) in row
                .iter_mut()
                .enumerate()
                .skip(c * FEATURES_PER_CHANNEL)
                .take(FEATURES_PER_CHANNEL)
            {
                *v *= if j % FEATURES_PER_CHANNEL == var {
                    TRANSIENT_GAIN * TRANSIENT_GAIN
                } else {
                    TRANSIENT_GAIN
                };
            }
        }
        let r = replay(
            model,
            windows,
            &rows,
            format!("channel {c} at x{TRANSIENT_GAIN}"),
        );
        if worst.as_ref().is_none_or(|w| r.wrong > w.wrong) {
            worst = Some(r);
        }
    }
    StressReport {
        gains,
        worst_transient: worst.expect("at least one channel"),
    }
}

/// `model` on `session` (the test recording) with, channel by channel, a transient in the
/// signal in every movement trial (see the module docs): the row of the channel that fared
/// worst (most wrong-way finger-windows; the first of equals), over the windows that overlap
/// a burst. Errors when the session's signal cannot be windowed, or has no movement trial.
pub fn stress_transients(
    model: &TrainedModel,
    session: &Session,
) -> Result<StressRow, SessionError> {
    let settings = session.meta.chain.validate()?;
    let wl = settings.window_len();
    let len = (TRANSIENT_MS * settings.sample_rate_hz() / 1000.0).round() as usize;
    let bursts: Vec<std::ops::Range<usize>> = session
        .meta
        .trials
        .iter()
        .filter(|t| t.kind != TrialKind::Rest)
        .map(|t| {
            let r = session.recording.range_of(t.start_us, t.end_us);
            let mid = (r.start + r.end) / 2;
            mid.saturating_sub(len / 2).max(r.start)..(mid + len / 2).min(r.end)
        })
        .filter(|b| !b.is_empty())
        .collect();
    if bursts.is_empty() {
        return Err(SessionError::Spec(format!(
            "{}: no movement trial to inject a transient into",
            session.name.display()
        )));
    }
    let channels = session.recording.channels;
    let mut worst: Option<StressRow> = None;
    for c in 0..channels {
        let mut s = session.clone();
        for b in &bursts {
            for i in b.clone() {
                s.recording.samples[i * channels + c] *= TRANSIENT_GAIN;
            }
        }
        let all = s.windows(&WindowOptions::default())?;
        let mut hit = LabelledWindows {
            n_features: all.n_features,
            features: Vec::new(),
            labels: Vec::new(),
        };
        for (i, l) in all.labels.iter().enumerate() {
            let start = l.end_sample.saturating_sub(wl);
            if bursts
                .iter()
                .any(|b| start < b.end && l.end_sample > b.start)
            {
                hit.features.extend_from_slice(all.row(i));
                hit.labels.push(*l);
            }
        }
        let condition = format!("channel {c} at x{TRANSIENT_GAIN} for {TRANSIENT_MS} ms");
        let r = replay(model, &hit, &hit.features, condition);
        if worst.as_ref().is_none_or(|w| r.wrong > w.wrong) {
            worst = Some(r);
        }
    }
    Ok(worst.expect("at least one channel"))
}

/// The reports of several models side by side: one line per condition, per model the
/// wrong-way share and the largest |y|.
pub fn stress_table(models: &[(String, StressReport)]) -> String {
    let mut out = format!(
        "Beyond the calibration: movement finger-windows pointing the wrong way (clamped output \
         beyond {WRONG_WAY} against the trial), largest raw |y|; windows the envelope moved \
         back / found implausible (rest)\n{:<22}",
        "condition"
    );
    for (name, _) in models {
        out.push_str(&format!(" | {name:<38}"));
    }
    out.push('\n');
    let Some((_, first)) = models.first() else {
        return out;
    };
    let n_rows = first.gains.len() + 1;
    for i in 0..n_rows {
        let row_of = |r: &StressReport| -> StressRow {
            r.gains
                .get(i)
                .cloned()
                .unwrap_or_else(|| r.worst_transient.clone())
        };
        let label = if i < first.gains.len() {
            row_of(first).condition
        } else {
            format!("worst channel at x{TRANSIENT_GAIN}")
        };
        out.push_str(&format!("{label:<22}"));
        for (_, r) in models {
            let row = row_of(r);
            let cell = format!(
                "{:.2}%, |y| {:.3}, {}/{}{}",
                row.wrong_percent(),
                row.max_abs,
                row.beyond,
                row.implausible,
                if i < first.gains.len() {
                    String::new()
                } else {
                    format!(" ({})", row.condition)
                }
            );
            out.push_str(&format!(" | {cell:<38}"));
        }
        out.push('\n');
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{AnyModel, ModelKind, ModelSpec, Normalizer, TrainedModel, TrainingSummary};
    use crate::session::WindowLabel;

    /// On a random ResDD without an envelope, the x1 row counts exactly what the model's own
    /// predictions give, and the table names every condition.
    #[test]
    fn the_rows_count_what_the_predictor_outputs() {
        let chain = crate::dsp::ChainConfig {
            channels: 2,
            ..crate::dsp::ChainConfig::default()
        };
        let n = 2 * FEATURES_PER_CHANNEL;
        let spec = ModelSpec::default();
        let model = AnyModel::random(ModelKind::ResDd, &spec, n, N_FINGERS, 3).unwrap();
        let m = TrainedModel::new(
            model,
            spec,
            Normalizer::identity(n),
            chain,
            TrainingSummary::untrained(ModelKind::ResDd),
        )
        .unwrap();
        let features: Vec<f64> = (0..4 * n).map(|j| 0.1 + (j % 7) as f64 * 0.05).collect();
        let labels = (0..4)
            .map(|i| WindowLabel {
                trial: 0,
                targets: [if i % 2 == 0 { 1.0 } else { -1.0 }; N_FINGERS],
                mask: [true; N_FINGERS],
                end_sample: i,
            })
            .collect();
        let w = LabelledWindows {
            n_features: n,
            features,
            labels,
        };
        let r = stress(&m, &w);
        assert_eq!(r.gains.len(), STRESS_GAINS.len());
        // x1 is the windows as they are: the same outputs as the model's own predictions.
        let direct = m.predict_rows(&w.features);
        let (mut wrong, mut max) = (0, 0.0f64);
        for (y, l) in direct.iter().zip(&w.labels) {
            for (v, t) in y.iter().zip(&l.targets) {
                max = max.max(v.abs());
                wrong += usize::from(t * hand_label(*v) < -WRONG_WAY);
            }
        }
        let x1 = &r.gains[0];
        assert_eq!((x1.condition.as_str(), x1.movement), ("x1", 20));
        assert_eq!((x1.wrong, x1.max_abs), (wrong, max));
        assert_eq!((x1.beyond, x1.implausible), (0, 0), "no envelope");
        assert!(x1.range.0 <= x1.range.1 && x1.range.1.abs().max(x1.range.0.abs()) == max);
        assert!(r.worst_transient.condition.starts_with("channel "));
        let table = stress_table(&[("resdd".into(), r)]);
        assert!(
            table.contains("x1.5") && table.contains("worst channel at x10"),
            "{table}"
        );
    }
}
