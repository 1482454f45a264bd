//! Seeded Gaussian noise.
//!
//! `rand_distr` is not a workspace dependency and one Box–Muller generator is a few lines, so it
//! lives here. ChaCha8 keeps the stream identical on every platform and `rand` version, which is
//! what "same seed, same frames, bit for bit" needs.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// A reproducible stream of standard-normal samples.
#[derive(Debug, Clone)]
pub struct GaussianNoise {
    rng: ChaCha8Rng,
    spare: Option<f64>,
}

impl GaussianNoise {
    /// Stream `stream` of `seed`: distinct streams of one seed are independent, so each muscle
    /// and each channel gets its own and adding one never shifts the others.
    pub fn new(seed: u64, stream: u64) -> Self {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(stream);
        Self { rng, spare: None }
    }

    /// One N(0, 1) sample.
    pub fn next_std(&mut self) -> f64 {
        if let Some(s) = self.spare.take() {
            return s;
        }
        // Box–Muller; u1 is kept away from 0 so ln() stays finite.
        let u1: f64 = self.rng.gen::<f64>().max(f64::MIN_POSITIVE);
        let u2: f64 = self.rng.gen::<f64>();
        let r = (-2.0 * u1.ln()).sqrt();
        let (s, c) = (std::f64::consts::TAU * u2).sin_cos();
        self.spare = Some(r * s);
        r * c
    }

    /// A uniform sample in `[lo, hi)`.
    pub fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.rng.gen::<f64>()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn standard_normal_moments() {
        let mut g = GaussianNoise::new(7, 0);
        let n = 100_000;
        let (mut s, mut s2) = (0.0, 0.0);
        for _ in 0..n {
            let x = g.next_std();
            s += x;
            s2 += x * x;
        }
        let mean = s / n as f64;
        let var = s2 / n as f64 - mean * mean;
        assert!(mean.abs() < 0.02, "mean {mean}");
        assert!((var - 1.0).abs() < 0.02, "var {var}");
    }

    #[test]
    fn streams_differ_and_repeat() {
        let a: Vec<f64> = (0..8)
            .map({
                let mut g = GaussianNoise::new(1, 0);
                move |_| g.next_std()
            })
            .collect();
        let b: Vec<f64> = (0..8)
            .map({
                let mut g = GaussianNoise::new(1, 0);
                move |_| g.next_std()
            })
            .collect();
        let c: Vec<f64> = (0..8)
            .map({
                let mut g = GaussianNoise::new(1, 1);
                move |_| g.next_std()
            })
            .collect();
        assert_eq!(a, b);
        assert_ne!(a, c);
    }
}
