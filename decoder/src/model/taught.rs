//! The directions a calibration taught (issue 25, item 4).
//!
//! A finger whose calibration has no flexion trial (no window labelled above 0 for it) was
//! never shown what flexing it looks like, and one without an extension trial (none below 0)
//! what opening it looks like. Whatever the model outputs in such a direction is an accident
//! of the other fingers' and the other direction's training: on the 3DC participants, trained
//! without Open Hand, the default ResDD still opened fingers on test windows (down to -0.28).
//! So the output stage holds an untaught direction at 0: `y <- min(y, 0)` when flexion was not
//! taught, `y <- max(y, 0)` when extension was not. Both maps are non-decreasing with slope at
//! most 1, so every monotonic curve stays monotonic and the verification of the taught
//! directions (the only ones a calibration ray can have) is unchanged.
//!
//! A model file without the section (written before it existed) loads as "both taught": its
//! outputs are what they were.

use serde::{Deserialize, Serialize};

use super::dataset::{Dataset, N_FINGERS};

/// Per finger, whether the calibration taught flexion (a label > 0) and extension (< 0).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Taught {
    /// Finger `f` had an unmasked label above 0.
    pub flexion: [bool; N_FINGERS],
    /// Finger `f` had an unmasked label below 0.
    pub extension: [bool; N_FINGERS],
}

impl Default for Taught {
    /// Both directions of every finger (an older model file, or a full calibration).
    fn default() -> Self {
        Self::BOTH
    }
}

impl Taught {
    /// Every direction of every finger taught: the stage changes nothing.
    pub const BOTH: Taught = Taught {
        flexion: [true; N_FINGERS],
        extension: [true; N_FINGERS],
    };

    /// The directions `data`'s unmasked labels teach (masked labels never reach the loss, so
    /// they teach nothing).
    pub fn of_dataset(data: &Dataset) -> Self {
        let mut t = Taught {
            flexion: [false; N_FINGERS],
            extension: [false; N_FINGERS],
        };
        for i in 0..data.len() {
            let (y, m) = (data.target(i), data.mask(i));
            for f in (0..N_FINGERS).filter(|&f| m[f]) {
                t.flexion[f] |= y[f] > 0.0;
                t.extension[f] |= y[f] < 0.0;
            }
        }
        t
    }

    /// Whether every direction of every finger was taught (the stage is the identity).
    pub fn is_both(&self) -> bool {
        *self == Self::BOTH
    }

    /// `finger`'s output `y` with an untaught direction held at 0.
    #[inline]
    pub fn hold(&self, finger: usize, y: f64) -> f64 {
        let untaught = if y > 0.0 {
            !self.flexion[finger]
        } else {
            y < 0.0 && !self.extension[finger]
        };
        if untaught {
            0.0
        } else {
            y
        }
    }

    /// [`Taught::hold`] on all five outputs in place: no allocation.
    #[inline]
    pub fn apply(&self, y: &mut [f64; N_FINGERS]) {
        for (f, v) in y.iter_mut().enumerate() {
            *v = self.hold(f, *v);
        }
    }

    /// The untaught directions in words, e.g. "thumb extension, index extension" (empty when
    /// both directions of every finger were taught).
    pub fn describe_untaught(&self, names: &[&str]) -> String {
        let mut out = Vec::new();
        for f in 0..N_FINGERS {
            let name = names.get(f).copied().unwrap_or("?");
            if !self.flexion[f] {
                out.push(format!("{name} flexion"));
            }
            if !self.extension[f] {
                out.push(format!("{name} extension"));
            }
        }
        out.join(", ")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dsp::ChainConfig;

    #[test]
    fn an_untaught_direction_is_held_at_zero_and_the_taught_one_passes() {
        let t = Taught {
            flexion: [true, false, true, false, true],
            extension: [false, true, true, false, true],
        };
        let mut y = [-0.3, 0.4, -0.5, 0.7, 0.2];
        t.apply(&mut y);
        assert_eq!(y, [0.0, 0.0, -0.5, 0.0, 0.2]);
        let mut z = [0.6, -0.2, 0.5, -0.7, -0.2];
        t.apply(&mut z);
        assert_eq!(z, [0.6, -0.2, 0.5, 0.0, -0.2]);
        // Non-decreasing in y: a monotonic curve stays monotonic.
        for f in 0..N_FINGERS {
            let mut last = f64::NEG_INFINITY;
            for i in -100..=100 {
                let v = t.hold(f, i as f64 / 50.0);
                assert!(v >= last, "finger {f} at {i}");
                last = v;
            }
        }
        let mut same = [-0.3, 0.4, -0.5, 0.7, 0.2];
        Taught::BOTH.apply(&mut same);
        assert_eq!(same, [-0.3, 0.4, -0.5, 0.7, 0.2]);
        assert!(Taught::default().is_both() && !t.is_both());
        let names = ["thumb", "index", "middle", "ring", "pinky"];
        assert_eq!(
            t.describe_untaught(&names),
            "thumb extension, index flexion, ring flexion, ring extension"
        );
    }

    #[test]
    fn the_labels_say_what_was_taught_and_masked_labels_teach_nothing() {
        let chain = ChainConfig::default();
        let mut d = Dataset::new(chain.clone()).unwrap();
        let n = d.n_features();
        let x = vec![0.1; n];
        d.push(&x, [0.0; N_FINGERS], [true; N_FINGERS], 0).unwrap();
        d.push(&x, [1.0, 1.0, 0.5, 0.0, 0.0], [true; N_FINGERS], 1)
            .unwrap();
        d.push(
            &x,
            [-1.0, 0.0, 0.0, 0.0, -1.0],
            [true, true, true, true, false],
            2,
        )
        .unwrap();
        let t = Taught::of_dataset(&d);
        assert_eq!(t.flexion, [true, true, true, false, false]);
        assert_eq!(t.extension, [true, false, false, false, false]);
    }
}
