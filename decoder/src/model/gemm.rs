//! Matrix products over a mini-batch, on row-major slices: the batched training passes.
//!
//! Safe wrappers over nalgebra's `gemm` on strided views, which for these shapes runs
//! matrixmultiply's packed kernels (runtime AVX2/FMA detection on x86-64, NEON on aarch64):
//! about five times the throughput of one matrix-vector product per sample (see
//! `decoder/BENCHMARKS-model.md`). Single-threaded and with a fixed blocking, so the same shapes
//! on the same machine give the same bits; the summation order differs from [`super::linalg`]'s
//! per-sample kernels in the last bits. No heap allocation by the wrappers themselves.

use nalgebra::{DMatrixView, DMatrixViewMut};

use super::linalg::{matvec, matvec_t, outer_acc};

/// nalgebra hands a product to matrixmultiply only when every dimension exceeds 5; below that
/// its own loop walks strided (row-major) views wrongly, so smaller products (the 5-finger
/// output layer, tiny test shapes) run here row by row with the per-sample kernels instead.
fn packed(m: usize, k: usize, n: usize) -> bool {
    m > 5 && k > 5 && n > 5
}

/// Row-major `rows x cols` matrix in `s` (read).
fn view(s: &[f64], rows: usize, cols: usize) -> DMatrixView<'_, f64, nalgebra::Dyn, nalgebra::Dyn> {
    debug_assert_eq!(s.len(), rows * cols);
    DMatrixView::from_slice_with_strides(s, rows, cols, cols, 1)
}

/// The transpose (`cols x rows`) of the row-major `rows x cols` matrix in `s`.
fn view_t(
    s: &[f64],
    rows: usize,
    cols: usize,
) -> DMatrixView<'_, f64, nalgebra::Dyn, nalgebra::Dyn> {
    debug_assert_eq!(s.len(), rows * cols);
    DMatrixView::from_slice_with_strides(s, cols, rows, 1, cols)
}

/// Row-major `rows x cols` matrix in `s` (written).
fn view_mut(
    s: &mut [f64],
    rows: usize,
    cols: usize,
) -> DMatrixViewMut<'_, f64, nalgebra::Dyn, nalgebra::Dyn> {
    debug_assert_eq!(s.len(), rows * cols);
    DMatrixViewMut::from_slice_with_strides_mut(s, rows, cols, cols, 1)
}

/// `c = a · wᵀ` with `a` `m x k`, `w` `n x k` (a layer's weights, one row per output), `c`
/// `m x n`: the forward pass of a linear layer for `m` samples at once.
pub(crate) fn mul_wt(a: &[f64], w: &[f64], c: &mut [f64], m: usize, k: usize, n: usize) {
    if !packed(m, k, n) {
        for (ai, ci) in a.chunks_exact(k).zip(c.chunks_exact_mut(n)) {
            matvec(w, ai, ci);
        }
        return;
    }
    view_mut(c, m, n).gemm(1.0, &view(a, m, k), &view_t(w, n, k), 0.0);
}

/// `c = d · w` with `d` `m x n`, `w` `n x k`, `c` `m x k`: the input gradient of a linear
/// layer for `m` samples.
pub(crate) fn mul_w(d: &[f64], w: &[f64], c: &mut [f64], m: usize, n: usize, k: usize) {
    if !packed(m, n, k) {
        for (di, ci) in d.chunks_exact(n).zip(c.chunks_exact_mut(k)) {
            matvec_t(w, di, ci);
        }
        return;
    }
    view_mut(c, m, k).gemm(1.0, &view(d, m, n), &view(w, n, k), 0.0);
}

/// `g += dᵀ · a` with `d` `m x n`, `a` `m x k`, `g` `n x k`: a linear layer's weight gradient
/// summed over `m` samples.
pub(crate) fn acc_dt_a(g: &mut [f64], d: &[f64], a: &[f64], m: usize, n: usize, k: usize) {
    if !packed(n, m, k) {
        for (di, ai) in d.chunks_exact(n).zip(a.chunks_exact(k)) {
            outer_acc(g, di, ai);
        }
        return;
    }
    view_mut(g, n, k).gemm(1.0, &view_t(d, m, n), &view(a, m, k), 1.0);
}

/// `g[j] += Σ_i d[i][j]` for `d` `m x n` (a bias gradient summed over the samples, in order).
pub(crate) fn acc_col_sums(g: &mut [f64], d: &[f64]) {
    for row in d.chunks_exact(g.len()) {
        for (gj, dj) in g.iter_mut().zip(row) {
            *gj += dj;
        }
    }
}

/// `c[i] += b` for every row `c[i]` of `c` (a bias added to every sample).
pub(crate) fn add_row(c: &mut [f64], b: &[f64]) {
    for row in c.chunks_exact_mut(b.len()) {
        for (ci, bi) in row.iter_mut().zip(b) {
            *ci += bi;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn naive(a: &[f64], b: &[f64], m: usize, k: usize, n: usize) -> Vec<f64> {
        let mut c = vec![0.0; m * n];
        for i in 0..m {
            for j in 0..n {
                c[i * n + j] = (0..k).map(|p| a[i * k + p] * b[p * n + j]).sum();
            }
        }
        c
    }

    fn t(a: &[f64], r: usize, c: usize) -> Vec<f64> {
        (0..c * r).map(|i| a[(i % r) * c + i / r]).collect()
    }

    #[test]
    fn products_match_the_definition() {
        for (m, k, n) in [(7, 11, 9), (32, 96, 5), (3, 8, 7), (1, 6, 6)] {
            check(m, k, n);
        }
    }

    fn check(m: usize, k: usize, n: usize) {
        let a: Vec<f64> = (0..m * k).map(|i| ((i * 37 % 17) as f64) - 8.0).collect();
        let w: Vec<f64> = (0..n * k).map(|i| ((i * 13 % 19) as f64) - 9.0).collect();
        let close = |x: &[f64], y: &[f64]| x.iter().zip(y).all(|(p, q)| (p - q).abs() < 1e-9);
        let mut c = vec![f64::NAN; m * n];
        mul_wt(&a, &w, &mut c, m, k, n);
        assert!(close(&c, &naive(&a, &t(&w, n, k), m, k, n)));
        let mut back = vec![f64::NAN; m * k];
        mul_w(&c, &w, &mut back, m, n, k);
        assert!(close(&back, &naive(&c, &w, m, n, k)));
        let mut g = vec![1.0; n * k];
        acc_dt_a(&mut g, &c, &a, m, n, k);
        let want: Vec<f64> = naive(&t(&c, m, n), &a, n, m, k)
            .iter()
            .map(|v| v + 1.0)
            .collect();
        assert!(close(&g, &want));
    }
}
