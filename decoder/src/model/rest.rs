//! The rest stage: per finger, a soft dead zone fitted from the calibration's rest windows, so
//! that a relaxed hand stays still.
//!
//! A bias-free model maps zero input to zero, but a relaxed forearm is not silent: its rest
//! windows give small outputs that drift (on the 3DC test recordings, 0.07 to 0.13 on average).
//! After training, the model's outputs on every rest window of the calibration are read per
//! finger; the [`RestFit::quantile`] of the positive side gives the finger's upper width `up`,
//! that of the negative side the lower width `down` (each at most [`RestFit::max_width`]). The
//! stage then maps a finger's output `y` to
//!
//! `g(y) = h(y; up) / h(1; up)` for `y >= 0`, `g(y) = -h(-y; down) / h(1; down)` for `y < 0`,
//!
//! with `h(u; d) = u - d·φ(u/d)`, `φ(t) = t / (1 + t^n)^(1/n)` (a smooth `min(t, 1)`, `n` the
//! [`RestStage::sharpness`]), and `h(u; 0) = u`. So `h` is continuous, strictly increasing
//! (`h'(u) = 1 - φ'(u/d)`, and `0 < φ' < 1` for `u > 0`), near zero below `d` and `u - d`
//! above it. Hence `g` is continuous and strictly increasing, `g(0) = 0`, `g(±1) = ±1`: it keeps
//! every monotonic curve monotonic, every output's sign and every ranking (direction accuracy
//! and AUC are unchanged), and full effort still means full effort. Its slope is at most
//! `1 / h(1; d)` ([`RestStage::max_slope`]).
//!
//! The stage is part of [`super::TrainedModel`]'s output (its predictor, the verification,
//! the model file), so eval, decode, verification and the daemon share one path.

use serde::{Deserialize, Serialize};

use super::dataset::N_FINGERS;
use super::error::{ModelError, TrainError};

/// Largest dead-zone width accepted, in output units (full effort is 1).
pub const MAX_REST_WIDTH: f64 = 0.9;
/// Sharpness `n` of the knee written by [`RestStage::fit`].
pub const REST_SHARPNESS: f64 = 4.0;

/// How the rest stage is fitted after training (part of [`super::TrainConfig`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RestFit {
    /// Quantile of the rest outputs, per finger and side, that sets the dead zone's width
    /// (default 0.97), in `[0.5, 1]`.
    pub quantile: f64,
    /// Upper bound on either width (default 0.5), in `[0, MAX_REST_WIDTH]`.
    pub max_width: f64,
}

impl Default for RestFit {
    fn default() -> Self {
        RestFit {
            quantile: 0.97,
            max_width: 0.5,
        }
    }
}

impl RestFit {
    /// Checks both fields; the error names the field and its range.
    pub fn validate(&self) -> Result<(), TrainError> {
        if !(0.5..=1.0).contains(&self.quantile) {
            return Err(TrainError::Config(format!(
                "rest stage quantile must be in [0.5, 1], got {}",
                self.quantile
            )));
        }
        if !(0.0..=MAX_REST_WIDTH).contains(&self.max_width) {
            return Err(TrainError::Config(format!(
                "rest stage max_width must be in [0, {MAX_REST_WIDTH}], got {}",
                self.max_width
            )));
        }
        Ok(())
    }
}

/// The fitted stage: per finger the dead zone's width above and below zero. Written and read
/// as its three settings; what is read is not validated here: the model file's reader checks
/// it with [`RestStage::try_new`] and names the section in its error.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(from = "StageSettings", into = "StageSettings")]
pub struct RestStage {
    up: [f64; N_FINGERS],
    down: [f64; N_FINGERS],
    sharpness: f64,
    /// `h(1; d)` per finger above and below zero, `g`'s normalisation: computed once here, not
    /// twice per output in the tick (the same value, so the same bits).
    knee_up: [f64; N_FINGERS],
    knee_down: [f64; N_FINGERS],
}

/// What the model file records of a [`RestStage`].
#[derive(Serialize, Deserialize)]
struct StageSettings {
    up: [f64; N_FINGERS],
    down: [f64; N_FINGERS],
    sharpness: f64,
}

impl From<StageSettings> for RestStage {
    fn from(s: StageSettings) -> Self {
        RestStage::unchecked(s.up, s.down, s.sharpness)
    }
}

impl From<RestStage> for StageSettings {
    fn from(s: RestStage) -> Self {
        StageSettings {
            up: s.up,
            down: s.down,
            sharpness: s.sharpness,
        }
    }
}

/// `h(u; d)` for `u >= 0` (see the module docs).
#[inline]
fn knee(u: f64, d: f64, n: f64) -> f64 {
    if d == 0.0 {
        return u;
    }
    // u - d·t/r with r = (1 + t^n)^(1/n) >= 1, written as u·(r - 1)/r with r - 1 from
    // expm1/ln_1p: every factor is >= 0, so the knee never dips below 0 by rounding near
    // u = 0 (the direct difference did, by 4e-18, on aarch64's powf).
    let t = u / d;
    let r_minus_1 = ((t.powf(n)).ln_1p() / n).exp_m1();
    u * (r_minus_1 / (1.0 + r_minus_1))
}

/// The `q` quantile of `v` (nearest rank; `v` not empty).
fn quantile(v: &mut [f64], q: f64) -> f64 {
    v.sort_by(f64::total_cmp);
    v[((v.len() - 1) as f64 * q).round() as usize]
}

impl RestStage {
    /// A stage with these widths (each finite, in `[0, MAX_REST_WIDTH]`) and sharpness (finite,
    /// in `[1, 64]`); the error names the finger and side at fault.
    pub fn try_new(
        up: [f64; N_FINGERS],
        down: [f64; N_FINGERS],
        sharpness: f64,
    ) -> Result<Self, ModelError> {
        if !(1.0..=64.0).contains(&sharpness) {
            return Err(ModelError::InvalidSpec(format!(
                "rest stage sharpness must be in [1, 64], got {sharpness}"
            )));
        }
        for (side, widths) in [("up", &up), ("down", &down)] {
            if let Some((f, w)) = widths
                .iter()
                .enumerate()
                .find(|(_, w)| !(0.0..=MAX_REST_WIDTH).contains(*w))
            {
                return Err(ModelError::InvalidSpec(format!(
                    "rest stage width {side} of finger {f} is {w}: must be in [0, {MAX_REST_WIDTH}]"
                )));
            }
        }
        Ok(Self::unchecked(up, down, sharpness))
    }

    fn unchecked(up: [f64; N_FINGERS], down: [f64; N_FINGERS], sharpness: f64) -> Self {
        RestStage {
            up,
            down,
            sharpness,
            knee_up: up.map(|d| knee(1.0, d, sharpness)),
            knee_down: down.map(|d| knee(1.0, d, sharpness)),
        }
    }

    /// Fits the widths from the model's outputs on rest windows (see the module docs). Errors
    /// when there is no output or one is not finite.
    pub fn fit(rest_outputs: &[[f64; N_FINGERS]], fit: &RestFit) -> Result<Self, ModelError> {
        if rest_outputs.is_empty() {
            return Err(ModelError::InvalidSpec(
                "rest stage: no rest window to fit it from".into(),
            ));
        }
        if let Some(i) = rest_outputs
            .iter()
            .position(|y| y.iter().any(|v| !v.is_finite()))
        {
            return Err(ModelError::InvalidSpec(format!(
                "rest stage: the model's output on rest window {i} is not finite"
            )));
        }
        let mut up = [0.0; N_FINGERS];
        let mut down = [0.0; N_FINGERS];
        let mut col = vec![0.0; rest_outputs.len()];
        for f in 0..N_FINGERS {
            for (c, y) in col.iter_mut().zip(rest_outputs) {
                *c = y[f];
            }
            up[f] = quantile(&mut col, fit.quantile).clamp(0.0, fit.max_width);
            down[f] = (-quantile(&mut col, 1.0 - fit.quantile)).clamp(0.0, fit.max_width);
        }
        Self::try_new(up, down, REST_SHARPNESS)
    }

    /// Dead-zone width above zero, per finger.
    pub fn up(&self) -> &[f64; N_FINGERS] {
        &self.up
    }
    /// Dead-zone width below zero, per finger.
    pub fn down(&self) -> &[f64; N_FINGERS] {
        &self.down
    }
    /// The knee's sharpness `n`.
    pub fn sharpness(&self) -> f64 {
        self.sharpness
    }

    /// `g(y)` for `finger` (see the module docs).
    #[inline]
    pub fn map(&self, finger: usize, y: f64) -> f64 {
        let n = self.sharpness;
        if y >= 0.0 {
            knee(y, self.up[finger], n) / self.knee_up[finger]
        } else {
            -knee(-y, self.down[finger], n) / self.knee_down[finger]
        }
    }

    /// Applies the stage to all five outputs in place: no allocation.
    #[inline]
    pub fn apply(&self, y: &mut [f64; N_FINGERS]) {
        for (f, v) in y.iter_mut().enumerate() {
            *v = self.map(f, *v);
        }
    }

    /// An upper bound on the slope of `g` for `finger`: `1 / h(1; d)` of its wider side.
    pub fn max_slope(&self, finger: usize) -> f64 {
        let d = self.up[finger].max(self.down[finger]);
        1.0 / knee(1.0, d, self.sharpness)
    }
}

/// `model` with the rest stage `fit` says, fitted from its raw outputs on the rest windows of
/// `data` (every target 0, every finger in the loss). Unchanged without `fit` or without rest
/// windows (a two-point calibration has none).
pub(crate) fn with_fitted_rest(
    model: super::TrainedModel,
    data: &super::Dataset,
    fit: Option<RestFit>,
) -> Result<super::TrainedModel, ModelError> {
    let Some(fit) = fit else {
        return Ok(model);
    };
    let raw = model.with_rest_stage(None);
    let outputs: Vec<[f64; N_FINGERS]> = (0..data.len())
        .filter(|&i| data.target(i).iter().all(|&t| t == 0.0) && data.mask(i).iter().all(|&m| m))
        .map(|i| raw.predict(data.row(i)))
        .collect();
    if outputs.is_empty() {
        return Ok(raw);
    }
    let stage = RestStage::fit(&outputs, &fit)?;
    Ok(raw.with_rest_stage(Some(stage)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn the_cached_normalisation_gives_the_formula_bit_for_bit_and_survives_the_file() {
        let up = [0.0, 0.1, 0.22, 0.5, 0.9];
        let down = [0.9, 0.0, 0.1, 0.03, 0.25];
        let st = RestStage::try_new(up, down, REST_SHARPNESS).unwrap();
        for f in 0..N_FINGERS {
            for i in -300..=300 {
                let y = f64::from(i) / 100.0;
                let want = if y >= 0.0 {
                    knee(y, up[f], REST_SHARPNESS) / knee(1.0, up[f], REST_SHARPNESS)
                } else {
                    -knee(-y, down[f], REST_SHARPNESS) / knee(1.0, down[f], REST_SHARPNESS)
                };
                assert_eq!(st.map(f, y).to_bits(), want.to_bits(), "finger {f}, y {y}");
            }
        }
        let text = serde_json::to_string(&st).unwrap();
        assert!(
            !text.contains("knee"),
            "the file records the settings only: {text}"
        );
        let back: RestStage = serde_json::from_str(&text).unwrap();
        assert_eq!(back, st);
    }

    fn width() -> impl Strategy<Value = f64> {
        prop_oneof![Just(0.0), 0.0..=MAX_REST_WIDTH]
    }

    proptest! {
        /// For any widths and sharpness: ±1 maps to ±1 exactly, 0 to 0, the map is
        /// non-decreasing, keeps every sign, and its slope stays within `max_slope`.
        #[test]
        fn the_stage_is_monotonic_keeps_signs_and_maps_unit_to_unit(
            up in proptest::array::uniform5(width()),
            down in proptest::array::uniform5(width()),
            n in 1.0f64..=16.0,
            a in -3.0f64..3.0,
            b in -3.0f64..3.0,
        ) {
            let s = RestStage::try_new(up, down, n).unwrap();
            let (lo, hi) = if a <= b { (a, b) } else { (b, a) };
            for f in 0..N_FINGERS {
                prop_assert_eq!(s.map(f, 1.0), 1.0);
                prop_assert_eq!(s.map(f, -1.0), -1.0);
                prop_assert_eq!(s.map(f, 0.0), 0.0);
                let (gl, gh) = (s.map(f, lo), s.map(f, hi));
                prop_assert!(gl <= gh, "finger {f}: g({lo}) = {gl} > g({hi}) = {gh}");
                prop_assert!(gh - gl <= s.max_slope(f) * (hi - lo) * (1.0 + 1e-12) + 1e-15);
                for v in [lo, hi] {
                    let g = s.map(f, v);
                    prop_assert!(g == 0.0 || g.signum() == v.signum(), "g({v}) = {g}");
                }
            }
        }
    }

    #[test]
    fn a_wide_stage_pulls_rest_toward_zero_and_leaves_full_effort_alone() {
        let s = RestStage::try_new([0.2; N_FINGERS], [0.1; N_FINGERS], REST_SHARPNESS).unwrap();
        assert!(s.map(0, 0.1).abs() < 0.02, "{}", s.map(0, 0.1));
        assert!(s.map(0, -0.05).abs() < 0.01, "{}", s.map(0, -0.05));
        // Well above the width, the output is the shifted input, rescaled.
        let above = s.map(0, 0.8);
        assert!((above - (0.8 - 0.2) / (1.0 - 0.2)).abs() < 0.01, "{above}");
    }

    #[test]
    fn fit_reads_the_quantile_of_each_side_and_bad_input_is_refused() {
        let outputs: Vec<[f64; N_FINGERS]> = (0..=100)
            .map(|i| {
                let v = i as f64 / 100.0; // 0.00 ..= 1.00
                [0.3 * v, -0.2 * v, 0.1 * v - 0.05, 0.0, 0.9 * v]
            })
            .collect();
        let fit = RestFit {
            quantile: 0.9,
            max_width: 0.5,
        };
        let s = RestStage::fit(&outputs, &fit).unwrap();
        let close = |a: f64, b: f64| (a - b).abs() < 1e-12;
        assert!(close(s.up()[0], 0.27) && close(s.down()[0], 0.0), "{s:?}");
        assert!(
            close(s.up()[1], 0.0) && close(s.down()[1], 0.2 * 0.9),
            "{s:?}"
        );
        assert!(close(s.up()[2], 0.04) && close(s.down()[2], 0.04), "{s:?}");
        assert!(close(s.up()[3], 0.0) && close(s.down()[3], 0.0), "{s:?}");
        assert!(close(s.up()[4], 0.5), "capped at max_width: {s:?}");
        assert!(RestStage::fit(&[], &fit).is_err());
        let e = RestStage::fit(&[[0.0, f64::NAN, 0.0, 0.0, 0.0]], &fit).unwrap_err();
        assert!(e.to_string().contains("rest window 0"), "{e}");
        let e = RestStage::try_new([0.0, 0.0, -0.1, 0.0, 0.0], [0.0; N_FINGERS], 4.0);
        assert!(e.unwrap_err().to_string().contains("up of finger 2"));
        let bad = RestFit {
            quantile: 0.2,
            ..RestFit::default()
        };
        assert!(bad.validate().unwrap_err().to_string().contains("quantile"));
    }
}
