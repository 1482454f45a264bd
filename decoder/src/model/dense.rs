//! The two three-layer dense baselines of the paper:
//! - **LN**: `y = W3·W2·W1·x`, bias-free, no activation (a linear map in factored form, so zero
//!   input gives zero output).
//! - **MLP**: `y = W3·relu(W2·relu(W1·x + b1) + b2) + b3`. It has biases, as the paper's
//!   baseline (PyTorch's `nn.Linear` default) most likely did; therefore, unlike ResDD and LN,
//!   zero input does **not** give exactly zero output.
//!
//! Initialisation: LN Glorot-uniform everywhere; MLP He-uniform before each ReLU, Glorot for the
//! output layer, biases zero.

use super::batch::BatchWork;
use super::error::{check_params, ModelError};
use super::init::SeededRng;
use super::kind::ModelKind;
use super::linalg::{axpy, matvec, matvec_bias, matvec_t, outer_acc, relu, relu_backward};
use super::spec::{check_width, LnSpec, MlpSpec};
use super::traits::{check_io, stacked, Model, Scratch, TensorInfo, Trainable};

/// LN or MLP (see the module docs); `kind()` says which.
#[derive(Debug, Clone, PartialEq)]
pub struct DenseNet {
    kind: ModelKind,
    n_in: usize,
    hidden: [usize; 2],
    n_out: usize,
    params: Vec<f64>,
}

impl DenseNet {
    fn is_mlp(kind: ModelKind) -> bool {
        kind == ModelKind::Mlp
    }

    /// `(rows, cols)` of the three weight matrices.
    fn layer_shapes(n_in: usize, hidden: [usize; 2], n_out: usize) -> [(usize, usize); 3] {
        [
            (hidden[0], n_in),
            (hidden[1], hidden[0]),
            (n_out, hidden[1]),
        ]
    }

    /// Number of parameters for a shape (`kind` is `Ln` or `Mlp`).
    pub fn param_count(kind: ModelKind, n_in: usize, hidden: [usize; 2], n_out: usize) -> usize {
        let bias = Self::is_mlp(kind);
        Self::layer_shapes(n_in, hidden, n_out)
            .iter()
            .map(|&(r, c)| r * c + if bias { r } else { 0 })
            .sum()
    }

    fn check(
        kind: ModelKind,
        n_in: usize,
        hidden: [usize; 2],
        n_out: usize,
    ) -> Result<(), ModelError> {
        if !matches!(kind, ModelKind::Ln | ModelKind::Mlp) {
            return Err(ModelError::InvalidSpec(format!(
                "DenseNet cannot be a {kind} model"
            )));
        }
        check_width("input size", n_in)?;
        check_width("first hidden width", hidden[0])?;
        check_width("second hidden width", hidden[1])?;
        check_width("output size", n_out)
    }

    /// The tensors of an LN (`w1..w3`) or MLP (`w1, b1.bias, .., b3.bias`) of this shape,
    /// without building one. Errors on an invalid shape.
    pub fn layout(
        kind: ModelKind,
        n_in: usize,
        hidden: [usize; 2],
        n_out: usize,
    ) -> Result<Vec<TensorInfo>, ModelError> {
        Self::check(kind, n_in, hidden, n_out)?;
        let mut named = Vec::new();
        for (j, (r, c)) in Self::layer_shapes(n_in, hidden, n_out)
            .into_iter()
            .enumerate()
        {
            named.push((format!("w{}", j + 1), vec![r, c]));
            if Self::is_mlp(kind) {
                named.push((format!("b{}.bias", j + 1), vec![r]));
            }
        }
        Ok(stacked(named))
    }

    /// An LN model from its parameters `[W1, W2, W3]` (row-major).
    pub fn ln_from_params(
        spec: LnSpec,
        n_in: usize,
        n_out: usize,
        params: Vec<f64>,
    ) -> Result<Self, ModelError> {
        Self::from_params(ModelKind::Ln, n_in, spec.hidden, n_out, params)
    }

    /// An MLP from its parameters `[W1, b1, W2, b2, W3, b3]` (row-major).
    pub fn mlp_from_params(
        spec: MlpSpec,
        n_in: usize,
        n_out: usize,
        params: Vec<f64>,
    ) -> Result<Self, ModelError> {
        Self::from_params(ModelKind::Mlp, n_in, spec.hidden, n_out, params)
    }

    fn from_params(
        kind: ModelKind,
        n_in: usize,
        hidden: [usize; 2],
        n_out: usize,
        params: Vec<f64>,
    ) -> Result<Self, ModelError> {
        Self::check(kind, n_in, hidden, n_out)?;
        let expected = Self::param_count(kind, n_in, hidden, n_out);
        check_params(&kind.to_string(), expected, &params)?;
        Ok(DenseNet {
            kind,
            n_in,
            hidden,
            n_out,
            params,
        })
    }

    /// A randomly initialised LN model.
    pub fn ln_random(
        spec: LnSpec,
        n_in: usize,
        n_out: usize,
        seed: u64,
    ) -> Result<Self, ModelError> {
        Self::init(
            ModelKind::Ln,
            n_in,
            spec.hidden,
            n_out,
            &mut SeededRng::new(seed),
        )
    }

    /// A randomly initialised MLP.
    pub fn mlp_random(
        spec: MlpSpec,
        n_in: usize,
        n_out: usize,
        seed: u64,
    ) -> Result<Self, ModelError> {
        Self::init(
            ModelKind::Mlp,
            n_in,
            spec.hidden,
            n_out,
            &mut SeededRng::new(seed),
        )
    }

    pub(crate) fn init(
        kind: ModelKind,
        n_in: usize,
        hidden: [usize; 2],
        n_out: usize,
        rng: &mut SeededRng,
    ) -> Result<Self, ModelError> {
        Self::check(kind, n_in, hidden, n_out)?;
        let mut net = DenseNet {
            kind,
            n_in,
            hidden,
            n_out,
            params: vec![0.0; Self::param_count(kind, n_in, hidden, n_out)],
        };
        let mlp = Self::is_mlp(kind);
        for t in net.tensors() {
            if t.name.ends_with("bias") {
                continue; // biases start at zero
            }
            let (rows, cols) = (t.shape[0], t.shape[1]);
            let w = &mut net.params[t.offset..t.offset + t.len()];
            // Tensor order: w1, (b1), w2, (b2), w3, (b3); the last weight is the output layer.
            let is_output = t.name == "w3";
            if mlp && !is_output {
                rng.he(w, cols);
            } else {
                rng.xavier(w, cols, rows, 1.0);
            }
        }
        Ok(net)
    }

    /// The two hidden widths.
    pub(crate) fn hidden(&self) -> [usize; 2] {
        self.hidden
    }

    pub(crate) fn has_bias(&self) -> bool {
        Self::is_mlp(self.kind)
    }

    /// Slices `(W, b)` of layer `i` (b empty for LN).
    pub(crate) fn layer(&self, i: usize) -> (&[f64], &[f64]) {
        let shapes = Self::layer_shapes(self.n_in, self.hidden, self.n_out);
        let mut off = 0;
        for (j, &(r, c)) in shapes.iter().enumerate() {
            let nb = if self.has_bias() { r } else { 0 };
            if j == i {
                return (
                    &self.params[off..off + r * c],
                    &self.params[off + r * c..off + r * c + nb],
                );
            }
            off += r * c + nb;
        }
        unreachable!("layer index {i} out of 0..3")
    }
}

impl Model for DenseNet {
    fn kind(&self) -> ModelKind {
        self.kind
    }
    fn n_inputs(&self) -> usize {
        self.n_in
    }
    fn n_outputs(&self) -> usize {
        self.n_out
    }
    fn scratch_size(&self) -> (usize, usize) {
        (2 * (self.hidden[0] + self.hidden[1]), 0)
    }

    fn predict_with(&self, x: &[f64], y: &mut [f64], scratch: &mut Scratch) {
        check_io(self, x, y.len());
        let (nf, ni) = self.scratch_size();
        scratch.ensure(nf, ni);
        let [h1, h2] = self.hidden;
        let (a1, rest) = scratch.buf.split_at_mut(h1);
        let a2 = &mut rest[..h2];
        let ((w1, b1), (w2, b2), (w3, b3)) = (self.layer(0), self.layer(1), self.layer(2));
        if self.has_bias() {
            matvec_bias(w1, b1, x, a1);
            relu(a1);
            matvec_bias(w2, b2, a1, a2);
            relu(a2);
            matvec_bias(w3, b3, a2, y);
        } else {
            matvec(w1, x, a1);
            matvec(w2, a1, a2);
            matvec(w3, a2, y);
        }
    }
}

impl Trainable for DenseNet {
    fn params(&self) -> &[f64] {
        &self.params
    }
    fn params_mut(&mut self) -> &mut [f64] {
        &mut self.params
    }

    fn tensors(&self) -> Vec<TensorInfo> {
        Self::layout(self.kind, self.n_in, self.hidden, self.n_out)
            .expect("validated at construction")
    }

    fn backward(&self, x: &[f64], dy: &[f64], scratch: &mut Scratch, grad: &mut [f64]) {
        check_io(self, x, dy.len());
        assert_eq!(
            grad.len(),
            self.params.len(),
            "{} gradient length",
            self.kind
        );
        let [h1, h2] = self.hidden;
        let (a1, rest) = scratch.buf.split_at_mut(h1);
        let (a2, rest) = rest.split_at_mut(h2);
        let (d2, rest) = rest.split_at_mut(h2);
        let d1 = &mut rest[..h1];
        let (w2, _) = self.layer(1);
        let (w3, _) = self.layer(2);
        let bias = self.has_bias();
        let shapes = Self::layer_shapes(self.n_in, self.hidden, self.n_out);
        let sizes = shapes.map(|(r, c)| r * c);
        let nb = |r: usize| if bias { r } else { 0 };
        let (g1, rest) = grad.split_at_mut(sizes[0]);
        let (gb1, rest) = rest.split_at_mut(nb(h1));
        let (g2, rest) = rest.split_at_mut(sizes[1]);
        let (gb2, rest) = rest.split_at_mut(nb(h2));
        let (g3, gb3) = rest.split_at_mut(sizes[2]);

        outer_acc(g3, dy, a2);
        if bias {
            axpy(1.0, dy, gb3);
        }
        matvec_t(w3, dy, d2);
        if bias {
            relu_backward(a2, d2);
        }
        outer_acc(g2, d2, a1);
        if bias {
            axpy(1.0, d2, gb2);
        }
        matvec_t(w2, d2, d1);
        if bias {
            relu_backward(a1, d1);
        }
        outer_acc(g1, d1, x);
        if bias {
            axpy(1.0, d1, gb1);
        }
    }

    fn batch_work_size(&self, rows: usize) -> (usize, usize) {
        (self.batch_floats(rows), 0)
    }
    fn forward_batch(&self, x: &[f64], y: &mut [f64], work: &mut BatchWork) {
        self.forward_rows(x, y, work);
    }
    fn backward_batch(&self, x: &[f64], dy: &[f64], work: &mut BatchWork, grad: &mut [f64]) {
        self.backward_rows(x, dy, work, grad);
    }
}
