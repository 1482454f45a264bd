//! Seeded random numbers for weight initialisation, shuffling and splits.
//!
//! The samplers are written here on top of `RngCore::next_u64` (ChaCha8) instead of using
//! `rand`'s distributions, so that the same seed gives the same weights bit for bit even if a
//! future `rand` release changes how its distributions consume random words.

use rand::{RngCore, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// The project's deterministic random source.
pub(crate) struct SeededRng(ChaCha8Rng);

impl SeededRng {
    /// A generator for `seed`.
    pub(crate) fn new(seed: u64) -> Self {
        SeededRng(ChaCha8Rng::seed_from_u64(seed))
    }

    /// Uniform in `[0, 1)` with 53 random bits.
    pub(crate) fn unit(&mut self) -> f64 {
        (self.0.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Uniform in `[-a, a)`.
    pub(crate) fn symmetric(&mut self, a: f64) -> f64 {
        (2.0 * self.unit() - 1.0) * a
    }

    /// Uniform integer in `0..n` (`n > 0`), by the multiply-shift method.
    pub(crate) fn below(&mut self, n: usize) -> usize {
        ((u128::from(self.0.next_u64()) * n as u128) >> 64) as usize
    }

    /// Fisher-Yates shuffle.
    pub(crate) fn shuffle<T>(&mut self, v: &mut [T]) {
        for i in (1..v.len()).rev() {
            let j = self.below(i + 1);
            v.swap(i, j);
        }
    }

    /// Fills `w` (a `fan_out x fan_in` matrix) uniformly in `±gain·sqrt(6 / (fan_in + fan_out))`
    /// (Glorot/Xavier uniform).
    pub(crate) fn xavier(&mut self, w: &mut [f64], fan_in: usize, fan_out: usize, gain: f64) {
        let a = gain * (6.0 / (fan_in + fan_out) as f64).sqrt();
        for x in w {
            *x = self.symmetric(a);
        }
    }

    /// Fills `w` uniformly in `±sqrt(6 / fan_in)` (He/Kaiming uniform, for layers followed by ReLU).
    pub(crate) fn he(&mut self, w: &mut [f64], fan_in: usize) {
        let a = (6.0 / fan_in as f64).sqrt();
        for x in w {
            *x = self.symmetric(a);
        }
    }
}
