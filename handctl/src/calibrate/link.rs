//! The calibrating hold: before the first cue, a running `handd` is asked to hold the hand
//! (`{"cmd":"calibrating"}` on its control socket), so that the patient's calibration
//! contractions do not move it; it stays held until a model is deployed and `handctl arm`
//! follows. Behind a small trait ([`DaemonLink`]) so that the rest of the calibration does not
//! depend on how the request travels.

use std::path::PathBuf;

use driver::control::{request, ControlError};
use driver::protocol::{Reply, Request};

/// What handd said to the calibrating request.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum HoldOutcome {
    /// No daemon listens on the socket: nothing drives the hand (say so, and go on).
    NoDaemon(PathBuf),
    /// handd holds the hand; its message.
    Held(String),
}

/// The daemon side of calibrating.
pub trait DaemonLink {
    /// Asks the daemon to hold the hand while calibrating. A refusal or a bad answer is an
    /// error (the hand might move); no daemon at all is [`HoldOutcome::NoDaemon`].
    fn calibrating(&mut self) -> Result<HoldOutcome, String>;
}

/// handd's control socket.
#[derive(Debug, Clone)]
pub struct SocketLink {
    /// The socket's path.
    pub path: PathBuf,
}

impl DaemonLink for SocketLink {
    fn calibrating(&mut self) -> Result<HoldOutcome, String> {
        if !self.path.exists() {
            return Ok(HoldOutcome::NoDaemon(self.path.clone()));
        }
        match request(&self.path, &Request::Calibrating) {
            Ok(reply) => read_reply(reply),
            Err(ControlError::Connect { source, .. })
                if source.kind() == std::io::ErrorKind::ConnectionRefused =>
            {
                Ok(HoldOutcome::NoDaemon(self.path.clone()))
            }
            Err(e) => Err(e.to_string()),
        }
    }
}

/// What handd's reply means for the calibration.
fn read_reply(reply: Reply) -> Result<HoldOutcome, String> {
    match reply {
        Reply::Ok { message, .. } => Ok(HoldOutcome::Held(message)),
        Reply::Refused { reason } => Err(format!(
            "handd refused to hold the hand for calibration: {reason} (a handd without the \
             calibrating request is older than this handctl: update it, or stop it with \
             `handctl stop` before calibrating)"
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn replies_are_read_as_handd_means_them() {
        let ok = Reply::Ok {
            message: "held".into(),
            status: None,
        };
        assert_eq!(read_reply(ok), Ok(HoldOutcome::Held("held".into())));
        let no = Reply::Refused {
            reason: "unknown cmd".into(),
        };
        assert!(read_reply(no).expect_err("refused").contains("unknown cmd"));
        let mut gone = SocketLink {
            path: "/nonexistent/handd.sock".into(),
        };
        assert!(matches!(gone.calibrating(), Ok(HoldOutcome::NoDaemon(_))));
    }
}
