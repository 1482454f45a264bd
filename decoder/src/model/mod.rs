//! Models that map a feature vector to five finger labels, their training, and model files.
//!
//! - Architectures ([`ResDd`], LN and MLP as [`DenseNet`], [`Cnn`]; [`AnyModel`] picks one at
//!   run time) share the [`Model`] trait (allocation-free inference with a caller-owned
//!   [`Scratch`]) and the [`Trainable`] trait (flat parameters and an analytic gradient).
//! - [`Normalizer`]: per-feature scale, no centring, so zero input stays zero.
//! - [`Dataset`] + [`train`](fn@train): masked MSE plus the effort-ray penalty
//!   ([`EffortPenalty`]), Adam or SGD, early stopping on held-out windows (by default the end of
//!   every trial), deterministic for a given seed.
//! - [`RestStage`]: a soft dead zone per finger fitted from the calibration's rest windows, so a
//!   relaxed hand stays still (monotonic, keeps ±1 at ±1).
//! - [`Taught`]: the directions the calibration taught per finger; an untaught one is held at 0
//!   ([`OutputStage`]: the rest stage then that hold, shared by predictor and verifier).
//! - [`Provenance`]: which patient, which session, when, and any quality gates bypassed.
//! - [`TrainedModel`]: what a model file holds ([`TrainedModel::save`] / [`TrainedModel::load`]);
//!   [`Predictor`] runs it in the daemon's tick.
//!
//! Numbers are `f64` throughout; matrices are row-major plain slices: one flat parameter vector
//! per model keeps optimizers and the file format uniform and makes it easy to guarantee that
//! inference never allocates. Inference runs one sample at a time ([`Model`]);
//! training runs each mini-batch as matrix products ([`Trainable::forward_batch`],
//! [`BatchWork`]; nalgebra's `gemm`, see `gemm.rs`).

mod any;
mod batch;
mod cnn;
mod cnn_batch;
mod cone;
mod config;
mod dataset;
mod dense;
mod dense_batch;
mod effort;
mod effort_batch;
mod envelope;
mod error;
mod file;
mod gemm;
mod init;
mod kind;
mod linalg;
#[cfg(target_arch = "x86_64")]
mod matvec_x86;
mod normalizer;
mod optim;
mod output;
pub mod provenance;
mod resdd;
mod resdd_batch;
mod rest;
mod spec;
mod split;
mod summary;
mod taught;
mod train;
mod trained;
mod traits;
pub mod verify;

pub use any::AnyModel;
pub use batch::BatchWork;
pub use cnn::Cnn;
pub use cone::{PatternCone, CONE_LEAST, CONE_MARGIN, MAX_PATTERNS};
pub use config::{Optimizer, TrainConfig, ValidationSplit};
pub use dataset::{Dataset, N_FINGERS};
pub use dense::DenseNet;
pub use effort::{ray_directions, ray_penalty, EffortPenalty, RayWork, MAX_EFFORT_POINTS};
pub use envelope::{Envelope, ALONE_MARGIN, PLAUSIBLE_FLOOR, PLAUSIBLE_SPREAD};
pub use error::{FileError, ModelError, TrainError};
pub use file::{FORMAT_VERSION, HEADER_LEN, MAGIC, NORMALIZER_TENSOR};
pub use kind::ModelKind;
pub use normalizer::Normalizer;
pub use output::{hand_label, OutputStage};
pub use provenance::Provenance;
pub use resdd::{ResDd, ResDdActivations, RESDD_INPUT_GAIN};
pub use rest::{RestFit, RestStage, MAX_REST_WIDTH, REST_SHARPNESS};
pub use spec::{
    CnnSpec, LnSpec, MlpSpec, ModelSpec, ResDdSpec, ResDdVariant, MAX_MODULES, MAX_WIDTH,
};
pub use summary::TrainingSummary;
pub use taught::Taught;
pub use train::{train, EpochReport};
pub use trained::{Predictor, TrainedModel};
pub use traits::{Model, Scratch, TensorInfo, Trainable};
