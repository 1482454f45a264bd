//! LN's and MLP's batched passes: the three layers of [`super::dense`] for a whole mini-batch
//! as matrix products.
//!
//! Layout of [`BatchWork::buf`] for `r` rows and hidden widths `h1`, `h2` (row-major blocks):
//! `a1` (`r x h1`), `a2` (`r x h2`), then the backward blocks `d2` (`r x h2`), `d1` (`r x h1`).

use super::batch::BatchWork;
use super::dense::DenseNet;
use super::gemm::{acc_col_sums, acc_dt_a, add_row, mul_w, mul_wt};
use super::linalg::{relu, relu_backward};
use super::traits::{Model, Trainable};

impl DenseNet {
    /// Floats of [`BatchWork`] for `rows` samples.
    pub(crate) fn batch_floats(&self, rows: usize) -> usize {
        let [h1, h2] = self.hidden();
        2 * (h1 + h2) * rows
    }

    /// One layer for `rows` samples: `out = a·Wᵀ (+ b)`, then ReLU if `relu_after`.
    fn layer_rows(&self, i: usize, a: &[f64], out: &mut [f64], rows: usize, relu_after: bool) {
        let (w, b) = self.layer(i);
        let (k, n) = (a.len() / rows.max(1), out.len() / rows.max(1));
        mul_wt(a, w, out, rows, k, n);
        if self.has_bias() {
            add_row(out, b);
            if relu_after {
                relu(out);
            }
        }
    }

    /// The batched forward pass (see [`Trainable::forward_batch`]).
    pub(crate) fn forward_rows(&self, x: &[f64], y: &mut [f64], work: &mut BatchWork) {
        let (n_in, n_out) = (self.n_inputs(), self.n_outputs());
        let rows = x.len() / n_in;
        assert!(
            x.len() == rows * n_in && y.len() == rows * n_out,
            "{} batch: x and y must hold the same number of whole rows",
            self.kind()
        );
        work.ensure(self.batch_floats(rows), 0);
        let [h1, h2] = self.hidden();
        let (a1, rest) = work.buf.split_at_mut(rows * h1);
        let a2 = &mut rest[..rows * h2];
        self.layer_rows(0, x, a1, rows, true);
        self.layer_rows(1, a1, a2, rows, true);
        self.layer_rows(2, a2, y, rows, false);
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
        let rows = x.len() / n_in;
        assert!(
            dy.len() == rows * n_out && work.buf.len() >= self.batch_floats(rows),
            "{} batch: dy rows or work do not match x",
            self.kind()
        );
        assert_eq!(
            grad.len(),
            self.params().len(),
            "{} gradient length",
            self.kind()
        );
        let [h1, h2] = self.hidden();
        let (a1, rest) = work.buf.split_at_mut(rows * h1);
        let (a2, rest) = rest.split_at_mut(rows * h2);
        let (d2, rest) = rest.split_at_mut(rows * h2);
        let d1 = &mut rest[..rows * h1];
        let bias = self.has_bias();
        let [g1, gb1, g2, gb2, g3, gb3] = self.split_grad(grad);
        let (w2, w3) = (self.layer(1).0, self.layer(2).0);

        acc_dt_a(g3, dy, a2, rows, n_out, h2);
        mul_w(dy, w3, d2, rows, n_out, h2);
        if bias {
            acc_col_sums(gb3, dy);
            relu_backward(a2, d2);
        }
        acc_dt_a(g2, d2, a1, rows, h2, h1);
        mul_w(d2, w2, d1, rows, h2, h1);
        if bias {
            acc_col_sums(gb2, d2);
            relu_backward(a1, d1);
        }
        acc_dt_a(g1, d1, x, rows, h1, n_in);
        if bias {
            acc_col_sums(gb1, d1);
        }
    }

    /// The gradient split as `[W1, b1, W2, b2, W3, b3]` (the biases empty for LN).
    fn split_grad<'g>(&self, grad: &'g mut [f64]) -> [&'g mut [f64]; 6] {
        let [h1, h2] = self.hidden();
        let n_b = |r: usize| if self.has_bias() { r } else { 0 };
        let sizes = [
            h1 * self.n_inputs(),
            n_b(h1),
            h2 * h1,
            n_b(h2),
            self.n_outputs() * h2,
            n_b(self.n_outputs()),
        ];
        let mut out: [&mut [f64]; 6] = Default::default();
        let mut rest = grad;
        for (slot, n) in out.iter_mut().zip(sizes) {
            let (a, b) = rest.split_at_mut(n);
            *slot = a;
            rest = b;
        }
        out
    }
}
