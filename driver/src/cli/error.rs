//! The CLI's error type: every lower layer's error, said plainly.

/// Why a command failed.
#[derive(Debug, thiserror::Error)]
pub enum CliError {
    /// The session could not be read.
    #[error(transparent)]
    Session(#[from] decoder::session::SessionError),
    /// Training failed.
    #[error("training: {0}")]
    Train(#[from] decoder::model::TrainError),
    /// The model file could not be written or read.
    #[error("model file: {0}")]
    File(#[from] decoder::model::FileError),
    /// Scoring or plotting failed.
    #[error("evaluation: {0}")]
    Eval(#[from] decoder::eval::EvalError),
    /// A file or directory could not be created.
    #[error("{path}: {source}")]
    Io {
        /// The path.
        path: String,
        /// What the OS said.
        source: std::io::Error,
    },
    /// The quality gates found trials to redo.
    #[error("the session failed its quality gates ({0} trial problem(s) above); redo those trials, or pass --ignore-gates")]
    Gates(usize),
    /// The command cannot do what was asked with this data.
    #[error("{0}")]
    Usage(String),
}

impl CliError {
    /// Process exit code: 3 for refused quality gates, 1 otherwise.
    pub fn exit_code(&self) -> u8 {
        match self {
            CliError::Gates(_) => 3,
            _ => 1,
        }
    }
}
