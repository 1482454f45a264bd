//! What can go wrong in a calibration, said plainly.

use std::path::Path;

use super::protocol::ProtocolError;

/// Why a calibration stopped.
#[derive(Debug, thiserror::Error)]
pub enum CalibrateError {
    /// The protocol file is bad.
    #[error("protocol: {0}")]
    Protocol(#[from] ProtocolError),
    /// A file could not be written or read.
    #[error("{path}: {source}")]
    Io {
        /// The path.
        path: String,
        /// What the OS said.
        source: std::io::Error,
    },
    /// The session could not be written or read back.
    #[error(transparent)]
    Session(#[from] decoder::session::SessionError),
    /// The session's chain settings are invalid.
    #[error("chain settings: {0}")]
    Chain(#[from] decoder::dsp::ConfigError),
    /// The bus failed.
    #[error("CAN bus: {0}")]
    Bus(String),
    /// Ctrl-C: the finished trials and the log are on disk.
    #[error(
        "interrupted: {kept} trial(s) kept in {dir}; `handctl calibrate --resume --out {dir}` \
         continues with trial {next}"
    )]
    Interrupted {
        /// The output directory.
        dir: String,
        /// Trials kept.
        kept: usize,
        /// The next trial (1-based, as the session numbers them).
        next: usize,
    },
    /// A trial failed its check on every attempt.
    #[error("{trial} failed its check {attempts} times (last: {reason}); fix the cause (electrodes, instructions) and run `handctl calibrate --resume`")]
    TrialFailed {
        /// The trial.
        trial: String,
        /// Attempts made.
        attempts: u32,
        /// The last attempt's reasons.
        reason: String,
    },
    /// `--resume` cannot continue what is in the directory.
    #[error("--resume: {0}")]
    Resume(String),
}

impl CalibrateError {
    /// An I/O error on `path`, for `map_err`.
    pub fn io(path: &Path) -> impl FnOnce(std::io::Error) -> CalibrateError + '_ {
        move |source| CalibrateError::Io {
            path: path.display().to_string(),
            source,
        }
    }
}
