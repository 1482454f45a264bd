//! The interface every architecture implements: inference without allocation, and the flat
//! parameter vector plus analytic gradient that training and gradient checks use.

use super::batch::BatchWork;
use super::kind::ModelKind;

/// Work memory for one forward (and backward) pass of one model.
///
/// Inference must not allocate in the daemon's tick, yet a model must stay shareable (`&self`),
/// so activations live here, in a buffer the caller creates once with [`Model::new_scratch`] and
/// reuses. After [`Model::predict_with`] it holds the activations that [`Trainable::backward`]
/// needs.
#[derive(Debug, Clone, Default)]
pub struct Scratch {
    pub(crate) buf: Vec<f64>,
    pub(crate) idx: Vec<usize>,
}

impl Scratch {
    /// Scratch with room for `n_f64` floats and `n_idx` indices (normally via [`Model::new_scratch`]).
    pub fn with_capacity(n_f64: usize, n_idx: usize) -> Self {
        Scratch {
            buf: vec![0.0; n_f64],
            idx: vec![0; n_idx],
        }
    }

    /// Grows the buffers if a model needs more than they hold (no-op when big enough).
    pub(crate) fn ensure(&mut self, n_f64: usize, n_idx: usize) {
        if self.buf.len() < n_f64 {
            self.buf.resize(n_f64, 0.0);
        }
        if self.idx.len() < n_idx {
            self.idx.resize(n_idx, 0);
        }
    }
}

/// One named parameter tensor inside a model's flat parameter vector.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TensorInfo {
    /// Name, e.g. "w_in", "w_mod.1", "conv1.bias".
    pub name: String,
    /// Shape, row-major (e.g. `[rows, cols]`).
    pub shape: Vec<usize>,
    /// Offset of the first element in the flat parameter vector.
    pub offset: usize,
}

impl TensorInfo {
    /// Number of elements.
    pub fn len(&self) -> usize {
        self.shape.iter().product()
    }

    /// Whether the tensor has no elements.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// Offsets for tensors stored back to back in the given order.
pub(crate) fn stacked(named: Vec<(String, Vec<usize>)>) -> Vec<TensorInfo> {
    let mut offset = 0;
    named
        .into_iter()
        .map(|(name, shape)| {
            let t = TensorInfo {
                name,
                shape,
                offset,
            };
            offset += t.len();
            t
        })
        .collect()
}

/// A feature-to-label model with fixed input and output sizes.
///
/// `predict_with` is the daemon's path: no allocation, no `Result`; it panics only if `x`, `y`
/// have the wrong length (a programming error; shapes are validated once when a model file is
/// loaded). `predict` is the convenient offline path and allocates its scratch per call.
pub trait Model {
    /// The architecture.
    fn kind(&self) -> ModelKind;
    /// Length of the input (feature) vector.
    fn n_inputs(&self) -> usize;
    /// Length of the output vector (5 fingers for trained decoders).
    fn n_outputs(&self) -> usize;
    /// Floats and indices of scratch a pass needs.
    fn scratch_size(&self) -> (usize, usize);

    /// Scratch big enough for this model.
    fn new_scratch(&self) -> Scratch {
        let (f, i) = self.scratch_size();
        Scratch::with_capacity(f, i)
    }

    /// Computes `y = f(x)`, keeping activations in `scratch`. Allocates only if `scratch` is
    /// smaller than [`Model::scratch_size`] (never when it came from [`Model::new_scratch`]).
    fn predict_with(&self, x: &[f64], y: &mut [f64], scratch: &mut Scratch);

    /// Computes `y = f(x)` with a temporary scratch (allocates; for offline use).
    fn predict(&self, x: &[f64], y: &mut [f64]) {
        let mut s = self.new_scratch();
        self.predict_with(x, y, &mut s);
    }
}

/// A model whose parameters are one flat vector with an analytic gradient.
pub trait Trainable: Model {
    /// All parameters, in the order of [`Trainable::tensors`].
    fn params(&self) -> &[f64];
    /// Mutable access to the parameters (optimizers, tests).
    fn params_mut(&mut self) -> &mut [f64];
    /// Names and shapes of the tensors making up the parameter vector.
    fn tensors(&self) -> Vec<TensorInfo>;
    /// Accumulates `∂L/∂θ` into `grad` (same length as `params`) given `dy = ∂L/∂y`.
    ///
    /// Must follow a [`Model::predict_with`] on the same `x` with the same `scratch`, whose
    /// activations it reads (backward buffers also live in `scratch`).
    fn backward(&self, x: &[f64], dy: &[f64], scratch: &mut Scratch, grad: &mut [f64]);

    /// Floats and indices of [`BatchWork`] a batched pass over `rows` samples needs (the
    /// per-sample fallback needs none besides its scratch).
    fn batch_work_size(&self, rows: usize) -> (usize, usize) {
        let _ = rows;
        (0, 0)
    }

    /// Work memory for batched passes of up to `rows` samples.
    fn new_batch_work(&self, rows: usize) -> BatchWork {
        let (f, i) = self.batch_work_size(rows);
        BatchWork::with_capacity(f, i, self.new_scratch())
    }

    /// `y = f(x)` for `rows = x.len() / n_inputs` samples at once (`x` and `y` row-major, one
    /// sample per row), keeping the activations in `work` for [`Trainable::backward_batch`].
    /// Equals [`Model::predict_with`] row by row up to summation order (last bits). The
    /// default runs one sample at a time.
    fn forward_batch(&self, x: &[f64], y: &mut [f64], work: &mut BatchWork) {
        let (n_in, n_out) = (self.n_inputs(), self.n_outputs());
        for (xi, yi) in x.chunks_exact(n_in).zip(y.chunks_exact_mut(n_out)) {
            self.predict_with(xi, yi, &mut work.scratch);
        }
    }

    /// Accumulates `Σ_rows ∂L/∂θ` into `grad` given `dy` (one row of `∂L/∂y` per sample). Must
    /// follow a [`Trainable::forward_batch`] on the same `x` with the same `work`. The default
    /// reruns each sample's forward pass, then its [`Trainable::backward`].
    fn backward_batch(&self, x: &[f64], dy: &[f64], work: &mut BatchWork, grad: &mut [f64]) {
        let (n_in, n_out) = (self.n_inputs(), self.n_outputs());
        let mut y = [0.0; MAX_BATCH_FALLBACK_OUT];
        for (xi, di) in x.chunks_exact(n_in).zip(dy.chunks_exact(n_out)) {
            self.predict_with(xi, &mut y[..n_out], &mut work.scratch);
            self.backward(xi, di, &mut work.scratch, grad);
        }
    }
}

/// Most outputs the per-sample fallback of [`Trainable::backward_batch`] supports.
const MAX_BATCH_FALLBACK_OUT: usize = super::spec::MAX_WIDTH;

/// Asserts the input/output lengths of a pass (cheap; catches wiring errors loudly).
#[inline]
pub(crate) fn check_io(m: &impl Model, x: &[f64], y_len: usize) {
    assert_eq!(x.len(), m.n_inputs(), "{} model: input length", m.kind());
    assert_eq!(y_len, m.n_outputs(), "{} model: output length", m.kind());
}
