//! The one error type of the session layer.

use std::path::PathBuf;

/// Why a calibration session could not be read, imported or labelled.
#[derive(Debug, thiserror::Error)]
pub enum SessionError {
    /// A file could not be read or written.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// What the OS said.
        source: std::io::Error,
    },
    /// A file could not be replaced atomically.
    #[error(transparent)]
    Write(#[from] crate::fsio::WriteError),
    /// `session.toml` is not valid TOML or does not have the expected fields (the message
    /// carries the line and column).
    #[error("{path}: {message}")]
    Toml {
        /// The file.
        path: PathBuf,
        /// The parser's message, with line and column.
        message: String,
    },
    /// The metadata is well-formed but says something impossible.
    #[error("{path}: {message}")]
    Invalid {
        /// The file the statement comes from.
        path: PathBuf,
        /// What is wrong and where.
        message: String,
    },
    /// The recording itself (samples or frames) is unusable.
    #[error("{path}: {message}")]
    Recording {
        /// The recording file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// The chain configuration in the session is rejected by the signal chain.
    #[error("chain configuration: {0}")]
    Chain(#[from] crate::dsp::ConfigError),
    /// A session spec on the command line could not be understood.
    #[error("{0}")]
    Spec(String),
}

impl SessionError {
    pub(crate) fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        SessionError::Io {
            path: path.into(),
            source,
        }
    }
    pub(crate) fn invalid(path: impl Into<PathBuf>, message: impl Into<String>) -> Self {
        SessionError::Invalid {
            path: path.into(),
            message: message.into(),
        }
    }
    pub(crate) fn recording(path: impl Into<PathBuf>, message: impl Into<String>) -> Self {
        SessionError::Recording {
            path: path.into(),
            message: message.into(),
        }
    }
}
