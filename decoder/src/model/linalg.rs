//! Dense kernels on row-major slices for one sample at a time: the daemon's inference path, and
//! the per-sample reference the batched training passes ([`super::gemm`]) are tested against.
//!
//! Plain slices: the daemon's tick must not allocate, the parameters of a model live in one
//! flat vector (so optimizers treat every model alike), and these loops are short enough to
//! read. Every function is deterministic (fixed summation order), which the "same seed, same
//! weights" guarantee relies on.

/// Dot product with eight independent accumulators (enough independent add chains to keep
/// the vector units busy; fixed order, so results are reproducible).
#[inline]
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

/// `y += a * x`.
#[inline]
pub(crate) fn axpy(a: f64, x: &[f64], y: &mut [f64]) {
    debug_assert_eq!(x.len(), y.len());
    for (yi, xi) in y.iter_mut().zip(x) {
        *yi += a * xi;
    }
}

/// `y = W x` with `W` row-major `y.len() x x.len()`.
#[inline]
pub(crate) fn matvec(w: &[f64], x: &[f64], y: &mut [f64]) {
    debug_assert_eq!(w.len(), x.len() * y.len());
    for (row, yi) in w.chunks_exact(x.len()).zip(y.iter_mut()) {
        *yi = dot(row, x);
    }
}

/// `y = W x + b`.
#[inline]
pub(crate) fn matvec_bias(w: &[f64], b: &[f64], x: &[f64], y: &mut [f64]) {
    debug_assert_eq!(b.len(), y.len());
    for ((row, yi), bi) in w.chunks_exact(x.len()).zip(y.iter_mut()).zip(b) {
        *yi = dot(row, x) + bi;
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
