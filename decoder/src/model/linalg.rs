//! Dense kernels on row-major slices for one sample at a time: the daemon's inference path, and
//! the per-sample reference the batched training passes ([`super::gemm`]) are tested against.
//!
//! Plain slices: the daemon's tick must not allocate, the parameters of a model live in one
//! flat vector (so optimizers treat every model alike), and these loops are short enough to
//! read. [`matvec`], the inference path's one heavy loop, runs in the build [`Simd`] chooses.
//! Every function is deterministic (fixed summation order), which the "same seed, same
//! weights" guarantee relies on.

use crate::dsp::Simd;

/// Dot product with eight independent accumulators (enough independent add chains to keep
/// the vector units busy; fixed order, so results are reproducible).
#[inline(always)]
pub(crate) fn dot(a: &[f64], b: &[f64]) -> f64 {
    debug_assert_eq!(a.len(), b.len());
    let mut acc = [0.0f64; 8];
    let ca = a.chunks_exact(8);
    let cb = b.chunks_exact(8);
    let (ra, rb) = (ca.remainder(), cb.remainder());
    for (x, y) in ca.zip(cb) {
        for k in 0..8 {
            acc[k] += x[k] * y[k];
        }
    }
    let mut tail = 0.0;
    for (x, y) in ra.iter().zip(rb) {
        tail += x * y;
    }
    ((acc[0] + acc[4]) + (acc[1] + acc[5])) + ((acc[2] + acc[6]) + (acc[3] + acc[7])) + tail
}

/// Rows of `W x`, one [`dot`] each, compiled inside [`Simd::run`] (on x86_64 with AVX2,
/// [`super::matvec_x86`] runs instead, four rows at a time); every operation is a correctly
/// rounded multiply or add, so the build changes speed only.
#[inline(always)]
fn matvec_rows(w: &[f64], x: &[f64], y: &mut [f64]) {
    for (row, yi) in w.chunks_exact(x.len()).zip(y.iter_mut()) {
        *yi = dot(row, x);
    }
}

/// `y += a * x`.
#[inline]
pub(crate) fn axpy(a: f64, x: &[f64], y: &mut [f64]) {
    debug_assert_eq!(x.len(), y.len());
    for (yi, xi) in y.iter_mut().zip(x) {
        *yi += a * xi;
    }
}

/// `y = W x` with `W` row-major `y.len() x x.len()`; each output has [`dot`]'s bits.
#[inline]
pub(crate) fn matvec(w: &[f64], x: &[f64], y: &mut [f64]) {
    debug_assert_eq!(w.len(), x.len() * y.len());
    if x.is_empty() {
        y.fill(0.0);
        return;
    }
    let simd = Simd::detect();
    #[cfg(target_arch = "x86_64")]
    if let Some(v3) = simd.x86_v3() {
        v3.vectorize(
            #[inline(always)]
            || super::matvec_x86::matvec(v3, w, x, y),
        );
        return;
    }
    simd.run(|| matvec_rows(w, x, y));
}

/// `y = W x + b`.
#[inline]
pub(crate) fn matvec_bias(w: &[f64], b: &[f64], x: &[f64], y: &mut [f64]) {
    debug_assert_eq!(b.len(), y.len());
    matvec(w, x, y);
    for (yi, bi) in y.iter_mut().zip(b) {
        *yi += bi;
    }
}

/// `dx = Wᵀ dy` (overwrites `dx`), `W` row-major `dy.len() x dx.len()`.
#[inline]
pub(crate) fn matvec_t(w: &[f64], dy: &[f64], dx: &mut [f64]) {
    debug_assert_eq!(w.len(), dx.len() * dy.len());
    dx.fill(0.0);
    let cols = dx.len();
    for (row, &d) in w.chunks_exact(cols).zip(dy) {
        axpy(d, row, dx);
    }
}

/// `G += dy ⊗ x` (gradient of `W` in `y = W x`).
#[inline]
pub(crate) fn outer_acc(g: &mut [f64], dy: &[f64], x: &[f64]) {
    debug_assert_eq!(g.len(), x.len() * dy.len());
    for (grow, &d) in g.chunks_exact_mut(x.len()).zip(dy) {
        axpy(d, x, grow);
    }
}

/// `v = max(v, 0)` in place.
#[inline]
pub(crate) fn relu(v: &mut [f64]) {
    for x in v {
        if *x < 0.0 {
            *x = 0.0;
        }
    }
}

/// Zeroes the gradient where the ReLU output `a` was clamped (`a <= 0`).
#[inline]
pub(crate) fn relu_backward(a: &[f64], d: &mut [f64]) {
    for (di, ai) in d.iter_mut().zip(a) {
        if *ai <= 0.0 {
            *di = 0.0;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Deterministic values spread over several binades, so a changed summation order would
    /// show in the last bits.
    fn values(n: usize, seed: u64) -> Vec<f64> {
        let mut s = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
        (0..n)
            .map(|_| {
                s ^= s << 13;
                s ^= s >> 7;
                s ^= s << 17;
                let u = (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
                u * f64::powi(10.0, (s % 7) as i32 - 3)
            })
            .collect()
    }

    #[test]
    fn dispatched_matvec_has_the_bits_of_the_portable_dot_per_row() {
        for (rows, cols) in [
            (1, 1),
            (3, 7),
            (4, 8),
            (5, 9),
            (96, 96),
            (5, 96),
            (13, 17),
            (8, 3),
        ] {
            let w = values(rows * cols, (rows * 100 + cols) as u64);
            let x = values(cols, cols as u64 + 7);
            let mut y = vec![f64::NAN; rows];
            matvec(&w, &x, &mut y);
            for (r, yr) in y.iter().enumerate() {
                let want = dot(&w[r * cols..(r + 1) * cols], &x);
                assert_eq!(yr.to_bits(), want.to_bits(), "{rows}x{cols}, row {r}");
            }
            let b = values(rows, 3);
            let mut yb = vec![f64::NAN; rows];
            matvec_bias(&w, &b, &x, &mut yb);
            for r in 0..rows {
                assert_eq!(yb[r].to_bits(), (y[r] + b[r]).to_bits(), "bias, row {r}");
            }
        }
    }

    #[test]
    fn empty_input_gives_zeros() {
        let mut y = [f64::NAN; 3];
        matvec(&[], &[], &mut y);
        assert_eq!(y, [0.0; 3]);
    }
}
