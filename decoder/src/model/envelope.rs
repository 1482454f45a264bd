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
//! channel stands alone. The level of a channel is its RMS over the calibration's largest RMS
//! of that channel, and two tests share one spread ([`PLAUSIBLE_SPREAD`]; the third, below,
//! has its own margin):
//! - *alone*: the top channel is above [`PLAUSIBLE_FLOOR`] and more than the next channel
//!   times the larger of the spread and [`ALONE_MARGIN`] times the calibration's own largest
//!   top-over-next ratio (recorded at training: [`Envelope::alone`]). A muscle is never under
//!   one electrode only: a genuine contraction, of any strength, reaches the neighbouring
//!   electrodes as it did at calibration, and a stronger one raises them together; an
//!   electrode pressed, lifted, knocked or hit raises one. On P4, P6 and P7 the top channel
//!   is at most 2.36, 1.76 and 1.89 times the next in the train recordings' windows (rest and
//!   movement, top above the floor) and 2.39, 2.17 and 1.55 in the test recordings'
//!   (`cargo run -p decoder --example channel_spread`); one channel at ten times its level
//!   stands alone in 86-92% of the test windows.
//!   Relative to the calibration, because the ratio is a property of the electrodes: a sparse
//!   band, or a calibration whose windows already had one channel alone, raises the bar or
//!   turns the test off (an infinite ratio, one channel, or a file from before it). This test
//!   catches a knock at rest, which stays inside the calibration's range.
//! - *beyond alone*: the top channel is beyond the calibration (above 1) and more than the
//!   spread times the median channel. It catches a few more of the pressed-electrode windows
//!   on the 3DC recordings (P7's channel 3 at ten times its level), and it also calls a
//!   stronger single-finger effort implausible: one finger moves a few of twelve channels and
//!   leaves the median at the noise floor (the simulator's patient at 2x effort is held safe
//!   most of the time). Without it, such an effort is projected back with the noise floor of
//!   the other channels scaled below rest, and the other fingers move up to 0.42 while asked
//!   to rest (issue 25: a projection that keeps the rest level would let it go).
//!
//! - *off the patterns* (when the file records the calibration's channel patterns): the top
//!   channel is above [`PLAUSIBLE_FLOOR`] and the window's per-channel power lies farther from
//!   every non-negative combination of the calibration's movements than the calibration's own
//!   windows did, by [`super::CONE_MARGIN`] ([`PatternCone`]: a band turned around the
//!   forearm, with the figures of where it can fire and where it cannot).
//!
//! An implausible window gives no movement: the predictor outputs rest (0) for it, and the
//! daemon raises `signal_quality`.
//!
//! The projection runs in the [`super::Predictor`], the one path the daemon, `handctl decode`,
//! evaluation and replay share; it allocates nothing.

use crate::dsp::{FEATURES_PER_CHANNEL, FEATURE_NAMES};

use super::cone::PatternCone;
use super::error::ModelError;

/// The plausibility check's spread (see [`Envelope::implausible`]): the least ratio of the top
/// channel's level (RMS over the calibration's largest RMS of that channel) to the next
/// channel's at which it stands alone, and of the top channel's to the median channel's at
/// which a channel beyond the calibration stands alone. Chosen on the 3DC recordings: every
/// channel at 5x stays below the median test, and no window of P4, P6 or P7 (top level above
/// 0.1) has its top channel 2.5x the next.
pub const PLAUSIBLE_SPREAD: f64 = 2.5;

/// The level (of the calibration's largest, per channel) a channel must pass before it can
/// stand alone: below it a window is the rest's noise, whatever its shape.
pub const PLAUSIBLE_FLOOR: f64 = 0.1;

/// How far beyond the calibration's own largest top-over-next ratio a window's may go before
/// its top channel stands alone (with the spread as the least): on P4, P6 and P7 the test
/// recordings reach at most 1.23x the train recordings' ratio (P6: 2.17 against 1.76).
pub const ALONE_MARGIN: f64 = 1.5;

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
    /// The calibration's own largest top-over-next channel ratio (windows whose top channel is
    /// above [`PLAUSIBLE_FLOOR`]): what "alone" means on this patient's electrodes. None for a
    /// file written before it was recorded, or one channel: the *alone* test is then off.
    alone: Option<f64>,
    /// The calibration's channel patterns (the *off the patterns* test); None for a file
    /// written before they were recorded: the test is then off.
    cone: Option<PatternCone>,
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
            alone: None,
            cone: None,
        })
    }

    /// The envelope of `rows` (raw feature vectors of `n` features each): per feature, the
    /// largest value. Errors on no rows, a row of another length, or a non-finite value.
    pub fn fit<'a>(n: usize, rows: impl Iterator<Item = &'a [f64]>) -> Result<Self, ModelError> {
        let mut max = vec![0.0f64; n];
        let mut kept: Vec<&[f64]> = Vec::new();
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
            kept.push(r);
        }
        if kept.is_empty() {
            return Err(ModelError::InvalidSpec(
                "envelope: no calibration windows".into(),
            ));
        }
        let envelope = Self::try_new(max)?;
        // The calibration's own largest ratio, over the windows with some activity.
        let alone = kept
            .iter()
            .filter_map(|r| {
                let (top, next) = envelope.top_two(r)?;
                (top > PLAUSIBLE_FLOOR).then(|| {
                    if next > 0.0 {
                        top / next
                    } else {
                        f64::INFINITY
                    }
                })
            })
            .fold(None, |a: Option<f64>, v| Some(a.map_or(v, |a| a.max(v))));
        envelope.with_alone(alone.map(|a| a.max(1.0)))
    }

    /// The envelope with `alone` as the calibration's largest top-over-next ratio (see
    /// [`Envelope::implausible`]): finite and >= 1 (an infinite ratio, a calibration window
    /// with one channel alone, is stored as none: the test is off), or none.
    pub fn with_alone(mut self, alone: Option<f64>) -> Result<Self, ModelError> {
        match alone {
            Some(a) if a.is_nan() || a < 1.0 => Err(ModelError::InvalidSpec(format!(
                "envelope: the calibration's channel ratio {a} must be >= 1"
            ))),
            Some(a) if a.is_infinite() => Ok(Self {
                alone: None,
                ..self
            }),
            _ => {
                self.alone = if self.channels() < 2 { None } else { alone };
                Ok(self)
            }
        }
    }

    /// The calibration's largest top-over-next channel ratio, when recorded.
    pub fn alone(&self) -> Option<f64> {
        self.alone
    }

    /// The envelope with the calibration's channel patterns fitted from its windows: `rows`
    /// (raw feature vectors) with each window's per-finger targets (+ flexion, - extension,
    /// 0 rest). With more movements than [`super::MAX_PATTERNS`], or a channel the
    /// calibration never saw above 0 (no level to scale it by), the test stays off.
    pub fn with_patterns<'a>(
        self,
        windows: impl Iterator<Item = (&'a [f64], &'a [f64; 5])>,
    ) -> Result<Self, ModelError> {
        let channels = self.channels();
        let dead = (0..channels).any(|c| self.max[c * FEATURES_PER_CHANNEL + self.rms] <= 0.0);
        if channels > MAX_CHANNELS || dead {
            return Ok(self);
        }
        let mut rows: Vec<(Vec<f64>, [i8; 5], bool)> = Vec::new();
        for (x, t) in windows {
            if x.len() != self.max.len() {
                return Err(ModelError::Shape {
                    what: "calibration window".into(),
                    expected: self.max.len(),
                    found: x.len(),
                });
            }
            let mut power = [0.0f64; MAX_CHANNELS];
            let top = self.powers(x, &mut power);
            let key = t.map(|v| i8::from(v > 0.0) - i8::from(v < 0.0));
            rows.push((power[..channels].to_vec(), key, top > PLAUSIBLE_FLOOR));
        }
        let cone = PatternCone::fit(
            channels,
            rows.iter().map(|(p, k, c)| (p.as_slice(), *k, *c)),
        )?;
        Ok(Self { cone, ..self })
    }

    /// The envelope with `cone` as the calibration's channel patterns (from a file).
    pub fn with_cone(self, cone: Option<PatternCone>) -> Result<Self, ModelError> {
        if let Some(c) = &cone {
            if c.channels() != self.channels() {
                return Err(ModelError::Shape {
                    what: "channel patterns".into(),
                    expected: self.channels(),
                    found: c.channels(),
                });
            }
        }
        Ok(Self { cone, ..self })
    }

    /// The calibration's channel patterns, when recorded.
    pub fn cone(&self) -> Option<&PatternCone> {
        self.cone.as_ref()
    }

    /// Per channel of `x`, its power (level squared) into `power`; returns the top level.
    /// Infinite for a channel the calibration never saw move (its largest RMS 0).
    #[inline]
    fn powers(&self, x: &[f64], power: &mut [f64; MAX_CHANNELS]) -> f64 {
        let mut top = 0.0f64;
        for (c, p) in power
            .iter_mut()
            .enumerate()
            .take(self.channels().min(MAX_CHANNELS))
        {
            let e = self.level(x, c);
            top = top.max(e);
            *p = e * e;
        }
        top
    }

    /// The guard beyond the calibration, one line for a technician (`handctl status`): for
    /// `None`, a model file without an envelope. The flag is true when a guard is missing that
    /// a model trained today has (the envelope, or the alone test on two or more channels).
    pub fn describe(envelope: Option<&Self>) -> (String, bool) {
        let Some(e) = envelope else {
            return (
                "beyond the calibration: NOT bounded (the file has no calibration envelope: \
                 an older model; retrain it to get the guard)"
                    .into(),
                true,
            );
        };
        let (alone, alone_missing) = e.describe_alone();
        let (patterns, patterns_missing) = e.describe_patterns();
        (
            format!("beyond the calibration: {alone}; {patterns}"),
            alone_missing || patterns_missing,
        )
    }

    /// The *alone* test, for [`Envelope::describe`]: its line, and whether it is missing.
    fn describe_alone(&self) -> (String, bool) {
        match self.alone {
            _ if self.channels() < 2 => (
                "bounded by its envelope (one channel: no alone test)".to_string(),
                false,
            ),
            Some(a) => (
                format!(
                    "bounded by its envelope; a channel standing alone is implausible (the \
                     calibration's reached {a:.2}x the next)"
                ),
                false,
            ),
            None => (
                "bounded by its envelope; the alone test is OFF (the file records no channel \
                 ratio: an older model, so a knocked electrode at rest is not caught; retrain \
                 it to get the test)"
                    .to_string(),
                true,
            ),
        }
    }

    /// The *off the patterns* test, for [`Envelope::describe`]: its line, and whether it is
    /// missing.
    fn describe_patterns(&self) -> (String, bool) {
        match &self.cone {
            None => (
                "the pattern test is OFF (the file records no channel patterns: an older \
                 model, so a band turned on the forearm is not caught; retrain it to get the \
                 test)"
                    .to_string(),
                true,
            ),
            Some(c) if c.bar() >= 1.0 => (
                format!(
                    "the pattern test cannot fire on this calibration (its own windows fit its \
                     channel patterns only to {:.2})",
                    c.worst()
                ),
                false,
            ),
            Some(c) => (
                format!(
                    "a window off the calibration's {} channel patterns is implausible (misfit \
                     above {:.3}; the calibration's reached {:.3})",
                    c.patterns().count(),
                    c.bar(),
                    c.worst()
                ),
                false,
            ),
        }
    }

    /// Channels the envelope covers.
    fn channels(&self) -> usize {
        self.max.len() / FEATURES_PER_CHANNEL
    }

    /// The top and next channel levels of `x` (RMS over the calibration's largest); None with
    /// fewer than two channels. No allocation.
    #[inline]
    fn top_two(&self, x: &[f64]) -> Option<(f64, f64)> {
        let channels = self.channels().min(MAX_CHANNELS);
        if channels < 2 {
            return None;
        }
        let (mut top, mut next) = (0.0f64, 0.0f64);
        for c in 0..channels {
            let e = self.level(x, c);
            if e > top {
                next = top;
                top = e;
            } else if e > next {
                next = e;
            }
        }
        Some((top, next))
    }

    /// Channel `c`'s level in `x`: its RMS over the calibration's largest.
    #[inline]
    fn level(&self, x: &[f64], c: usize) -> f64 {
        let j = c * FEATURES_PER_CHANNEL + self.rms;
        let m = self.max[j];
        if m > 0.0 {
            x[j] / m
        } else {
            f64::INFINITY
        }
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

    /// Whether `x` is implausible (see the module docs), by either of two tests:
    /// - **alone** (when the calibration's ratio is recorded): the top channel's level is
    ///   above [`PLAUSIBLE_FLOOR`] and more than the next channel's times the larger of the
    ///   spread ([`PLAUSIBLE_SPREAD`] by default) and [`ALONE_MARGIN`] times the calibration's
    ///   own largest ratio (a knocked or pressed electrode, inside the calibration's range or
    ///   beyond it);
    /// - **beyond alone**: the top channel is beyond the calibration (above 1) and more than
    ///   the spread times the median channel's.
    ///
    /// No allocation.
    #[inline]
    pub fn implausible(&self, x: &[f64]) -> bool {
        let channels = (x.len() / FEATURES_PER_CHANNEL).min(MAX_CHANNELS);
        let mut level = [0.0f64; MAX_CHANNELS];
        for (c, e) in level.iter_mut().enumerate().take(channels) {
            *e = self.level(x, c);
        }
        let e = &mut level[..channels];
        e.sort_unstable_by(|a, b| b.total_cmp(a));
        // The upper median (largest first: index n - 1 - n/2 of n).
        let (top, median) = (e[0], e[channels - 1 - channels / 2]);
        let beyond_alone = top > 1.0 && top > self.spread * median;
        let alone = match (self.alone, e.get(1)) {
            (Some(a), Some(next)) => {
                top > PLAUSIBLE_FLOOR && top > self.spread.max(ALONE_MARGIN * a) * next
            }
            _ => false,
        };
        alone || beyond_alone || self.off_patterns(x, top)
    }

    /// The misfit of `x`'s channel powers against the calibration's patterns, when the file
    /// records them and the top channel is above [`PLAUSIBLE_FLOOR`] (what the *off the
    /// patterns* test compares with its bar). No allocation.
    pub fn pattern_misfit(&self, x: &[f64]) -> Option<f64> {
        let cone = self.cone.as_ref()?;
        let mut power = [0.0f64; MAX_CHANNELS];
        let top = self.powers(x, &mut power);
        (top > PLAUSIBLE_FLOOR && top.is_finite()).then(|| cone.misfit(&power[..cone.channels()]))
    }

    /// The *off the patterns* test: the top channel above the floor (and finite) and the
    /// window's channel powers off the calibration's cone.
    #[inline]
    fn off_patterns(&self, x: &[f64], top: f64) -> bool {
        let Some(cone) = &self.cone else {
            return false;
        };
        if !(top > PLAUSIBLE_FLOOR && top.is_finite()) {
            return false;
        }
        let mut power = [0.0f64; MAX_CHANNELS];
        self.powers(x, &mut power);
        cone.off(&power[..cone.channels()])
    }

    /// Sets the plausibility check's spread (see [`Envelope::implausible`]); `spread` must be
    /// finite and above 1 (the caller validated it: handd's config allows 1.5 to 100).
    pub fn set_spread(&mut self, spread: f64) {
        debug_assert!(spread.is_finite() && spread > 1.0, "spread {spread}");
        self.spread = spread;
    }

    /// Sets the *off the patterns* test's margin over the calibration's own worst misfit (see
    /// [`PatternCone::set_margin`]); nothing without recorded patterns.
    pub fn set_pattern_margin(&mut self, margin: f64) {
        if let Some(c) = &mut self.cone {
            c.set_margin(margin);
        }
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
    fn describe_flags_a_file_without_a_guard_of_todays_models() {
        let (text, flagged) = Envelope::describe(None);
        assert!(flagged && text.contains("NOT bounded"), "{text}");
        let (text, flagged) = Envelope::describe(Some(&unit(12)));
        assert!(flagged && text.contains("alone test is OFF"), "{text}");
        let cone = |channels: usize, worst: f64| {
            PatternCone::try_new(
                channels,
                vec![vec![1.0 / (channels as f64).sqrt(); channels]],
                worst,
            )
            .expect("cone")
        };
        let alone_only = unit(12).with_alone(Some(2.36)).expect("ratio");
        let (text, flagged) = Envelope::describe(Some(&alone_only));
        assert!(flagged && text.contains("pattern test is OFF"), "{text}");
        let on = alone_only.with_cone(Some(cone(12, 0.035))).expect("cone");
        let (text, flagged) = Envelope::describe(Some(&on));
        assert!(!flagged && text.contains("2.36x the next"), "{text}");
        assert!(text.contains("misfit above 0.070"), "{text}");
        let noisy = on.clone().with_cone(Some(cone(12, 0.68))).expect("cone");
        let (text, flagged) = Envelope::describe(Some(&noisy));
        assert!(!flagged && text.contains("cannot fire"), "{text}");
        let one = unit(1).with_cone(Some(cone(1, 0.0))).expect("cone");
        let (text, flagged) = Envelope::describe(Some(&one));
        assert!(!flagged && text.contains("one channel"), "{text}");
        assert!(unit(2).with_cone(Some(cone(3, 0.0))).is_err());
    }

    #[test]
    fn a_channel_the_calibration_never_saw_leaves_the_pattern_test_off() {
        let mut max = vec![1.0; 2 * FEATURES_PER_CHANNEL];
        let e = Envelope::try_new(max.clone()).expect("envelope");
        max[FEATURES_PER_CHANNEL + e.rms] = 0.0;
        let x = vec![0.5; 2 * FEATURES_PER_CHANNEL];
        let rows = [(x.as_slice(), &[1.0, 0.0, 0.0, 0.0, 0.0])];
        let live = e.with_patterns(rows.iter().copied()).expect("patterns");
        assert!(live.cone().is_some());
        let dead = Envelope::try_new(max)
            .and_then(|e| e.with_patterns(rows.iter().copied()))
            .expect("no error, the test off");
        assert!(dead.cone().is_none());
    }

    #[test]
    fn a_window_off_the_calibrations_patterns_is_implausible() {
        // Two channels; the calibration moved them together only.
        let e = unit(2)
            .with_cone(Some(
                PatternCone::try_new(2, vec![vec![0.5f64.sqrt(); 2]], 0.01).expect("cone"),
            ))
            .expect("cone");
        let rms = |a: f64, b: f64| {
            let mut x = vec![0.0; 2 * FEATURES_PER_CHANNEL];
            x[e.rms] = a;
            x[FEATURES_PER_CHANNEL + e.rms] = b;
            x
        };
        assert!(!e.implausible(&rms(0.5, 0.5)));
        assert!(e.implausible(&rms(0.5, 0.3)), "a shape it never saw");
        assert!(
            !e.implausible(&rms(0.05, 0.03)),
            "below the floor it is rest"
        );
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

    /// Channel levels (RMS over the calibration's largest) as a window of `unit` features.
    fn levels(l: &[f64]) -> Vec<f64> {
        l.iter()
            .flat_map(|v| std::iter::repeat_n(*v, FEATURES_PER_CHANNEL))
            .collect()
    }

    #[test]
    fn a_lone_channel_is_implausible_inside_the_calibration_too() {
        // A calibration whose top channel was at most 1.5x the next: the test is at 2.5x.
        let e = unit(12).with_alone(Some(1.5)).expect("ratio");
        assert!(
            !unit(12).implausible(&levels(&[
                0.5, 0.02, 0.02, 0.02, 0.02, 0.02, 0.02, 0.02, 0.02, 0.02, 0.02, 0.02
            ])),
            "without the calibration's ratio (an older file) the alone test is off"
        );
        let finger = [
            0.02, 0.02, 0.5, 1.0, 0.6, 0.05, 0.02, 0.02, 0.02, 0.02, 0.02, 0.02,
        ];
        assert!(
            !e.implausible(&levels(&finger)),
            "one finger at full effort"
        );
        // The same finger at 2x: beyond the calibration while the median channel stays at the
        // noise floor, so the median test calls it implausible (module docs).
        let strong: Vec<f64> = finger.iter().map(|v| v * 2.0).collect();
        assert!(e.implausible(&levels(&strong)), "beyond alone");
        // One channel alone, inside the envelope: a knock at rest (no channel beyond).
        let mut knock = [0.02; 12];
        knock[7] = 0.6;
        assert!(
            e.implausible(&levels(&knock)),
            "a knock on channel 7 at rest"
        );
        // The same shape under the floor is the rest's noise.
        let mut noise = [0.01; 12];
        noise[7] = 0.08;
        assert!(!e.implausible(&levels(&noise)), "under the floor");
        // The test is against the next channel: two at 2.5x its level is exactly the spread.
        let mut edge = [0.2; 12];
        edge[0] = 0.5;
        assert!(!e.implausible(&levels(&edge)), "at the spread");
        edge[0] = 0.51;
        assert!(e.implausible(&levels(&edge)), "just beyond the spread");
        // A calibration whose own windows reached 3x: alone means beyond 1.5 * 3 = 4.5x.
        let sparse = unit(12).with_alone(Some(3.0)).expect("ratio");
        edge[0] = 0.8;
        assert!(
            !sparse.implausible(&levels(&edge)),
            "4x: within this calibration's 4.5x"
        );
        edge[0] = 0.95;
        assert!(sparse.implausible(&levels(&edge)), "4.75x: beyond it");
    }

    #[test]
    fn fit_records_the_calibrations_own_channel_ratio() {
        let per = FEATURES_PER_CHANNEL;
        let row = |l: [f64; 3]| -> Vec<f64> {
            l.iter()
                .flat_map(|v| std::iter::repeat_n(*v, per))
                .collect()
        };
        let rows = [
            row([1.0, 0.5, 0.1]),
            row([0.2, 1.0, 0.8]),
            row([0.05, 0.01, 0.01]),
        ];
        let e = Envelope::fit(3 * per, rows.iter().map(Vec::as_slice)).expect("fit");
        // Levels over the maxima (1, 1, 0.8): [1, 0.5, 0.125] gives 2; [0.2, 1, 1] gives 1;
        // the third is below the floor and left out.
        assert_eq!(e.alone(), Some(2.0));
        // One channel: no ratio, the test is off.
        let one = Envelope::fit(per, [vec![1.0; per]].iter().map(Vec::as_slice)).expect("fit");
        assert_eq!(one.alone(), None);
        // A calibration window with one channel alone (next at 0): the test is off too.
        let lone = [row([1.0, 0.0, 0.0]), row([0.0, 1.0, 1.0])];
        let e = Envelope::fit(3 * per, lone.iter().map(Vec::as_slice)).expect("fit");
        assert_eq!(e.alone(), None);
        assert!(unit(2).with_alone(Some(0.5)).is_err());
        assert!(unit(2).with_alone(Some(f64::NAN)).is_err());
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
