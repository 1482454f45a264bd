//! The effort-ray penalty (issue 12): training that keeps a decoder monotonic in effort.
//!
//! A calibration window scaled to effort `k` has its amplitude features scaled by `k` and VAR
//! by `k²` (the same ray [`crate::eval::scale_features`] and the exact verifier use; the
//! normalizer is scale-only, so a ray of normalized features is a ray of raw ones). Along the
//! ray of a flexion (`s = +1`) or extension (`s = -1`) window, the trial's finger must move in
//! the trial's direction. The penalty samples the ray at `k = 0`, one jittered point in each of
//! [`EffortPenalty::points`] equal strata of `(0, 1)`, and `k = 1`, and charges every interval
//! whose slope in the trial's direction falls short of [`EffortPenalty::min_slope`]:
//!
//! `P = Σ_j Δk_j · max(0, m − s·Δy_j / Δk_j)²`
//!
//! a Riemann sum of `∫ max(0, m − s·y'(k))² dk`. It is zero for a curve that rises with at
//! least slope `m` everywhere and grows with the size of every reversal, so its gradient pushes
//! reversals out. The jitter is redrawn every epoch, so over the epochs the whole ray is
//! covered, not a fixed grid that a reversal could hide between; the exact verifier
//! ([`super::verify`]) judges the result afterwards.
//!
//! Beyond full effort (issue 25 item 3, [`EffortPenalty::beyond`]): the predictor holds a
//! window inside the calibration's envelope, so a ray's output past its edge `k_e` is its
//! output at `k_e`; on `(1, k_e]` the model still runs, and may turn back. With `beyond > 0`
//! (default 3), that many jittered points in equal strata of `(1, k_e]` and `k_e` itself are
//! added to each ray, charged with slope margin 0 (there the output need only not go back:
//! rising with slope `m` would push it past full scale) on the label the hand gets
//! ([`hand_label`]: clamped to full scale, as the daemon's conditioner and the verifier beyond
//! full effort clamp it): an output above full scale that comes back to it costs nothing, so
//! the penalty spends the model's capacity only on the reversals a hand would show. On P4, P6
//! and P7 (seed 0) it leaves 12, 0 and 0 of the 3375, 4200 and 4075 calibration rays reversing
//! beyond full effort by more than 0.01 (worst 0.031), against 563, 54 and 1 (worst 0.756)
//! without it (`cargo test --release -p decoder --test eval_3dc -- --nocapture`; the figures,
//! and what it costs, in docs/EVALUATION.md).

use serde::{Deserialize, Serialize};

use super::dataset::N_FINGERS;
use super::error::TrainError;
use super::output::hand_label;
use super::traits::{Scratch, Trainable};
use crate::eval::scale_features;

/// Settings of the effort-ray penalty.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct EffortPenalty {
    /// Weight of the penalty against the mean squared error (default 30, tuned with Adam,
    /// whose step does not grow with the gradient; with SGD the weight multiplies the step, so
    /// use a weight near 1 there).
    pub weight: f64,
    /// Jittered efforts per ray between 0 and 1, besides both ends (default 6).
    pub points: usize,
    /// Slope in the trial's direction below which an interval is charged, label units per unit
    /// of effort; the ideal `y = s·k` has slope 1 (default 0.3).
    pub min_slope: f64,
    /// Jittered efforts per ray between full effort and the ray's envelope edge, besides the
    /// edge itself (default 3; 0 stops the penalty at full effort, as before issue 25, and as
    /// a model file written before it says).
    #[serde(default)]
    pub beyond: usize,
}

impl Default for EffortPenalty {
    fn default() -> Self {
        EffortPenalty {
            weight: 30.0,
            points: 6,
            min_slope: 0.3,
            beyond: 3,
        }
    }
}

/// Most jittered points per ray.
pub const MAX_EFFORT_POINTS: usize = 64;

impl EffortPenalty {
    /// Checks every field; the error names the field and its allowed range.
    pub fn validate(&self) -> Result<(), TrainError> {
        let bad = |m: String| Err(TrainError::Config(m));
        if !(self.weight > 0.0 && self.weight.is_finite()) {
            return bad(format!(
                "effort penalty weight must be > 0 and finite, got {}",
                self.weight
            ));
        }
        if !(1..=MAX_EFFORT_POINTS).contains(&self.points) {
            return bad(format!(
                "effort penalty points must be in 1..={MAX_EFFORT_POINTS}, got {}",
                self.points
            ));
        }
        if self.beyond > MAX_EFFORT_POINTS {
            return bad(format!(
                "effort penalty beyond must be in 0..={MAX_EFFORT_POINTS}, got {}",
                self.beyond
            ));
        }
        if !(0.0..=1.0).contains(&self.min_slope) {
            return bad(format!(
                "effort penalty min_slope must be in [0, 1], got {}",
                self.min_slope
            ));
        }
        Ok(())
    }

    /// Fills `ks` with `0`, one point per stratum `((j + u_j) / points)` for the `u_j` in
    /// `jitter` (each in `[0, 1)`), and `1`. `ks` must be `points + 2` long.
    pub fn efforts(&self, jitter: &[f64], ks: &mut [f64]) {
        assert_eq!(jitter.len(), self.points, "one jitter per stratum");
        assert_eq!(ks.len(), self.points + 2, "efforts: points + 2");
        let n = self.points as f64;
        ks[0] = 0.0;
        for (j, (k, u)) in ks[1..=self.points].iter_mut().zip(jitter).enumerate() {
            *k = (j as f64 + u) / n;
        }
        ks[self.points + 1] = 1.0;
    }

    /// Efforts per ray: both ends, the jittered points, and with [`EffortPenalty::beyond`] the
    /// points past full effort and the edge.
    pub fn n_efforts(&self) -> usize {
        self.points + 2 + if self.beyond > 0 { self.beyond + 1 } else { 0 }
    }

    /// Jitters per ray ([`EffortPenalty::points`] + [`EffortPenalty::beyond`]).
    pub fn n_jitter(&self) -> usize {
        self.points + self.beyond
    }

    /// [`EffortPenalty::efforts`], then with `beyond > 0` one point per stratum of `(1, edge]`
    /// and `edge` (`edge` <= 1: all at 1, charging nothing). `jitter` is
    /// [`EffortPenalty::n_jitter`] long, `ks` [`EffortPenalty::n_efforts`].
    pub fn efforts_to(&self, jitter: &[f64], edge: f64, ks: &mut [f64]) {
        assert_eq!(jitter.len(), self.n_jitter(), "one jitter per stratum");
        assert_eq!(ks.len(), self.n_efforts(), "efforts: n_efforts");
        let p = self.points;
        self.efforts(&jitter[..p], &mut ks[..p + 2]);
        if self.beyond == 0 {
            return;
        }
        let span = (edge - 1.0).max(0.0);
        let n = self.beyond as f64;
        for (j, (k, u)) in ks[p + 2..p + 2 + self.beyond]
            .iter_mut()
            .zip(&jitter[p..])
            .enumerate()
        {
            *k = 1.0 + span * (j as f64 + u) / n;
        }
        ks[p + 2 + self.beyond] = 1.0 + span;
    }
}

/// Buffers for one ray: the scaled input, the outputs at every effort and their gradients.
#[derive(Debug, Clone)]
pub struct RayWork {
    x: Vec<f64>,
    y: Vec<[f64; N_FINGERS]>,
    dy: Vec<[f64; N_FINGERS]>,
}

impl RayWork {
    /// Buffers for `n_inputs` features and `n_efforts` points per ray.
    pub fn new(n_inputs: usize, n_efforts: usize) -> Self {
        RayWork {
            x: vec![0.0; n_inputs],
            y: vec![[0.0; N_FINGERS]; n_efforts],
            dy: vec![[0.0; N_FINGERS]; n_efforts],
        }
    }
}

/// The penalty of one window's ray, `Σ_f P_f` over the fingers with `dirs[f] != 0` (`±1`, the
/// trial's direction for that finger), at the efforts `ks` (ascending, from
/// [`EffortPenalty::efforts`]), with slope margin `min_slope`. When `grad` is given, adds
/// `scale · ∂P/∂θ` to it. `x` is the window's normalized features; `scratch` must fit `model`.
#[allow(clippy::too_many_arguments)]
pub fn ray_penalty<M: Trainable + ?Sized>(
    model: &M,
    x: &[f64],
    dirs: &[f64; N_FINGERS],
    ks: &[f64],
    min_slope: f64,
    work: &mut RayWork,
    scratch: &mut Scratch,
    grad: Option<(&mut [f64], f64)>,
) -> f64 {
    assert!(
        ks.len() >= 2 && work.y.len() >= ks.len(),
        "ray work too small"
    );
    for (j, &k) in ks.iter().enumerate() {
        scale_features(x, k, &mut work.x);
        model.predict_with(&work.x, &mut work.y[j][..model.n_outputs()], scratch);
        work.dy[j] = [0.0; N_FINGERS];
    }
    let n = ks.len();
    let penalty = charge(&work.y[..n], &mut work.dy[..n], dirs, ks, min_slope);
    if let Some((grad, scale)) = grad {
        backward_points(model, x, ks, work, scratch, grad, scale);
    }
    penalty
}

/// The penalty of one ray from its outputs `y` at the efforts `ks` (one row per effort), adding
/// `∂P/∂y` to `dy` (same shape); see [`ray_penalty`].
pub(crate) fn charge(
    y: &[[f64; N_FINGERS]],
    dy: &mut [[f64; N_FINGERS]],
    dirs: &[f64; N_FINGERS],
    ks: &[f64],
    min_slope: f64,
) -> f64 {
    let mut penalty = 0.0;
    for j in 0..ks.len() - 1 {
        let dk = ks[j + 1] - ks[j];
        if dk <= 0.0 {
            continue;
        }
        // Past full effort the output need only not go back (see the module docs).
        let beyond = ks[j] >= 1.0;
        let min_slope = if beyond { 0.0 } else { min_slope };
        for (f, &s) in dirs.iter().enumerate().filter(|(_, &s)| s != 0.0) {
            let (a, da) = label_of(y[j][f], beyond);
            let (b, db) = label_of(y[j + 1][f], beyond);
            let r = min_slope - s * (b - a) / dk;
            if r > 0.0 {
                penalty += dk * r * r;
                // ∂(dk·r²)/∂y_{j+1} = -2·s·r, ∂/∂y_j = +2·s·r.
                dy[j + 1][f] -= 2.0 * s * r * db;
                dy[j][f] += 2.0 * s * r * da;
            }
        }
    }
    penalty
}

/// Past full effort, the label the hand gets ([`hand_label`]: clamped to full scale) and its
/// derivative; below, the output itself.
fn label_of(y: f64, beyond: bool) -> (f64, f64) {
    if beyond && y.abs() > 1.0 {
        (hand_label(y), 0.0)
    } else {
        (y, 1.0)
    }
}

/// Back-propagates the output gradients of the points that have one.
fn backward_points<M: Trainable + ?Sized>(
    model: &M,
    x: &[f64],
    ks: &[f64],
    work: &mut RayWork,
    scratch: &mut Scratch,
    grad: &mut [f64],
    scale: f64,
) {
    let n_out = model.n_outputs();
    for (j, &k) in ks.iter().enumerate() {
        if work.dy[j].iter().all(|&d| d == 0.0) {
            continue;
        }
        for d in work.dy[j].iter_mut() {
            *d *= scale;
        }
        scale_features(x, k, &mut work.x);
        let mut y = [0.0; N_FINGERS];
        model.predict_with(&work.x, &mut y[..n_out], scratch);
        model.backward(&work.x, &work.dy[j][..n_out], scratch, grad);
    }
}

/// The direction of every finger whose ray a window's label constrains: `±1` where the finger
/// counts and its target is non-zero, 0 elsewhere (rest, and fingers trained toward 0).
pub fn ray_directions(target: &[f64; N_FINGERS], mask: &[bool; N_FINGERS]) -> [f64; N_FINGERS] {
    std::array::from_fn(|f| {
        if mask[f] && target[f] != 0.0 {
            target[f].signum()
        } else {
            0.0
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn beyond_full_effort_the_points_reach_the_edge_and_charge_only_going_back() {
        let e = EffortPenalty {
            points: 2,
            beyond: 2,
            ..EffortPenalty::default()
        };
        assert_eq!((e.n_efforts(), e.n_jitter()), (7, 4));
        let mut ks = vec![0.0; 7];
        e.efforts_to(&[0.5, 0.5, 0.5, 0.5], 3.0, &mut ks);
        assert_eq!(ks, [0.0, 0.25, 0.75, 1.0, 1.5, 2.5, 3.0]);
        e.efforts_to(&[0.5, 0.5, 0.5, 0.5], 0.8, &mut ks);
        assert_eq!(&ks[3..], &[1.0; 4], "an edge at or below 1 adds nothing");
        let off = EffortPenalty {
            beyond: 0,
            ..EffortPenalty::default()
        };
        assert_eq!((off.n_efforts(), off.n_jitter()), (8, 6));
        let default = EffortPenalty::default();
        assert_eq!((default.n_efforts(), default.n_jitter()), (12, 9));
        // y = k up to 1, then flat: charged nowhere past 1 (margin 0 there), though the
        // slope margin 0.3 would charge the flat part below 1.
        let ks = [0.0, 0.5, 1.0, 2.0, 3.0];
        let y: Vec<[f64; N_FINGERS]> = [0.0, 0.5, 1.0, 1.0, 1.0]
            .iter()
            .map(|v| [*v; N_FINGERS])
            .collect();
        let mut dy = vec![[0.0; N_FINGERS]; 5];
        let dirs = [1.0, 0.0, 0.0, 0.0, 0.0];
        assert_eq!(charge(&y, &mut dy, &dirs, &ks, 0.3), 0.0);
        // Going back past 1 is charged.
        let mut back = y.clone();
        back[4][0] = 0.8;
        assert!(charge(&back, &mut dy, &dirs, &ks, 0.3) > 0.0);
        // Past full effort the hand's label is judged: above full scale and back to it is not
        // going back (the hand sees 1 throughout), and costs no gradient; below it, it is.
        let over: Vec<[f64; N_FINGERS]> = [0.0, 0.5, 1.0, 1.6, 1.0]
            .iter()
            .map(|v| [*v; N_FINGERS])
            .collect();
        let mut dy = vec![[0.0; N_FINGERS]; 5];
        assert_eq!(charge(&over, &mut dy, &dirs, &ks, 0.3), 0.0);
        assert!(dy.iter().all(|d| d[0] == 0.0));
        let mut under = over.clone();
        under[4][0] = 0.9;
        let p = charge(&under, &mut dy, &dirs, &ks, 0.3);
        // From 1.6 (the hand: 1) to 0.9 over dk 1: r = 0.1, charged dk·r² = 0.01.
        assert!((p - 0.01).abs() < 1e-12, "{p}");
        assert_eq!(dy[3][0], 0.0, "no gradient through the clamp at 1.6");
        assert!(dy[4][0] < 0.0, "raising the last label lowers the penalty");
        assert!(EffortPenalty {
            beyond: MAX_EFFORT_POINTS + 1,
            ..EffortPenalty::default()
        }
        .validate()
        .is_err());
    }
}
