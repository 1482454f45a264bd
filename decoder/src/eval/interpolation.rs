//! Interpolation analysis (the paper's Table 4): does the output scale smoothly with effort?
//!
//! A held-out flexion or extension window is scaled down to effort `k` in `0..=1`: amplitude-like
//! features (RMS, MAV, SD, INT, WL, DASDV, DAMV) scale with the signal, so they are multiplied
//! by `k`, and VAR, a power, by `k²`. The model's output for the trial's finger is then read
//! against the ideal `s·k` (`s` = +1 flexion, -1 extension).
//!
//! A curve *fails* when it is monotonic in neither direction: some step goes up by more than
//! the tolerance and some step goes down by more than the tolerance. A curve is *correct* when it
//! never moves against the trial's direction by more than the tolerance and ends on the trial's
//! side of zero at `k = 1`. Per curve, Spearman's rho between `s·k` and the output and the R² of
//! a straight-line fit of the output on `s·k` measure how proportional the response is.

use super::error::EvalError;
use super::stats::{linear_fit, spearman};
use crate::dsp::FEATURES_PER_CHANNEL;

/// Position of VAR (the only power-like feature) within a channel's features, in the chain's
/// order [`crate::dsp::FEATURE_NAMES`].
pub const VAR_INDEX: usize = 2;

/// How the curves are sampled and judged.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InterpolationConfig {
    /// Step of `k` from 0 to 1 (the paper: 0.05, 21 points).
    pub step: f64,
    /// A step against the curve's direction smaller than this (in output units, where full
    /// effort is 1) does not break monotonicity.
    pub tolerance: f64,
}

impl Default for InterpolationConfig {
    fn default() -> Self {
        Self {
            step: 0.05,
            tolerance: 0.01,
        }
    }
}

impl InterpolationConfig {
    /// The effort levels `0, step, 2 step, .., 1`.
    pub fn levels(&self) -> Result<Vec<f64>, EvalError> {
        if !(self.step > 0.0 && self.step <= 0.5 && self.step.is_finite()) {
            return Err(EvalError::Shape(format!(
                "interpolation step {} must be in (0, 0.5]",
                self.step
            )));
        }
        if !(self.tolerance >= 0.0 && self.tolerance.is_finite()) {
            return Err(EvalError::Shape(format!(
                "interpolation tolerance {} must be finite and >= 0",
                self.tolerance
            )));
        }
        let n = (1.0 / self.step).round() as usize;
        Ok((0..=n).map(|i| (i as f64 * self.step).min(1.0)).collect())
    }
}

/// One window to interpolate: its features, the finger read and the trial's direction.
#[derive(Debug, Clone, Copy)]
pub struct InterpolationInput<'a> {
    /// The window's features (raw, before the model's normalizer).
    pub features: &'a [f64],
    /// Finger whose output is read, 0 thumb .. 4 pinky.
    pub finger: usize,
    /// +1 for flexion, -1 for extension.
    pub sign: f64,
}

/// One interpolation curve.
#[derive(Debug, Clone, PartialEq)]
pub struct InterpolationCurve {
    /// Finger read.
    pub finger: usize,
    /// +1 flexion, -1 extension.
    pub sign: f64,
    /// Output at each effort level (levels from [`InterpolationConfig::levels`]).
    pub outputs: Vec<f64>,
    /// Monotonic in neither direction beyond the tolerance.
    pub failed: bool,
    /// Monotonic in the trial's direction and on the trial's side of zero at full effort.
    pub correct: bool,
    /// Spearman's rho of the output against `s·k`; `None` for a constant output.
    pub spearman: Option<f64>,
    /// R² of the straight-line fit of the output on `s·k` (0 for a constant output).
    pub r2: f64,
}

/// Per-finger (or pooled) summary of many curves.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct InterpolationSummary {
    /// Number of curves.
    pub curves: usize,
    /// Curves that are monotonic in neither direction.
    pub failures: usize,
    /// Curves that are monotonic in the right direction and end on the right side.
    pub correct: usize,
    /// Mean Spearman rho over curves with a defined rho.
    pub mean_spearman: f64,
    /// Curves with a constant output, left out of `mean_spearman`.
    pub constant: usize,
    /// Mean linear-fit R² over all curves.
    pub mean_r2: f64,
}

impl InterpolationSummary {
    /// Fraction of correct curves.
    pub fn correct_rate(&self) -> f64 {
        if self.curves == 0 {
            0.0
        } else {
            self.correct as f64 / self.curves as f64
        }
    }

    /// Summarises curves.
    pub fn of<'a>(curves: impl IntoIterator<Item = &'a InterpolationCurve>) -> Self {
        let mut s = Self::default();
        let (mut rho_sum, mut rho_n, mut r2_sum) = (0.0, 0usize, 0.0);
        for c in curves {
            s.curves += 1;
            s.failures += usize::from(c.failed);
            s.correct += usize::from(c.correct);
            match c.spearman {
                Some(r) => {
                    rho_sum += r;
                    rho_n += 1;
                }
                None => s.constant += 1,
            }
            r2_sum += c.r2;
        }
        if rho_n > 0 {
            s.mean_spearman = rho_sum / rho_n as f64;
        }
        if s.curves > 0 {
            s.mean_r2 = r2_sum / s.curves as f64;
        }
        s
    }
}

/// Multiplies amplitude features by `k` and VAR by `k²` into `out`.
pub fn scale_features(features: &[f64], k: f64, out: &mut [f64]) {
    for (j, (o, f)) in out.iter_mut().zip(features).enumerate() {
        *o = if j % FEATURES_PER_CHANNEL == VAR_INDEX {
            f * k * k
        } else {
            f * k
        };
    }
}

/// Judges one curve of outputs sampled at `levels`.
pub fn judge_curve(
    finger: usize,
    sign: f64,
    levels: &[f64],
    outputs: Vec<f64>,
    tolerance: f64,
) -> Result<InterpolationCurve, EvalError> {
    if levels.len() != outputs.len() {
        return Err(EvalError::LengthMismatch {
            what: "interpolation curve",
            left: levels.len(),
            right: outputs.len(),
        });
    }
    let mut rises = false;
    let mut falls = false;
    for w in outputs.windows(2) {
        let d = w[1] - w[0];
        rises |= d > tolerance;
        falls |= d < -tolerance;
    }
    // Moving against the trial's direction beyond the tolerance.
    let against = if sign > 0.0 { falls } else { rises };
    let end = outputs.last().copied().unwrap_or(0.0);
    let target: Vec<f64> = levels.iter().map(|k| sign * k).collect();
    let rho = match spearman(&target, &outputs) {
        Ok(r) => Some(r),
        Err(EvalError::NotEnoughData(_)) => None,
        Err(e) => return Err(e),
    };
    // A constant output has a perfect but meaningless straight-line fit: it is not
    // proportional to effort at all, so it scores 0.
    let r2 = if rho.is_some() {
        linear_fit(&target, &outputs)?.r2
    } else {
        0.0
    };
    Ok(InterpolationCurve {
        finger,
        sign,
        failed: rises && falls,
        correct: !against && sign * end > 0.0,
        outputs,
        spearman: rho,
        r2,
    })
}

/// Runs the analysis: for every input, the outputs of `predict` (features in, all finger
/// outputs out) at every effort level, judged as above.
pub fn interpolation_curves(
    inputs: &[InterpolationInput<'_>],
    n_outputs: usize,
    config: &InterpolationConfig,
    predict: &mut dyn FnMut(&[f64], &mut [f64]),
) -> Result<Vec<InterpolationCurve>, EvalError> {
    let levels = config.levels()?;
    let mut scaled = Vec::new();
    let mut y = vec![0.0; n_outputs];
    let mut curves = Vec::with_capacity(inputs.len());
    for input in inputs {
        if input.finger >= n_outputs {
            return Err(EvalError::Shape(format!(
                "interpolation: finger {} but the model has {n_outputs} outputs",
                input.finger
            )));
        }
        scaled.resize(input.features.len(), 0.0);
        let mut outputs = Vec::with_capacity(levels.len());
        for &k in &levels {
            scale_features(input.features, k, &mut scaled);
            predict(&scaled, &mut y);
            let v = y[input.finger];
            if !v.is_finite() {
                return Err(EvalError::NonFinite {
                    what: "model output",
                    index: input.finger,
                });
            }
            outputs.push(v);
        }
        curves.push(judge_curve(
            input.finger,
            input.sign,
            &levels,
            outputs,
            config.tolerance,
        )?);
    }
    Ok(curves)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn levels_are_twenty_one_points() {
        let l = InterpolationConfig::default().levels().unwrap();
        assert_eq!(l.len(), 21);
        assert_eq!(l[0], 0.0);
        assert_eq!(l[20], 1.0);
        assert!((l[1] - 0.05).abs() < 1e-15);
        assert!(InterpolationConfig {
            step: 0.0,
            tolerance: 0.01
        }
        .levels()
        .is_err());
    }

    #[test]
    fn var_scales_with_k_squared() {
        let f: Vec<f64> = (0..16).map(|i| 1.0 + i as f64).collect();
        let mut out = vec![0.0; 16];
        scale_features(&f, 0.5, &mut out);
        assert_eq!(out[0], 0.5);
        assert_eq!(out[2], 3.0 * 0.25);
        assert_eq!(out[10], 11.0 * 0.25);
        assert_eq!(out[11], 6.0);
    }

    #[test]
    fn a_linear_model_gives_straight_correct_curves() {
        // Output = sum of RMS features: proportional to k.
        let f = vec![0.2, 0.0, 9.0, 0.0, 0.0, 0.0, 0.0, 0.0];
        let inputs = [
            InterpolationInput {
                features: &f,
                finger: 1,
                sign: 1.0,
            },
            InterpolationInput {
                features: &f,
                finger: 0,
                sign: -1.0,
            },
        ];
        let mut predict = |x: &[f64], y: &mut [f64]| {
            y[0] = -5.0 * x[0];
            y[1] = 5.0 * x[0];
        };
        let curves =
            interpolation_curves(&inputs, 2, &InterpolationConfig::default(), &mut predict)
                .unwrap();
        for c in &curves {
            assert!(!c.failed && c.correct, "{c:?}");
            assert!((c.spearman.unwrap() - 1.0).abs() < 1e-12);
            assert!((c.r2 - 1.0).abs() < 1e-12);
            assert!((c.outputs[20] - c.sign).abs() < 1e-12);
        }
        let s = InterpolationSummary::of(&curves);
        assert_eq!((s.curves, s.failures, s.correct), (2, 0, 2));
        assert_eq!(s.correct_rate(), 1.0);
    }

    #[test]
    fn a_var_driven_model_is_monotonic_but_not_linear() {
        let f = vec![0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0];
        let inputs = [InterpolationInput {
            features: &f,
            finger: 0,
            sign: 1.0,
        }];
        let mut predict = |x: &[f64], y: &mut [f64]| y[0] = x[2];
        let c = &interpolation_curves(&inputs, 1, &InterpolationConfig::default(), &mut predict)
            .unwrap()[0];
        assert!(!c.failed && c.correct);
        assert!((c.spearman.unwrap() - 1.0).abs() < 1e-12);
        assert!(c.r2 < 0.99 && c.r2 > 0.9, "{}", c.r2);
    }

    #[test]
    fn judged_by_hand() {
        let levels = [0.0, 0.5, 1.0];
        // Up then down by more than the tolerance: a failure.
        let c = judge_curve(0, 1.0, &levels, vec![0.0, 0.8, 0.5], 0.01).unwrap();
        assert!(c.failed && !c.correct);
        // A dip within the tolerance is still monotonic.
        let c = judge_curve(
            0,
            1.0,
            &[0.0, 0.5, 0.75, 1.0],
            vec![0.0, 0.5, 0.495, 0.9],
            0.01,
        )
        .unwrap();
        assert!(!c.failed && c.correct);
        // Monotonic, but the wrong way: not a failure, not correct.
        let c = judge_curve(0, -1.0, &levels, vec![0.0, 0.4, 0.8], 0.01).unwrap();
        assert!(!c.failed && !c.correct);
        assert!((c.spearman.unwrap() + 1.0).abs() < 1e-12);
        // A flat zero output: no rho, not correct.
        let c = judge_curve(0, 1.0, &levels, vec![0.0; 3], 0.01).unwrap();
        assert!(!c.failed && !c.correct && c.spearman.is_none());
        let s = InterpolationSummary::of([&c]);
        assert_eq!((s.constant, s.curves), (1, 1));
    }

    #[test]
    fn bad_finger_or_non_finite_output_is_an_error() {
        let f = vec![1.0; 8];
        let inputs = [InterpolationInput {
            features: &f,
            finger: 5,
            sign: 1.0,
        }];
        let mut predict = |_: &[f64], _: &mut [f64]| {};
        assert!(
            interpolation_curves(&inputs, 5, &InterpolationConfig::default(), &mut predict)
                .is_err()
        );
        let inputs = [InterpolationInput {
            features: &f,
            finger: 0,
            sign: 1.0,
        }];
        let mut nan = |_: &[f64], y: &mut [f64]| y[0] = f64::NAN;
        assert!(
            interpolation_curves(&inputs, 5, &InterpolationConfig::default(), &mut nan).is_err()
        );
    }
}
