//! The per-finger summary after training, from the calibration windows:
//!
//! - contrast: the mean channel RMS of the finger's own flexion and extension trials against
//!   the rest trials' (what the contrast gate measures);
//! - reach: the model's mean output on those windows, signed by the target (1 = full flexion
//!   and extension reached);
//! - off-target: the mean |output| of the four other fingers on those windows (0 = selective);
//! - monotonic: no effort ray of the finger reverses beyond the tolerance (the verification).

use std::fmt::Write as _;

use decoder::dsp::{FEATURES_PER_CHANNEL, RMS_FEATURE};
use decoder::session::{TrialKind, FINGER_NAMES, N_FINGERS};

use super::training::Trained;

/// One finger's line.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FingerSummary {
    /// Finger index.
    pub finger: usize,
    /// Windows of its own trials (0: not in the protocol).
    pub windows: usize,
    /// Contraction RMS over rest RMS.
    pub contrast: f64,
    /// Mean output times the target's sign.
    pub reach: f64,
    /// Mean |output| of the other fingers.
    pub off_target: f64,
    /// No ray of this finger reverses.
    pub monotonic: bool,
}

fn strength(row: &[f64]) -> f64 {
    let ch = row.len() / FEATURES_PER_CHANNEL;
    (0..ch)
        .map(|c| row[c * FEATURES_PER_CHANNEL + RMS_FEATURE])
        .sum::<f64>()
        / ch.max(1) as f64
}

/// Every finger's summary.
pub fn summarize(t: &Trained) -> Vec<FingerSummary> {
    let trials = &t.session.meta.trials;
    let w = &t.windows;
    let rest: Vec<f64> = (0..w.len())
        .filter(|&i| trials[w.labels[i].trial].kind == TrialKind::Rest)
        .map(|i| strength(w.row(i)))
        .collect();
    let rest = rest.iter().sum::<f64>() / rest.len().max(1) as f64;
    let mut predictor = t.model.predictor();
    let mut acc = [(0usize, 0.0, 0.0, 0.0); N_FINGERS];
    for i in 0..w.len() {
        let trial = &trials[w.labels[i].trial];
        let (Some(f), false) = (trial.finger, trial.kind == TrialKind::Rest) else {
            continue;
        };
        let y = predictor.run(w.row(i));
        let a = &mut acc[f];
        a.0 += 1;
        a.1 += strength(w.row(i));
        a.2 += y[f] * trial.kind.target();
        a.3 += (0..N_FINGERS)
            .filter(|&g| g != f)
            .map(|g| y[g].abs())
            .sum::<f64>()
            / 4.0;
    }
    (0..N_FINGERS)
        .map(|f| {
            let (n, s, r, o) = acc[f];
            let d = n.max(1) as f64;
            FingerSummary {
                finger: f,
                windows: n,
                contrast: s / d / rest,
                reach: r / d,
                off_target: o / d,
                monotonic: t
                    .report
                    .entries
                    .iter()
                    .filter(|e| e.finger == f)
                    .all(|e| e.reversing == 0),
            }
        })
        .collect()
}

/// The summary as text, ending with the next steps.
pub fn render(t: &Trained, fingers: &[FingerSummary]) -> String {
    let mut s = format!(
        "{}\n\n{:<7} {:>9} {:>7} {:>11}  {}\n",
        t.description, "finger", "contrast", "reach", "off-target", "monotonic"
    );
    for f in fingers {
        let name = FINGER_NAMES[f.finger];
        if f.windows == 0 {
            let _ = writeln!(s, "{name:<7} not calibrated alone (not in the protocol)");
            continue;
        }
        let _ = writeln!(
            s,
            "{name:<7} {:>8.1}x {:>+7.2} {:>11.3}  {}",
            f.contrast,
            f.reach,
            f.off_target,
            if f.monotonic { "yes" } else { "NO (reverses)" }
        );
    }
    let _ = write!(
        s,
        "\nmodel written: {p}\nnext steps:\n  handctl deploy {p}\n  handctl arm\n",
        p = t.path.display()
    );
    s
}
