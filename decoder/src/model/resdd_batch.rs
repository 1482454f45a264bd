//! ResDD's batched passes: the model of [`super::resdd`] for a whole mini-batch as matrix
//! products (`X = x·W_inᵀ`, `G_l = A_{l-1}·W_lᵀ`, `y = A_L·W_outᵀ`, and their transposes back).
//!
//! Layout of [`BatchWork::buf`] for `r` rows, width `h`, `L` modules (each block `r x h`,
//! row-major): `X`, `G_1..G_L`, `A_1..A_L`, then the backward blocks `dA`, `dA_prev`, `dG`, `dX`.

use super::batch::BatchWork;
use super::gemm::{acc_dt_a, mul_w, mul_wt};
use super::resdd::ResDd;
use super::spec::ResDdVariant;
use super::traits::{Model, Trainable};

impl ResDd {
    /// Floats of [`BatchWork`] for `rows` samples.
    pub(crate) fn batch_floats(&self, rows: usize) -> usize {
        (5 + 2 * self.spec().modules) * self.spec().hidden * rows
    }

    /// The batched forward pass (see [`super::Trainable::forward_batch`]).
    pub(crate) fn forward_rows(&self, x: &[f64], y: &mut [f64], work: &mut BatchWork) {
        let (n_in, n_out) = (self.n_inputs(), self.n_outputs());
        let rows = x.len() / n_in;
        assert!(
            x.len() == rows * n_in && y.len() == rows * n_out,
            "ResDD batch: x and y must hold the same number of whole rows"
        );
        work.ensure(self.batch_floats(rows), 0);
        let (h, l_count) = (self.spec().hidden, self.spec().modules);
        let blk = rows * h;
        let (w_in, w_mods, w_out) = self.split_params();
        let (xh, rest) = work.buf.split_at_mut(blk);
        let (g_all, rest) = rest.split_at_mut(l_count * blk);
        let a_all = &mut rest[..l_count * blk];
        mul_wt(x, w_in, xh, rows, n_in, h);
        for l in 0..l_count {
            let g = &mut g_all[l * blk..(l + 1) * blk];
            let (before, after) = a_all.split_at_mut(l * blk);
            let prev: &[f64] = if l == 0 { xh } else { &before[(l - 1) * blk..] };
            mul_wt(prev, &w_mods[l * h * h..(l + 1) * h * h], g, rows, h, h);
            let gate: &[f64] = match self.spec().variant {
                ResDdVariant::InputGated => xh,
                ResDdVariant::Chained => prev,
            };
            for ((a, gi), mi) in after[..blk].iter_mut().zip(g.iter()).zip(gate) {
                *a = gi * mi + gi;
            }
        }
        let last: &[f64] = if l_count == 0 {
            xh
        } else {
            &a_all[(l_count - 1) * blk..]
        };
        mul_wt(last, w_out, y, rows, h, n_out);
    }

    /// The batched backward pass (see [`super::Trainable::backward_batch`]).
    pub(crate) fn backward_rows(
        &self,
        x: &[f64],
        dy: &[f64],
        work: &mut BatchWork,
        grad: &mut [f64],
    ) {
        let (n_in, n_out) = (self.n_inputs(), self.n_outputs());
        let rows = x.len() / n_in;
        assert!(
            dy.len() == rows * n_out && work.buf.len() >= self.batch_floats(rows),
            "ResDD batch: dy rows or work do not match x"
        );
        assert_eq!(grad.len(), self.params().len(), "ResDD gradient length");
        let (h, l_count) = (self.spec().hidden, self.spec().modules);
        let blk = rows * h;
        let (_, w_mods, w_out) = self.split_params();
        let (g_in, rest) = grad.split_at_mut(h * n_in);
        let (g_mods, g_out) = rest.split_at_mut(l_count * h * h);
        let (fwd, back) = work.buf.split_at_mut((1 + 2 * l_count) * blk);
        let (xh, rest) = fwd.split_at(blk);
        let (g_all, a_all) = rest.split_at(l_count * blk);
        let a_of = |l: usize| {
            if l == 0 {
                xh
            } else {
                &a_all[(l - 1) * blk..l * blk]
            }
        };
        let (da, rest) = back.split_at_mut(blk);
        let (dprev, rest) = rest.split_at_mut(blk);
        let (dg, rest) = rest.split_at_mut(blk);
        let dx = &mut rest[..blk];

        acc_dt_a(g_out, dy, a_of(l_count), rows, n_out, h);
        mul_w(dy, w_out, da, rows, n_out, h);
        dx.fill(0.0);
        for l in (1..=l_count).rev() {
            let (g, prev) = (&g_all[(l - 1) * blk..l * blk], a_of(l - 1));
            let chained = self.spec().variant == ResDdVariant::Chained;
            let gate = if chained { prev } else { xh };
            // A = G∘(M + 1): dG = dA∘(M + 1), dM = dA∘G.
            for ((dgi, dai), m) in dg.iter_mut().zip(da.iter()).zip(gate) {
                *dgi = dai * (m + 1.0);
            }
            let m = (l - 1) * h * h..l * h * h;
            acc_dt_a(&mut g_mods[m.clone()], dg, prev, rows, h, h);
            mul_w(dg, &w_mods[m], dprev, rows, h, h);
            let d_m: &mut [f64] = if chained { &mut *dprev } else { &mut *dx };
            for ((dm, dai), gi) in d_m.iter_mut().zip(da.iter()).zip(g) {
                *dm += dai * gi;
            }
            da.copy_from_slice(dprev);
        }
        // A_0 = X.
        for (dxi, dai) in dx.iter_mut().zip(da.iter()) {
            *dxi += dai;
        }
        acc_dt_a(g_in, dx, x, rows, h, n_in);
    }
}
