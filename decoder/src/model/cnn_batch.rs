//! The CNN's batched passes: both convolutions as one matrix product each over every
//! (sample, electrode) row of the mini-batch (im2col: each row holds the `kernel` neighbouring
//! electrodes' channels, zero beyond the edges, matching the weights' `(out, tap, in)` layout),
//! the max-pool per sample, the dense layers as matrix products.
//!
//! Layout of [`BatchWork::buf`] for `r` samples (row-major blocks): `col1` (`r·p x k·cin`),
//! `c1` (`r·p x f1`), `col2` (`r·p x k·f1`), `c2` (`r·p x f2`), `pooled` (`r x p2·f2`), `hid`
//! (`r x d`), then the backward blocks `d_hid`, `d_pool`, `d_c2`, `d_col2`, `d_c1`;
//! [`BatchWork::idx`] holds the pool's argmax electrodes (`r x p2·f2`).

use super::batch::BatchWork;
use super::cnn::{Cnn, Dims};
use super::gemm::{acc_col_sums, acc_dt_a, add_row, mul_w, mul_wt};
use super::linalg::{relu, relu_backward};
use super::traits::{Model, Trainable};

/// Block lengths of the work buffer for `r` samples, in layout order.
fn blocks(dm: &Dims, r: usize) -> [usize; 11] {
    let rp = r * dm.p;
    let pool = r * dm.p2 * dm.f2;
    [
        rp * dm.k * dm.cin,
        rp * dm.f1,
        rp * dm.k * dm.f1,
        rp * dm.f2,
        pool,
        r * dm.d,
        r * dm.d,
        pool,
        rp * dm.f2,
        rp * dm.k * dm.f1,
        rp * dm.f1,
    ]
}

/// Splits `buf` into the blocks of [`blocks`].
fn split_blocks<'b>(buf: &'b mut [f64], lens: &[usize; 11]) -> [&'b mut [f64]; 11] {
    let mut out: [&mut [f64]; 11] = Default::default();
    let mut rest = buf;
    for (slot, &n) in out.iter_mut().zip(lens) {
        let (a, b) = rest.split_at_mut(n);
        *slot = a;
        rest = b;
    }
    out
}

/// im2col for a "same"-padded convolution of odd width `k` over sequences of length `p`:
/// row `(s, q)` of `col` holds input rows `q - k/2 ..= q + k/2` of sample `s` (zero outside).
fn im2col(input: &[f64], p: usize, cin: usize, k: usize, col: &mut [f64]) {
    let pad = k / 2;
    for (s, sample) in input.chunks_exact(p * cin).enumerate() {
        for q in 0..p {
            let row = &mut col[(s * p + q) * k * cin..(s * p + q + 1) * k * cin];
            for (t, dst) in row.chunks_exact_mut(cin).enumerate() {
                match (q + t).checked_sub(pad).filter(|&src| src < p) {
                    Some(src) => dst.copy_from_slice(&sample[src * cin..(src + 1) * cin]),
                    None => dst.fill(0.0),
                }
            }
        }
    }
}

/// The adjoint of [`im2col`]: `din = Σ` of every column block back onto its input row.
fn col2im(dcol: &[f64], p: usize, cin: usize, k: usize, din: &mut [f64]) {
    let pad = k / 2;
    din.fill(0.0);
    for (s, sample) in din.chunks_exact_mut(p * cin).enumerate() {
        for q in 0..p {
            let row = &dcol[(s * p + q) * k * cin..(s * p + q + 1) * k * cin];
            for (t, src) in row.chunks_exact(cin).enumerate() {
                if let Some(dst) = (q + t).checked_sub(pad).filter(|&d| d < p) {
                    for (a, b) in sample[dst * cin..(dst + 1) * cin].iter_mut().zip(src) {
                        *a += b;
                    }
                }
            }
        }
    }
}

impl Cnn {
    /// Floats and indices of [`BatchWork`] for `rows` samples.
    pub(crate) fn batch_size(&self, rows: usize) -> (usize, usize) {
        let dm = self.d();
        (blocks(&dm, rows).iter().sum(), rows * dm.p2 * dm.f2)
    }

    /// The batched forward pass (see [`Trainable::forward_batch`]).
    pub(crate) fn forward_rows(&self, x: &[f64], y: &mut [f64], work: &mut BatchWork) {
        let (n_in, n_out) = (self.n_inputs(), self.n_outputs());
        let r = x.len() / n_in;
        assert!(
            x.len() == r * n_in && y.len() == r * n_out,
            "CNN batch: x and y must hold the same number of whole rows"
        );
        let (nf, ni) = self.batch_size(r);
        work.ensure(nf, ni);
        let dm = self.d();
        let [w1, b1, w2, b2, wd1, bd1, wd2, bd2] = self.split();
        let [col1, c1, col2, c2, pooled, hid, ..] = split_blocks(&mut work.buf, &blocks(&dm, r));
        let rp = r * dm.p;
        im2col(x, dm.p, dm.cin, dm.k, col1);
        mul_wt(col1, w1, c1, rp, dm.k * dm.cin, dm.f1);
        add_row(c1, b1);
        relu(c1);
        im2col(c1, dm.p, dm.f1, dm.k, col2);
        mul_wt(col2, w2, c2, rp, dm.k * dm.f1, dm.f2);
        add_row(c2, b2);
        relu(c2);
        let pool = dm.p2 * dm.f2;
        for (s, (out, idx)) in pooled
            .chunks_exact_mut(pool)
            .zip(work.idx.chunks_exact_mut(pool))
            .enumerate()
        {
            let c2s = &c2[s * dm.p * dm.f2..(s + 1) * dm.p * dm.f2];
            for (i, (o, src)) in out.iter_mut().zip(idx.iter_mut()).enumerate() {
                let (pp, c) = (i / dm.f2, i % dm.f2);
                let (a, b) = (c2s[2 * pp * dm.f2 + c], c2s[(2 * pp + 1) * dm.f2 + c]);
                // Ties go to the first element, as in PyTorch.
                (*o, *src) = if b > a { (b, 2 * pp + 1) } else { (a, 2 * pp) };
            }
        }
        mul_wt(pooled, wd1, hid, r, pool, dm.d);
        add_row(hid, bd1);
        relu(hid);
        mul_wt(hid, wd2, y, r, dm.d, n_out);
        add_row(y, bd2);
    }

    /// The batched backward pass (see [`Trainable::backward_batch`]).
    pub(crate) fn backward_rows(
        &self,
        x: &[f64],
        dy: &[f64],
        work: &mut BatchWork,
        grad: &mut [f64],
    ) {
        let (n_in, n_out) = (self.n_inputs(), self.n_outputs());
        let r = x.len() / n_in;
        let (nf, ni) = self.batch_size(r);
        assert!(
            dy.len() == r * n_out && work.buf.len() >= nf && work.idx.len() >= ni,
            "CNN batch: dy rows or work do not match x"
        );
        assert_eq!(grad.len(), self.params().len(), "CNN gradient length");
        let dm = self.d();
        let [_, _, w2, _, wd1, _, wd2, _] = self.split();
        let [gw1, gb1, gw2, gb2, gwd1, gbd1, gwd2, gbd2] = split_grad(grad, &dm);
        let [col1, c1, col2, c2, pooled, hid, d_hid, d_pool, d_c2, d_col2, d_c1] =
            split_blocks(&mut work.buf, &blocks(&dm, r));
        let (rp, pool) = (r * dm.p, dm.p2 * dm.f2);

        acc_dt_a(gwd2, dy, hid, r, n_out, dm.d);
        acc_col_sums(gbd2, dy);
        mul_w(dy, wd2, d_hid, r, n_out, dm.d);
        relu_backward(hid, d_hid);
        acc_dt_a(gwd1, d_hid, pooled, r, dm.d, pool);
        acc_col_sums(gbd1, d_hid);
        mul_w(d_hid, wd1, d_pool, r, dm.d, pool);
        d_c2.fill(0.0);
        for (i, (&dv, &src)) in d_pool.iter().zip(&work.idx[..r * pool]).enumerate() {
            let (s, c) = (i / pool, i % dm.f2);
            d_c2[(s * dm.p + src) * dm.f2 + c] += dv;
        }
        relu_backward(c2, d_c2);
        acc_dt_a(gw2, d_c2, col2, rp, dm.f2, dm.k * dm.f1);
        acc_col_sums(gb2, d_c2);
        mul_w(d_c2, w2, d_col2, rp, dm.f2, dm.k * dm.f1);
        col2im(d_col2, dm.p, dm.f1, dm.k, d_c1);
        relu_backward(c1, d_c1);
        acc_dt_a(gw1, d_c1, col1, rp, dm.f1, dm.k * dm.cin);
        acc_col_sums(gb1, d_c1);
    }
}

/// The gradient split into the eight tensors of [`Dims::sizes`].
fn split_grad<'g>(grad: &'g mut [f64], dm: &Dims) -> [&'g mut [f64]; 8] {
    let mut out: [&mut [f64]; 8] = Default::default();
    let mut rest = grad;
    for (slot, n) in out.iter_mut().zip(dm.sizes()) {
        let (a, b) = rest.split_at_mut(n);
        *slot = a;
        rest = b;
    }
    out
}
