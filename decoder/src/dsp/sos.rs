//! One second-order section (biquad) and its transposed-direct-form-II step.

use serde::{Deserialize, Serialize};

/// A second-order section `H(z) = (b0 + b1 z^-1 + b2 z^-2) / (1 + a1 z^-1 + a2 z^-2)`.
///
/// `a[0]` is always 1 (sections are normalised at design time). [`Sos::to_array`] gives scipy's
/// row layout `[b0, b1, b2, a0, a1, a2]`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Sos {
    /// Numerator `b0, b1, b2`.
    pub b: [f64; 3],
    /// Denominator `a0 (= 1), a1, a2`.
    pub a: [f64; 3],
}

impl Sos {
    /// scipy's `sos` row layout `[b0, b1, b2, a0, a1, a2]`.
    pub fn to_array(&self) -> [f64; 6] {
        [
            self.b[0], self.b[1], self.b[2], self.a[0], self.a[1], self.a[2],
        ]
    }

    /// One sample through the section; `z` is the section's two delay registers.
    ///
    /// The operation order is the one of scipy's `sosfilt` inner loop, so the two agree to the
    /// last bit given the same coefficients.
    #[inline(always)]
    pub fn step(&self, z: &mut [f64; 2], x: f64) -> f64 {
        let y = self.b[0] * x + z[0];
        z[0] = self.b[1] * x - self.a[1] * y + z[1];
        z[1] = self.b[2] * x - self.a[2] * y;
        y
    }
}
