//! The one error type of the evaluation layer.

/// Why a metric, table or plot could not be computed.
#[derive(Debug, thiserror::Error)]
pub enum EvalError {
    /// Two inputs that must pair up element by element have different lengths.
    #[error("{what}: {left} values against {right}")]
    LengthMismatch {
        /// Which computation was asked for.
        what: &'static str,
        /// Length of the first input.
        left: usize,
        /// Length of the second input.
        right: usize,
    },
    /// A metric needs data that is not there (no windows, one class only, constant input).
    #[error("{0}")]
    NotEnoughData(String),
    /// An input value is NaN or infinite.
    #[error("{what}: value {index} is not finite")]
    NonFinite {
        /// Which computation was asked for.
        what: &'static str,
        /// Index of the first bad value.
        index: usize,
    },
    /// A model's output or a feature row does not have the expected width.
    #[error("{0}")]
    Shape(String),
    /// Writing a table or curve file failed.
    #[error("{path}: {source}")]
    Write {
        /// The file being written.
        path: String,
        /// What the OS said.
        source: std::io::Error,
    },
    /// Writing a plot failed.
    #[error("plot {path}: {message}")]
    Plot {
        /// The file being written.
        path: String,
        /// What the plotting backend said.
        message: String,
    },
}

pub(crate) fn check_pair(what: &'static str, a: &[f64], b: &[f64]) -> Result<(), EvalError> {
    if a.len() != b.len() {
        return Err(EvalError::LengthMismatch {
            what,
            left: a.len(),
            right: b.len(),
        });
    }
    check_finite(what, a)?;
    check_finite(what, b)
}

pub(crate) fn check_finite(what: &'static str, a: &[f64]) -> Result<(), EvalError> {
    match a.iter().position(|v| !v.is_finite()) {
        Some(index) => Err(EvalError::NonFinite { what, index }),
        None => Ok(()),
    }
}
