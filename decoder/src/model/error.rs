//! Errors of the model layer: building a model, training it, and reading or writing model files.

use std::path::PathBuf;

use thiserror::Error;

/// A model, normalizer or dataset could not be built because an argument is invalid.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum ModelError {
    /// A model kind name that is not one of "resdd", "ln", "mlp", "cnn".
    #[error("unknown model kind {0:?}: expected one of resdd, ln, mlp, cnn")]
    UnknownKind(String),
    /// A hyper-parameter is out of its allowed range.
    #[error("invalid model specification: {0}")]
    InvalidSpec(String),
    /// A vector or matrix has the wrong length.
    #[error("shape mismatch for {what}: expected {expected}, found {found}")]
    Shape {
        /// What was being checked (e.g. "parameter vector", "normalizer scales").
        what: String,
        /// The expected length.
        expected: usize,
        /// The length that was given.
        found: usize,
    },
    /// A value that must be finite is NaN or infinite.
    #[error("non-finite value in {what} at index {index}")]
    NonFinite {
        /// Which array holds the value.
        what: String,
        /// Its flat index.
        index: usize,
    },
    /// The training set is empty, so no normalizer can be fitted.
    #[error("cannot fit a normalizer on zero rows")]
    EmptyFit,
}

/// Checks a flat parameter vector of `model` (e.g. "ResDD"): its length and that every value is
/// finite. Shared by every architecture's `from_params`.
pub(crate) fn check_params(model: &str, expected: usize, params: &[f64]) -> Result<(), ModelError> {
    if params.len() != expected {
        return Err(ModelError::Shape {
            what: format!("{model} parameter vector"),
            expected,
            found: params.len(),
        });
    }
    if let Some(index) = params.iter().position(|p| !p.is_finite()) {
        return Err(ModelError::NonFinite {
            what: format!("{model} parameters"),
            index,
        });
    }
    Ok(())
}

/// Training could not start or did not converge.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum TrainError {
    /// The dataset has no windows.
    #[error("the dataset is empty")]
    EmptyDataset,
    /// Every target of every window is masked out: there is nothing to fit.
    #[error("every target in the dataset is masked out: nothing to fit")]
    AllMasked,
    /// A feature value is NaN or infinite.
    #[error("non-finite feature in window {row}, feature {col}")]
    NonFiniteFeature {
        /// Window index.
        row: usize,
        /// Feature index.
        col: usize,
    },
    /// An unmasked target is NaN or infinite.
    #[error("non-finite target in window {row}, finger {finger}")]
    NonFiniteTarget {
        /// Window index.
        row: usize,
        /// Finger index (0 thumb .. 4 pinky).
        finger: usize,
    },
    /// A window has the wrong number of features.
    #[error("window has {found} features, the dataset expects {expected}")]
    FeatureCount {
        /// Features per window of the dataset.
        expected: usize,
        /// Features in the offending window.
        found: usize,
    },
    /// A training setting is out of range.
    #[error("invalid training configuration: {0}")]
    Config(String),
    /// The held-out split cannot be made (e.g. too few trials).
    #[error("cannot make the validation split: {0}")]
    Split(String),
    /// The loss became NaN or infinite.
    #[error("training diverged at epoch {epoch} (loss is not finite): lower the learning rate")]
    Diverged {
        /// The epoch (1-based) where the loss stopped being finite.
        epoch: usize,
    },
    /// The model could not be built.
    #[error(transparent)]
    Model(#[from] ModelError),
}

impl From<crate::fsio::WriteError> for FileError {
    fn from(e: crate::fsio::WriteError) -> Self {
        FileError::Io {
            op: e.op,
            path: e.path,
            source: e.source,
        }
    }
}

/// A model file could not be written or read, or it does not fit the running configuration.
#[derive(Debug, Error)]
pub enum FileError {
    /// The operating system refused a file operation.
    #[error("{op} {path}: {source}")]
    Io {
        /// What was being done ("create", "write", "rename", ...).
        op: &'static str,
        /// The file concerned.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// The file does not start with the model file magic bytes.
    #[error("not a handstack model file (bad magic bytes)")]
    NotAModelFile,
    /// The file has a format version this build does not read.
    #[error("unsupported model file version {found} (this build reads versions 1 to {supported})")]
    UnknownVersion {
        /// Version in the file.
        found: u32,
        /// Version this build reads and writes.
        supported: u32,
    },
    /// The file marks as required a metadata section this build does not know: it would run
    /// the model without part of what decides its outputs.
    #[error(
        "the model file requires {sections:?}, which this build does not know; use a handd and \
         handctl as new as the handctl train that wrote it"
    )]
    UnknownRequired {
        /// The unknown required sections.
        sections: Vec<String>,
    },
    /// The file is shorter or longer than its header says.
    #[error("model file length is wrong: header says {expected} body bytes, found {found}")]
    Length {
        /// Body length from the header.
        expected: u64,
        /// Body bytes actually present.
        found: u64,
    },
    /// The body's CRC-32 does not match the header: the file is corrupt.
    #[error(
        "model file checksum mismatch: header {stored:08x}, body {computed:08x} (file corrupt)"
    )]
    BadChecksum {
        /// CRC-32 stored in the header.
        stored: u32,
        /// CRC-32 computed over the body.
        computed: u32,
    },
    /// The metadata cannot be parsed or is inconsistent.
    #[error("malformed model file: {0}")]
    Malformed(String),
    /// A tensor's shape differs from what the model kind and specification require.
    #[error("wrong shape for {tensor}: expected {expected:?}, file has {found:?}")]
    WrongShape {
        /// Tensor name (e.g. "w_in", "normalizer.scale").
        tensor: String,
        /// Shape required by the specification.
        expected: Vec<usize>,
        /// Shape stored in the file.
        found: Vec<usize>,
    },
    /// A weight is NaN or infinite.
    #[error("non-finite weight in {tensor} at flat index {index}")]
    NonFiniteWeight {
        /// Tensor name.
        tensor: String,
        /// Flat index inside the tensor.
        index: usize,
    },
    /// The feature and filter configuration in the file differs from the one in use.
    #[error("model was trained with a different signal chain configuration (differs in: {})", fields.join(", "))]
    ChainMismatch {
        /// Top-level configuration fields that differ.
        fields: Vec<String>,
    },
    /// The model inside the file is invalid.
    #[error(transparent)]
    Model(#[from] ModelError),
}
