//! Second-order IIR sections that shape white noise into an sEMG-like spectrum.

/// Which response a [`Biquad`] has.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BiquadKind {
    /// Butterworth high-pass (Q = 1/√2).
    HighPass,
    /// Butterworth low-pass (Q = 1/√2).
    LowPass,
}

/// One direct-form-II-transposed biquad, designed with the bilinear transform (RBJ cookbook).
#[derive(Debug, Clone, Copy)]
pub struct Biquad {
    b: [f64; 3],
    a: [f64; 2],
    z: [f64; 2],
}

impl Biquad {
    /// A Butterworth section at `cutoff_hz` for `fs_hz`. The caller guarantees
    /// `0 < cutoff_hz < fs_hz / 2` (checked once in the amplifier config).
    pub fn butterworth(kind: BiquadKind, cutoff_hz: f64, fs_hz: f64) -> Self {
        let w0 = std::f64::consts::TAU * cutoff_hz / fs_hz;
        let (sin, cos) = w0.sin_cos();
        let alpha = sin / (2.0 * std::f64::consts::FRAC_1_SQRT_2);
        let a0 = 1.0 + alpha;
        let (b0, b1, b2) = match kind {
            BiquadKind::LowPass => ((1.0 - cos) / 2.0, 1.0 - cos, (1.0 - cos) / 2.0),
            BiquadKind::HighPass => ((1.0 + cos) / 2.0, -(1.0 + cos), (1.0 + cos) / 2.0),
        };
        Self {
            b: [b0 / a0, b1 / a0, b2 / a0],
            a: [-2.0 * cos / a0, (1.0 - alpha) / a0],
            z: [0.0; 2],
        }
    }

    /// Filters one sample.
    #[inline]
    pub fn process(&mut self, x: f64) -> f64 {
        let y = self.b[0] * x + self.z[0];
        self.z[0] = self.b[1] * x - self.a[0] * y + self.z[1];
        self.z[1] = self.b[2] * x - self.a[1] * y;
        y
    }

    /// Clears the state.
    pub fn reset(&mut self) {
        self.z = [0.0; 2];
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_scipy_butter_2_low_150_at_1k() {
        // scipy.signal.butter(2, 150, 'low', fs=1000)
        let f = Biquad::butterworth(BiquadKind::LowPass, 150.0, 1000.0);
        let b = [
            0.13110643991662593,
            0.26221287983325187,
            0.13110643991662593,
        ];
        let a = [-0.7477891782585034, 0.27221493792500717];
        for (got, want) in f.b.iter().zip(b.iter()).chain(f.a.iter().zip(a.iter())) {
            assert!((got - want).abs() < 1e-12, "{got} vs {want}");
        }
    }
}
