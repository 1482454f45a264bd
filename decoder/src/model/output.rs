//! The output stage: what a trained model does to the network's raw outputs before anyone sees
//! them. First the rest stage (the dead zone at rest, [`RestStage`], when the model has one),
//! then the directions the calibration never taught held at 0 ([`Taught`]).
//!
//! Both are non-decreasing per finger, so the stage is too, with slope at most the rest stage's
//! ([`OutputStage::max_slope`]): the exact verifier reads a polynomial through it at the same
//! critical points. The [`super::Predictor`] (daemon, eval, decode, replay) and the verifier
//! (`verify`, the check at `train`) both call [`OutputStage::map`]: one path.

use super::dataset::N_FINGERS;
use super::rest::RestStage;
use super::taught::Taught;

/// The label a finger gets from a model's output: clamped to full scale, `[-1, 1]` (the
/// labels' range: `F = kF·label`, `α = kα·label`), a non-finite output to 0 (rest: the caller
/// reports it as a fault). Non-decreasing with slope at most 1 on finite outputs. The daemon's
/// conditioner and the check beyond full effort ([`super::verify::verify_beyond`]) both call
/// it: the verifier judges the label the hand gets.
#[inline]
pub fn hand_label(y: f64) -> f64 {
    if y.is_finite() {
        y.clamp(-1.0, 1.0)
    } else {
        0.0
    }
}

/// The rest stage then the taught-direction hold.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OutputStage {
    /// The dead zone at rest (None: raw outputs).
    pub rest: Option<RestStage>,
    /// The directions held at 0.
    pub taught: Taught,
}

impl OutputStage {
    /// `finger`'s final output for raw output `y`.
    #[inline]
    pub fn map(&self, finger: usize, y: f64) -> f64 {
        let v = match &self.rest {
            Some(st) => st.map(finger, y),
            None => y,
        };
        self.taught.hold(finger, v)
    }

    /// [`OutputStage::map`] on all five outputs in place: no allocation.
    #[inline]
    pub fn apply(&self, y: &mut [f64; N_FINGERS]) {
        if let Some(st) = &self.rest {
            st.apply(y);
        }
        self.taught.apply(y);
    }

    /// An upper bound on the slope of [`OutputStage::map`] for `finger` (the hold's is 1).
    pub fn max_slope(&self, finger: usize) -> f64 {
        self.rest.map_or(1.0, |st| st.max_slope(finger))
    }

    /// Whether the stage changes nothing (no rest stage, every direction taught).
    pub fn is_identity(&self) -> bool {
        self.rest.is_none() && self.taught.is_both()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_rest_stage_runs_first_then_the_hold() {
        let rest = RestStage::try_new([0.2; N_FINGERS], [0.1; N_FINGERS], 4.0).unwrap();
        let mut taught = Taught::BOTH;
        taught.extension[1] = false;
        let s = OutputStage {
            rest: Some(rest),
            taught,
        };
        assert_eq!(s.map(1, -0.8), 0.0);
        assert_eq!(s.map(0, -0.8), rest.map(0, -0.8));
        assert_eq!(s.map(1, 0.8), rest.map(1, 0.8));
        let mut y = [-0.8, -0.8, 0.5, 0.0, 1.0];
        s.apply(&mut y);
        assert_eq!(y, [rest.map(0, -0.8), 0.0, rest.map(2, 0.5), 0.0, 1.0]);
        assert_eq!(s.max_slope(3), rest.max_slope(3));
        assert!(!s.is_identity());
        let id = OutputStage {
            rest: None,
            taught: Taught::BOTH,
        };
        assert!(id.is_identity());
        assert_eq!((id.map(2, -3.5), id.max_slope(2)), (-3.5, 1.0));
    }
}
