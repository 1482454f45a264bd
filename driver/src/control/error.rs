//! The control socket's one error type.

use std::path::PathBuf;

/// Errors of the control socket.
#[derive(Debug, thiserror::Error)]
pub enum ControlError {
    /// The socket could not be set up.
    #[error("control socket {path}: {what}: {source}")]
    Setup {
        /// The socket's path.
        path: PathBuf,
        /// The step that failed.
        what: &'static str,
        /// The cause.
        #[source]
        source: std::io::Error,
    },
    /// The configured group does not exist.
    #[error("control socket group {0:?} does not exist (in /etc/group)")]
    NoSuchGroup(String),
    /// Talking to the daemon failed (from `handctl`).
    #[error(
        "cannot talk to handd at {path}: {source} (is handd running, and are you in its group?)"
    )]
    Connect {
        /// The socket's path.
        path: PathBuf,
        /// The cause.
        #[source]
        source: std::io::Error,
    },
    /// The daemon's answer was not understood.
    #[error("handd sent a reply that is not understood: {0}")]
    BadReply(String),
    /// The daemon refused the request (a subscription; other requests return the refusal as
    /// a [`crate::protocol::Reply`]).
    #[error("handd refused: {0}")]
    Refused(String),
}
