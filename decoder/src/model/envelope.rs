//! The calibration's envelope: what the decoder is allowed to see (issue 25).
//!
//! ResDD is near-linear inside the signal its calibration saw and verified monotone along
//! every calibration ray there (`verify`). Outside, its products of inputs grow as powers of
//! the input: a grip twice as strong as the calibration's maximum, or one electrode pressed to
//! ten times its level, drives the outputs to hundreds or thousands, of either sign. Clamped to
//! [-1, 1] such an output can point the wrong way: the worst thing a prosthesis can do.
//!
//! The envelope is, per input feature, the largest value the calibration's windows reached
//! (every window of the session the model was trained on: rest, flexion and extension of every
//! finger). A window beyond it is moved back along its own effort ray until no feature is
//! beyond: the ray of the verification, which scales the window's signal by `k` (amplitude
//! features scale by `k`, VAR by `k²`), so `k` is the largest scale in `(0, 1]` at which every
//! feature is inside. Then:
//! - a stronger grip than the calibration's (every channel up by the same factor) comes back
//!   to the calibration's strongest window of that pattern: full output, in the right
//!   direction, never more;
//! - one channel far above anything the calibration saw (a pressed or lifted electrode) scales
//!   the whole window down by that channel's excess: the hand sees little effort, and rests;
//! - inside the envelope nothing changes (k = 1), bit for bit;
//! - along a verified ray the output is the ray's output at `min(k, k*)`: still monotone, so
//!   the verification stays true.
//!
//! The projection alone cannot tell a stronger grip from one pressed electrode: scaled down,
//! a window dominated by one channel is that channel's pattern at the calibration's edge, and
//! the model reads a movement into it (on the 3DC recordings, one channel at ten times its
//! level points most movement windows the wrong way). So a window is **implausible** when one
//! channel is beyond anything the calibration saw while the others are not: its RMS over the
//! calibration's largest is above 1 and more than [`PLAUSIBLE_SPREAD`] times the median
//! channel's. A genuine stronger contraction raises every active channel together (the median
//! with them); an electrode pressed, lifted or hit raises one. An implausible window gives no
//! movement: the predictor outputs rest (0) for it, and the daemon raises `signal_quality`.
//!
//! The projection runs in the [`super::Predictor`], the one path the daemon, `handctl decode`,
//! evaluation and replay share; it allocates nothing.

use crate::dsp::{FEATURES_PER_CHANNEL, FEATURE_NAMES};

use super::error::ModelError;

/// A window is implausible when its most excessive channel is more than this many times the
/// median channel's excess (each channel's RMS over the calibration's largest RMS of that
/// channel) and beyond the calibration (above 1). Chosen on the 3DC recordings: a whole
/// recording at 5x (every channel together) stays below it, one channel at 10x goes above.
pub const PLAUSIBLE_SPREAD: f64 = 2.5;

/// Most channels a window is checked over (the bus carries 12; the 3DC armband 10).
const MAX_CHANNELS: usize = 32;

/// Per input feature, the largest value of the calibration.
#[derive(Debug, Clone, PartialEq)]
pub struct Envelope {
    max: Vec<f64>,
    /// Whether input `j` scales with the square of the signal (VAR).
    squared: Vec<bool>,
    /// The index of RMS among a channel's features.
    rms: usize,
    /// The plausibility check's spread ([`PLAUSIBLE_SPREAD`] unless set): a setting of the
    /// daemon (handd.toml), not of the model file.
    spread: f64,
}

/// The index of VAR among a channel's features.
fn var_slot() -> usize {
    FEATURE_NAMES
        .iter()
        .position(|n| *n == "VAR")
        .expect("VAR is one of the chain's features")
}

impl Envelope {
    /// An envelope of `max` (one value per input feature, raw units): each finite and >= 0,
    /// whole channels of [`FEATURES_PER_CHANNEL`].
    pub fn try_new(max: Vec<f64>) -> Result<Self, ModelError> {
        if max.is_empty() || !max.len().is_multiple_of(FEATURES_PER_CHANNEL) {
            return Err(ModelError::InvalidSpec(format!(
                "envelope: {} values are not whole channels of {FEATURES_PER_CHANNEL} features",
                max.len()
            )));
        }
        if let Some((j, v)) = max
            .iter()
            .enumerate()
            .find(|(_, v)| !(v.is_finite() && **v >= 0.0))
        {
            return Err(ModelError::InvalidSpec(format!(
                "envelope: feature {j} is {v}: must be finite and >= 0"
            )));
        }
        let var = var_slot();
        let squared = (0..max.len())
            .map(|j| j % FEATURES_PER_CHANNEL == var)
            .collect();
        let rms = FEATURE_NAMES
            .iter()
            .position(|n| *n == "RMS")
            .expect("RMS is one of the chain's features");
        Ok(Self {
            max,
            squared,
            rms,
            spread: PLAUSIBLE_SPREAD,
        })
    }

    /// The envelope of `rows` (raw feature vectors of `n` features each): per feature, the
    /// largest value. Errors on no rows, a row of another length, or a non-finite value.
    pub fn fit<'a>(n: usize, rows: impl Iterator<Item = &'a [f64]>) -> Result<Self, ModelError> {
        let mut max = vec![0.0f64; n];
        let mut any = false;
        for r in rows {
            if r.len() != n {
                return Err(ModelError::Shape {
                    what: "envelope row".into(),
                    expected: n,
                    found: r.len(),
                });
            }
            for (m, v) in max.iter_mut().zip(r) {
                *m = m.max(*v);
            }
            any = true;
        }
        if !any {
            return Err(ModelError::InvalidSpec(
                "envelope: no calibration windows".into(),
            ));
        }
        Self::try_new(max)
    }

    /// Per input feature, the calibration's largest value.
    pub fn max(&self) -> &[f64] {
        &self.max
    }

    /// Input features.
    pub fn len(&self) -> usize {
        self.max.len()
    }

    /// Whether the envelope has no features (never: [`Envelope::try_new`] refuses it).
    pub fn is_empty(&self) -> bool {
        self.max.is_empty()
    }

    /// The largest signal scale `k` in `[0, 1]` at which every feature of `x` is inside the
    /// envelope (1 when it is inside already). Panics if `x` has another length.
    #[inline]
    pub fn scale_of(&self, x: &[f64]) -> f64 {
        assert_eq!(x.len(), self.max.len(), "feature count");
        let mut k = 1.0f64;
        for ((v, m), sq) in x.iter().zip(&self.max).zip(&self.squared) {
            if *v > *m {
                let r = if *v > 0.0 { m / v } else { 0.0 };
                k = k.min(if *sq { r.sqrt() } else { r });
            }
        }
        k
    }

    /// Whether `x` is implausible: one channel beyond the calibration while the others are not,
    /// its excess more than the spread ([`PLAUSIBLE_SPREAD`] by default) times the median
    /// channel's (see the module docs). No allocation.
    #[inline]
    pub fn implausible(&self, x: &[f64]) -> bool {
        let rms = self.rms;
        let channels = (x.len() / FEATURES_PER_CHANNEL).min(MAX_CHANNELS);
        let mut excess = [0.0f64; MAX_CHANNELS];
        for (c, e) in excess.iter_mut().enumerate().take(channels) {
            let j = c * FEATURES_PER_CHANNEL + rms;
            let m = self.max[j];
            *e = if m > 0.0 { x[j] / m } else { f64::INFINITY };
        }
        let e = &mut excess[..channels];
        let top = e.iter().copied().fold(0.0, f64::max);
        if top <= 1.0 {
            return false;
        }
        e.sort_unstable_by(f64::total_cmp);
        let median = e[channels / 2];
        top > self.spread * median
    }

    /// Sets the plausibility check's spread (see [`Envelope::implausible`]); `spread` must be
    /// finite and above 1 (the caller validated it: handd's config allows 1.5 to 100).
    pub fn set_spread(&mut self, spread: f64) {
        debug_assert!(spread.is_finite() && spread > 1.0, "spread {spread}");
        self.spread = spread;
    }

    /// The plausibility check's spread.
    pub fn spread(&self) -> f64 {
        self.spread
    }

    /// `x` moved back along its effort ray into the envelope, written to `out`; returns the
    /// scale applied (1: `out` is `x`, bit for bit). No allocation.
    #[inline]
    pub fn project(&self, x: &[f64], out: &mut [f64]) -> f64 {
        let k = self.scale_of(x);
        if k >= 1.0 {
            out.copy_from_slice(x);
            return 1.0;
        }
        let k2 = k * k;
        for ((o, v), sq) in out.iter_mut().zip(x).zip(&self.squared) {
            *o = v * if *sq { k2 } else { k };
        }
        k
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two channels: every feature's maximum 1, VAR's 1 too.
    fn unit(channels: usize) -> Envelope {
        Envelope::try_new(vec![1.0; FEATURES_PER_CHANNEL * channels]).expect("envelope")
    }

    #[test]
    fn inside_nothing_changes_bit_for_bit() {
        let e = unit(2);
        let x: Vec<f64> = (0..16).map(|j| 0.05 * j as f64).collect();
        let mut out = vec![0.0; 16];
        assert_eq!(e.project(&x, &mut out), 1.0);
        assert_eq!(out, x);
    }

    #[test]
    fn a_stronger_grip_comes_back_along_its_ray_to_the_boundary() {
        let e = unit(2);
        let var = var_slot();
        // The signal at scale 3 of a pattern with amplitude features 0.5 (VAR 0.25): amplitude
        // features 1.5, VAR 0.25·9 = 2.25.
        let x: Vec<f64> = (0..16)
            .map(|j| {
                if j % FEATURES_PER_CHANNEL == var {
                    2.25
                } else {
                    1.5
                }
            })
            .collect();
        let mut out = vec![0.0; 16];
        let k = e.project(&x, &mut out);
        assert!((k - 2.0 / 3.0).abs() < 1e-12, "k {k}");
        for (j, o) in out.iter().enumerate() {
            assert!(*o <= 1.0 + 1e-12, "feature {j} still beyond: {o}");
        }
        // Back at scale 2 of the 0.5 pattern: amplitude 1.0, VAR 0.25·4 = 1.0.
        assert!(out.iter().all(|o| (o - 1.0).abs() < 1e-12), "{out:?}");
    }

    #[test]
    fn one_channel_far_beyond_scales_the_whole_window_down() {
        let e = unit(2);
        let var = var_slot();
        let mut x = vec![0.5; 16];
        for (j, v) in x.iter_mut().enumerate().skip(FEATURES_PER_CHANNEL) {
            *v = if j % FEATURES_PER_CHANNEL == var {
                100.0
            } else {
                10.0
            };
        }
        let mut out = vec![0.0; 16];
        let k = e.project(&x, &mut out);
        assert!((k - 0.1).abs() < 1e-12, "k {k}");
        assert!(out[..FEATURES_PER_CHANNEL]
            .iter()
            .all(|o| *o <= 0.05 + 1e-12));
    }

    #[test]
    fn one_channel_beyond_is_implausible_every_channel_beyond_is_not() {
        let e = unit(4);
        let mut x = vec![0.6; 4 * FEATURES_PER_CHANNEL];
        assert!(!e.implausible(&x), "inside");
        let all: Vec<f64> = x.iter().map(|v| v * 3.0).collect();
        assert!(
            !e.implausible(&all),
            "a stronger contraction on every channel"
        );
        for v in &mut x[FEATURES_PER_CHANNEL..2 * FEATURES_PER_CHANNEL] {
            *v *= 10.0;
        }
        assert!(e.implausible(&x), "one electrode at ten times its level");
        // The spread is the daemon's setting: at 20 the same window is plausible.
        let mut wide = e.clone();
        wide.set_spread(20.0);
        assert!(!wide.implausible(&x), "spread 20: ten times is within it");
        assert_eq!(wide.spread(), 20.0);
    }

    #[test]
    fn fit_takes_each_features_largest_value_and_refuses_bad_input() {
        let rows = [vec![1.0; 8], vec![2.0; 8], vec![0.5; 8]];
        let e = Envelope::fit(8, rows.iter().map(Vec::as_slice)).expect("fit");
        assert_eq!(e.max(), &[2.0; 8]);
        assert!(Envelope::fit(8, std::iter::empty()).is_err());
        assert!(Envelope::try_new(vec![1.0; 7]).is_err());
        assert!(Envelope::try_new(vec![f64::NAN; 8]).is_err());
    }
}
