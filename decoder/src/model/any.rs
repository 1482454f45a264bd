//! `AnyModel`: one of the four architectures, chosen at run time (from a CLI flag or a file).

use super::batch::BatchWork;
use super::cnn::Cnn;
use super::dense::DenseNet;
use super::error::ModelError;
use super::init::SeededRng;
use super::kind::ModelKind;
use super::resdd::ResDd;
use super::spec::ModelSpec;
use super::traits::{Model, Scratch, TensorInfo, Trainable};

/// A model of any kind; dispatches [`Model`] and [`Trainable`] to the concrete architecture.
#[derive(Debug, Clone, PartialEq)]
pub enum AnyModel {
    /// ResDD.
    ResDd(ResDd),
    /// LN or MLP.
    Dense(DenseNet),
    /// CNN.
    Cnn(Cnn),
}

impl AnyModel {
    /// A freshly initialised model of `kind` with `spec`'s block for that kind (see each
    /// architecture's docs for its initialisation).
    pub fn random(
        kind: ModelKind,
        spec: &ModelSpec,
        n_in: usize,
        n_out: usize,
        seed: u64,
    ) -> Result<Self, ModelError> {
        Self::init(kind, spec, n_in, n_out, &mut SeededRng::new(seed))
    }

    pub(crate) fn init(
        kind: ModelKind,
        spec: &ModelSpec,
        n_in: usize,
        n_out: usize,
        rng: &mut SeededRng,
    ) -> Result<Self, ModelError> {
        Ok(match kind {
            ModelKind::ResDd => AnyModel::ResDd(ResDd::init(spec.resdd, n_in, n_out, rng)?),
            ModelKind::Ln => {
                AnyModel::Dense(DenseNet::init(kind, n_in, spec.ln.hidden, n_out, rng)?)
            }
            ModelKind::Mlp => {
                AnyModel::Dense(DenseNet::init(kind, n_in, spec.mlp.hidden, n_out, rng)?)
            }
            ModelKind::Cnn => AnyModel::Cnn(Cnn::init(spec.cnn, n_in, n_out, rng)?),
        })
    }

    /// A model of `kind` from a flat parameter vector (checked for length and finiteness).
    pub fn from_params(
        kind: ModelKind,
        spec: &ModelSpec,
        n_in: usize,
        n_out: usize,
        params: Vec<f64>,
    ) -> Result<Self, ModelError> {
        Ok(match kind {
            ModelKind::ResDd => {
                AnyModel::ResDd(ResDd::from_params(spec.resdd, n_in, n_out, params)?)
            }
            ModelKind::Ln => {
                AnyModel::Dense(DenseNet::ln_from_params(spec.ln, n_in, n_out, params)?)
            }
            ModelKind::Mlp => {
                AnyModel::Dense(DenseNet::mlp_from_params(spec.mlp, n_in, n_out, params)?)
            }
            ModelKind::Cnn => AnyModel::Cnn(Cnn::from_params(spec.cnn, n_in, n_out, params)?),
        })
    }

    /// The tensors a model of this kind and shape must have (used to check model files).
    pub fn expected_tensors(
        kind: ModelKind,
        spec: &ModelSpec,
        n_in: usize,
        n_out: usize,
    ) -> Result<Vec<TensorInfo>, ModelError> {
        // Computed from the shapes alone: a corrupt file claiming huge widths costs nothing here.
        match kind {
            ModelKind::ResDd => ResDd::layout(&spec.resdd, n_in, n_out),
            ModelKind::Ln => DenseNet::layout(kind, n_in, spec.ln.hidden, n_out),
            ModelKind::Mlp => DenseNet::layout(kind, n_in, spec.mlp.hidden, n_out),
            ModelKind::Cnn => Cnn::layout(&spec.cnn, n_in, n_out),
        }
    }

    fn inner(&self) -> &dyn Trainable {
        match self {
            AnyModel::ResDd(m) => m,
            AnyModel::Dense(m) => m,
            AnyModel::Cnn(m) => m,
        }
    }
}

impl Model for AnyModel {
    fn kind(&self) -> ModelKind {
        self.inner().kind()
    }
    fn n_inputs(&self) -> usize {
        self.inner().n_inputs()
    }
    fn n_outputs(&self) -> usize {
        self.inner().n_outputs()
    }
    fn scratch_size(&self) -> (usize, usize) {
        self.inner().scratch_size()
    }
    fn predict_with(&self, x: &[f64], y: &mut [f64], scratch: &mut Scratch) {
        match self {
            AnyModel::ResDd(m) => m.predict_with(x, y, scratch),
            AnyModel::Dense(m) => m.predict_with(x, y, scratch),
            AnyModel::Cnn(m) => m.predict_with(x, y, scratch),
        }
    }
}

impl Trainable for AnyModel {
    fn params(&self) -> &[f64] {
        self.inner().params()
    }
    fn params_mut(&mut self) -> &mut [f64] {
        match self {
            AnyModel::ResDd(m) => m.params_mut(),
            AnyModel::Dense(m) => m.params_mut(),
            AnyModel::Cnn(m) => m.params_mut(),
        }
    }
    fn tensors(&self) -> Vec<TensorInfo> {
        self.inner().tensors()
    }
    fn backward(&self, x: &[f64], dy: &[f64], scratch: &mut Scratch, grad: &mut [f64]) {
        match self {
            AnyModel::ResDd(m) => m.backward(x, dy, scratch, grad),
            AnyModel::Dense(m) => m.backward(x, dy, scratch, grad),
            AnyModel::Cnn(m) => m.backward(x, dy, scratch, grad),
        }
    }
    fn batch_work_size(&self, rows: usize) -> (usize, usize) {
        self.inner().batch_work_size(rows)
    }
    fn forward_batch(&self, x: &[f64], y: &mut [f64], work: &mut BatchWork) {
        match self {
            AnyModel::ResDd(m) => m.forward_batch(x, y, work),
            AnyModel::Dense(m) => m.forward_batch(x, y, work),
            AnyModel::Cnn(m) => m.forward_batch(x, y, work),
        }
    }
    fn backward_batch(&self, x: &[f64], dy: &[f64], work: &mut BatchWork, grad: &mut [f64]) {
        match self {
            AnyModel::ResDd(m) => m.backward_batch(x, dy, work, grad),
            AnyModel::Dense(m) => m.backward_batch(x, dy, work, grad),
            AnyModel::Cnn(m) => m.backward_batch(x, dy, work, grad),
        }
    }
}
