//! What the patient wants each finger to do, and how that drives the muscles.

use crate::emg::{extensor, flexor, Activation};
use crate::error::{check_range, SimError};
use crate::finger::N_FINGERS;

/// Intended force per finger in -1..=1: positive is flexion (drives the finger's flexor),
/// negative is extension (drives its extensor), 0 is rest.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Intent(pub [f64; N_FINGERS]);

impl Intent {
    /// Every finger at rest.
    pub const REST: Intent = Intent([0.0; N_FINGERS]);

    /// `level` on one finger, rest on the others.
    pub fn finger(f: usize, level: f64) -> Intent {
        let mut i = Intent::REST;
        if let Some(x) = i.0.get_mut(f) {
            *x = level;
        }
        i
    }

    /// `level` on every finger.
    pub fn all(level: f64) -> Intent {
        Intent([level; N_FINGERS])
    }

    /// Linear interpolation `self + (to - self) · s`, `s` in 0..=1.
    pub fn lerp(&self, to: &Intent, s: f64) -> Intent {
        Intent(std::array::from_fn(|f| {
            self.0[f] + (to.0[f] - self.0[f]) * s
        }))
    }

    /// The opposite intent: every finger's flexion becomes extension of the same level and
    /// the reverse.
    pub fn reversed(&self) -> Intent {
        Intent(self.0.map(|x| -x))
    }

    /// The same intent with every finger clamped to -1..=1.
    pub fn clamped(&self) -> Intent {
        Intent(self.0.map(|x| x.clamp(-1.0, 1.0)))
    }
}

/// How intents become muscle activations.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MuscleDrive {
    /// Activation of every muscle at rest (postural tone), 0..0.2.
    pub tonic: f64,
    /// Fraction of a contraction that also activates the antagonist (co-contraction stiffens
    /// the joint in real hands), 0..0.5.
    pub co_contraction: f64,
}

impl Default for MuscleDrive {
    fn default() -> Self {
        Self {
            tonic: 0.02,
            co_contraction: 0.1,
        }
    }
}

impl MuscleDrive {
    /// Checks the parameters.
    pub fn validate(&self) -> Result<(), SimError> {
        check_range("tonic", self.tonic, 0.0, 0.2, "0..=0.2")?;
        check_range("co_contraction", self.co_contraction, 0.0, 0.5, "0..=0.5")
    }

    /// The 10 source activations for `intent`: flexor of finger `f` at
    /// `tonic + (1 - tonic)·max(i, 0) + co·max(-i, 0)`, extensor mirrored.
    pub fn activation(&self, intent: &Intent) -> Activation {
        let mut a = Activation::default();
        for (f, &i) in intent.0.iter().enumerate() {
            let i = i.clamp(-1.0, 1.0);
            let (flex, ext) = (i.max(0.0), (-i).max(0.0));
            let span = 1.0 - self.tonic;
            a.0[flexor(f)] = (self.tonic + span * flex + self.co_contraction * ext).min(1.0);
            a.0[extensor(f)] = (self.tonic + span * ext + self.co_contraction * flex).min(1.0);
        }
        a
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flexion_drives_the_flexor_and_rest_is_tonic() {
        let d = MuscleDrive::default();
        let a = d.activation(&Intent::finger(2, 1.0));
        assert!((a.0[flexor(2)] - 1.0).abs() < 1e-12);
        assert!((a.0[extensor(2)] - (0.02 + 0.1)).abs() < 1e-12);
        assert!((a.0[flexor(0)] - 0.02).abs() < 1e-12);
        let e = d.activation(&Intent::finger(4, -0.5));
        assert!(e.0[extensor(4)] > e.0[flexor(4)]);
    }
}
