//! Every calibration window's effort ray of a session, verified, and the report for a
//! technician.

use std::fmt;

use super::error::VerifyError;
use super::ray::{RayCurves, RayVerifier};
use super::reversal::{largest_drop, Method, Reversal};
use crate::eval::{judge_curve, InterpolationConfig};
use crate::model::{ModelKind, N_FINGERS};
use crate::session::{LabelledWindows, Trial, FINGER_NAMES};

/// Default tolerance, label units (full effort is 1): the same 1% of full scale the
/// interpolation analysis forgives, far below what a user feels in a finger's position.
pub const DEFAULT_TOLERANCE: f64 = 0.01;

/// The rays of one trial for one finger.
#[derive(Debug, Clone, PartialEq)]
pub struct TrialFinger {
    /// The trial as the session names it, e.g. "trial 3 (all flexion, repetition 1)".
    pub trial: String,
    /// Finger index, 0 thumb .. 4 pinky.
    pub finger: usize,
    /// Rays (windows) checked.
    pub rays: usize,
    /// Rays whose worst reversal exceeds the tolerance.
    pub reversing: usize,
    /// The worst reversal among them.
    pub worst: Reversal,
    /// Rays whose largest reversal over the paper's 21 efforts alone exceeds the tolerance
    /// (the same measure as `reversing`, read at the samples only).
    pub sampled_reversing: usize,
    /// Rays the 21-point interpolation metric (`judge_curve`) calls non-monotonic.
    pub sampled_failed: usize,
    /// Rays the 21-point metric calls not correct (a step against the direction beyond the
    /// tolerance, or the wrong sign at full effort).
    pub sampled_not_correct: usize,
}

/// The verification of one model on one set of windows.
#[derive(Debug, Clone, PartialEq)]
pub struct VerifyReport {
    /// Model verified.
    pub kind: ModelKind,
    /// Exact or sampled.
    pub method: Method,
    /// Reversals up to this (label units) are accepted.
    pub tolerance: f64,
    /// Per trial and finger, in trial order.
    pub entries: Vec<TrialFinger>,
}

impl VerifyReport {
    /// Rays checked.
    pub fn rays(&self) -> usize {
        self.entries.iter().map(|e| e.rays).sum()
    }
    /// Rays reversing beyond the tolerance.
    pub fn reversing(&self) -> usize {
        self.entries.iter().map(|e| e.reversing).sum()
    }
    /// Rays reversing beyond the tolerance at the 21 efforts alone.
    pub fn sampled_reversing(&self) -> usize {
        self.entries.iter().map(|e| e.sampled_reversing).sum()
    }
    /// Rays the 21-point metric calls non-monotonic.
    pub fn sampled_failed(&self) -> usize {
        self.entries.iter().map(|e| e.sampled_failed).sum()
    }
    /// Rays the 21-point metric calls not correct.
    pub fn sampled_not_correct(&self) -> usize {
        self.entries.iter().map(|e| e.sampled_not_correct).sum()
    }
    /// The worst entry, if any ray was checked (the first of equals, in trial and finger
    /// order).
    pub fn worst(&self) -> Option<&TrialFinger> {
        self.entries.iter().reduce(|a, b| {
            if b.worst.amount.total_cmp(&a.worst.amount).is_gt() {
                b
            } else {
                a
            }
        })
    }
    /// True when no ray reverses beyond the tolerance.
    pub fn passed(&self) -> bool {
        self.reversing() == 0
    }
}

/// Verifies the ray of every flexion and extension window (rest windows have no direction)
/// for every finger the window's trial moves. `trials` are the session's, indexed as the
/// windows' labels index them.
pub fn verify_windows(
    verifier: &mut RayVerifier<'_>,
    windows: &LabelledWindows,
    trials: &[Trial],
    tolerance: f64,
) -> Result<VerifyReport, VerifyError> {
    check_inputs(verifier, windows, trials, tolerance)?;
    let levels = InterpolationConfig::default()
        .levels()
        .expect("the default levels are valid");
    let mut entries: Vec<TrialFinger> = Vec::new();
    for (i, label) in windows.labels.iter().enumerate() {
        let row = windows.row(i);
        let curves = verifier.curves(row);
        let paper: Vec<[f64; N_FINGERS]> =
            levels.iter().map(|&k| verifier.output_at(row, k)).collect();
        for f in (0..N_FINGERS).filter(|&f| label.mask[f] && label.targets[f] != 0.0) {
            let dir = label.targets[f].signum();
            let name = trials[label.trial].to_string();
            let at = match entries
                .iter()
                .position(|e| e.trial == name && e.finger == f)
            {
                Some(at) => at,
                None => {
                    entries.push(TrialFinger::new(name, f, verifier.method()));
                    entries.len() - 1
                }
            };
            let outputs: Vec<f64> = paper.iter().map(|y| y[f]).collect();
            let points: Vec<(f64, f64)> = levels.iter().copied().zip(outputs.clone()).collect();
            let at_samples = largest_drop(&points, dir, Method::Sampled(levels.len()));
            let judged = judge_curve(f, dir, &levels, outputs, tolerance)
                .expect("levels and outputs have one value each");
            let e = &mut entries[at];
            e.sampled_reversing += usize::from(at_samples.amount > tolerance);
            e.add(&curves, dir, tolerance, judged.failed, judged.correct);
        }
    }
    Ok(VerifyReport {
        kind: verifier.kind(),
        method: verifier.method(),
        tolerance,
        entries,
    })
}

pub(super) fn check_inputs(
    verifier: &RayVerifier<'_>,
    windows: &LabelledWindows,
    trials: &[Trial],
    tolerance: f64,
) -> Result<(), VerifyError> {
    if !(tolerance.is_finite() && tolerance >= 0.0) {
        return Err(VerifyError::Tolerance(tolerance));
    }
    if windows.n_features != verifier.n_inputs() {
        return Err(VerifyError::Features {
            expected: verifier.n_inputs(),
            found: windows.n_features,
        });
    }
    if let Some((window, l)) = windows
        .labels
        .iter()
        .enumerate()
        .find(|(_, l)| l.trial >= trials.len())
    {
        return Err(VerifyError::Trial {
            window,
            trial: l.trial,
            trials: trials.len(),
        });
    }
    Ok(())
}

impl TrialFinger {
    fn new(trial: String, finger: usize, method: Method) -> Self {
        TrialFinger {
            trial,
            finger,
            rays: 0,
            reversing: 0,
            worst: Reversal::none(method),
            sampled_reversing: 0,
            sampled_failed: 0,
            sampled_not_correct: 0,
        }
    }

    fn add(&mut self, curves: &RayCurves, dir: f64, tol: f64, failed: bool, correct: bool) {
        let r = curves.reversal(self.finger, dir);
        self.rays += 1;
        self.reversing += usize::from(r.amount > tol);
        self.sampled_failed += usize::from(failed);
        self.sampled_not_correct += usize::from(!correct);
        if r.amount > self.worst.amount || self.rays == 1 {
            self.worst = r;
        }
    }
}

impl fmt::Display for Method {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Method::Exact => write!(f, "exact (critical points of the output polynomial)"),
            Method::Sampled(n) => write!(f, "SAMPLED at {n} efforts (a lower bound, not a proof)"),
        }
    }
}

impl fmt::Display for VerifyReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "{} effort-ray check, {}; tolerance {} (label units)",
            self.kind, self.method, self.tolerance
        )?;
        for e in self.entries.iter().filter(|e| e.reversing > 0) {
            writeln!(
                f,
                "  REVERSES {} {}: {} of {} rays; worst {:.4} from effort {:.3} to {:.3}",
                e.trial,
                FINGER_NAMES.get(e.finger).copied().unwrap_or("?"),
                e.reversing,
                e.rays,
                e.worst.amount,
                e.worst.from_k,
                e.worst.to_k
            )?;
        }
        let worst = self.worst().map_or(0.0, |e| e.worst.amount);
        writeln!(
            f,
            "{} rays checked, {} reverse by more than {} (worst {worst:.4}); at the paper's 21 \
             efforts alone {} reverse, and its metric calls {} non-monotonic, {} not correct",
            self.rays(),
            self.reversing(),
            self.tolerance,
            self.sampled_reversing(),
            self.sampled_failed(),
            self.sampled_not_correct()
        )?;
        if self.passed() {
            writeln!(f, "every finger follows its effort: monotonic on every ray")?;
        } else {
            writeln!(
                f,
                "some fingers move against the effort: recalibrate, or retrain and verify again"
            )?;
        }
        Ok(())
    }
}
