//! Synthetic calibration data for the model tests: a linear mixing of ten muscle sources
//! (flexor and extensor per finger) into electrodes, so the true decoder is known.
#![allow(dead_code)]

use decoder::dsp::ChainConfig;
use decoder::model::{Dataset, N_FINGERS};

/// SplitMix64 in [0, 1).
pub struct Gen(pub u64);
impl Gen {
    pub fn unit(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64
    }
}

pub fn chain(channels: usize) -> ChainConfig {
    ChainConfig {
        channels,
        ..ChainConfig::default()
    }
}

/// Feature vector for per-finger activations `act` in [-1, 1] (positive = flexor).
pub fn features(mix: &[Vec<f64>], act: &[f64; N_FINGERS], g: &mut Gen, noise: f64) -> Vec<f64> {
    let mut x = vec![0.0; mix[0].len()];
    for (f, a) in act.iter().enumerate() {
        let src = if *a >= 0.0 { 2 * f } else { 2 * f + 1 };
        for (xj, mj) in x.iter_mut().zip(&mix[src]) {
            *xj += a.abs() * mj;
        }
    }
    for v in &mut x {
        *v = (*v + noise * g.unit()) * 50.0; // µV-like scale; the normalizer must cope
    }
    x
}

/// Random non-negative mixing of 10 sources into `nf` features.
pub fn mixing(nf: usize, g: &mut Gen) -> Vec<Vec<f64>> {
    (0..2 * N_FINGERS)
        .map(|_| (0..nf).map(|_| g.unit().powi(2)).collect())
        .collect()
}

/// The paper's protocol plus rest: per finger flexion (+1) and extension (-1) trials, and rest
/// trials; `reps` repetitions of each, `windows` windows per trial.
pub fn calibration(channels: usize, reps: usize, windows: usize, seed: u64) -> Dataset {
    let mut g = Gen(seed);
    let nf = 8 * channels;
    let mix = mixing(nf, &mut g);
    let mut d = Dataset::new(chain(channels)).expect("valid chain");
    let mut trial = 0;
    for _ in 0..reps {
        for f in 0..N_FINGERS {
            for dir in [1.0, -1.0] {
                for _ in 0..windows {
                    let mut act = [0.0; N_FINGERS];
                    act[f] = dir * (0.8 + 0.2 * g.unit());
                    let x = features(&mix, &act, &mut g, 0.05);
                    let mut t = [0.0; N_FINGERS];
                    t[f] = dir;
                    let mut m = [false; N_FINGERS];
                    m[f] = true;
                    d.push(&x, t, m, trial).expect("valid window");
                }
                trial += 1;
            }
        }
        for _ in 0..windows {
            let x = features(&mix, &[0.0; N_FINGERS], &mut g, 0.05);
            d.push(&x, [0.0; N_FINGERS], [true; N_FINGERS], trial)
                .expect("valid window");
        }
        trial += 1;
    }
    d
}
