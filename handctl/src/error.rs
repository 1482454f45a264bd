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
    /// handd's control socket could not be reached, or answered badly (the io::Error, if any,
    /// is the source).
    #[error(transparent)]
    Control(#[from] driver::control::ControlError),
    /// The configuration that names handd's socket could not be read.
    #[error("cannot find handd's socket: {0}")]
    Config(#[from] driver::config::ConfigError),
    /// The CAN interface is down or missing.
    #[error(transparent)]
    Bus(#[from] driver::transport::TransportError),
    /// A CAN socket could not be opened, set up or read.
    #[error("CAN interface {iface:?}: {what}: {source}")]
    Can {
        /// The interface.
        iface: String,
        /// What was being done.
        what: String,
        /// What the OS said.
        source: std::io::Error,
    },
    /// The command is not in this build of handctl.
    #[cfg_attr(
        feature = "sim",
        allow(dead_code, reason = "only a build without `sim` leaves a command out")
    )]
    #[error("{what} is not in this build of handctl; build it with: {build}")]
    NotBuilt {
        /// The command or option.
        what: &'static str,
        /// The command line that builds it.
        build: &'static str,
    },
    /// The run's model does not load under its config.
    #[error(transparent)]
    Startup(#[from] driver::startup::StartupError),
    /// A tape could not be read or replayed.
    #[error(transparent)]
    Tape(#[from] driver::tape::TapeError),
    /// A replay gave other frames than the tape holds.
    #[error("{0} round(s) of frames differ from the tape (listed above)")]
    ReplayDiffers(u64),
    /// The quality gates found trials to redo.
    #[error("the session failed its quality gates ({0} trial problem(s) above); redo those trials, or pass --ignore-gates")]
    Gates(usize),
    /// The session moves some finger in one direction only; `--ignore-gates` does not override it.
    #[error(
        "the session moves {0} finger(s) in one direction only (above): such a finger would be \
         trained with one anchor and never driven the other way; record the missing direction \
         (--ignore-gates does not override this; --allow-one-direction does, for a research \
         recording that holds one direction only, never for a patient's model)"
    )]
    OneDirection(usize),
    /// A verification could not run.
    #[error("verification: {0}")]
    Verify(#[from] decoder::model::verify::VerifyError),
    /// Effort rays on which a finger goes back against the effort.
    #[error("{0} effort ray(s) reverse beyond the tolerance (listed above)")]
    Reversals(usize),
    /// Effort rays on which a finger goes back, or beyond full scale, only beyond full effort.
    #[error(
        "beyond full effort (efforts up to {k_max}): {reversing} effort ray(s) reverse and \
         {overshooting} overshoot beyond the tolerance (listed above); efforts [0, 1] pass"
    )]
    ReversalsBeyond {
        /// Rays reversing.
        reversing: usize,
        /// Rays overshooting full scale.
        overshooting: usize,
        /// The largest effort checked.
        k_max: f64,
    },
    /// `handctl train` refused to write a model that reverses beyond the tolerance.
    #[error(
        "model NOT written: {verdict}. Retrain (another --seed, more --epochs), recalibrate, \
         or pass --force to write it anyway (the file then records it as FORCED)"
    )]
    Refused {
        /// The verification, naming the worst finger, trial and amount.
        verdict: String,
    },
    /// `handctl deploy`: the model's patient differs from the running model's (or either is
    /// unknown), and there was neither `--yes` nor a terminal to ask on.
    #[error(
        "not deployed: {change}. Check that this is the right patient's model, then pass --yes \
         (stdin is not a terminal, so nothing was asked)"
    )]
    Unconfirmed {
        /// Both patients, in words.
        change: String,
    },
    /// A model could not be put together (e.g. a record that contradicts itself).
    #[error("model: {0}")]
    Model(#[from] decoder::model::ModelError),
    /// The guided calibration stopped.
    #[error("calibrate: {0}")]
    Calibrate(#[from] crate::calibrate::error::CalibrateError),
    /// The command cannot do what was asked with this data.
    #[error("{0}")]
    Usage(String),
}

impl CliError {
    /// Process exit code: 3 for refused quality gates, 4 for a model refused by its
    /// verification, 5 for a deploy to another patient not confirmed, 1 otherwise.
    pub fn exit_code(&self) -> u8 {
        match self {
            CliError::Gates(_) | CliError::OneDirection(_) => 3,
            CliError::Refused { .. } => 4,
            CliError::Unconfirmed { .. } => 5,
            _ => 1,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use driver::control::ControlError;

    #[test]
    fn socket_failures_keep_the_os_error_as_their_source() {
        let e = CliError::from(ControlError::Connect {
            path: "/run/handstack/handctl.sock".into(),
            source: std::io::Error::from(std::io::ErrorKind::ConnectionRefused),
        });
        assert!(matches!(e, CliError::Control(_)), "{e:?}");
        let source = std::error::Error::source(&e).expect("a source");
        let io = source
            .downcast_ref::<std::io::Error>()
            .expect("the io::Error itself");
        assert_eq!(io.kind(), std::io::ErrorKind::ConnectionRefused);
        assert!(e.to_string().contains("handctl.sock"), "{e}");
        assert_eq!(e.exit_code(), 1);
    }
}
