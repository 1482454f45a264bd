//! The calibrating hold: before the first cue, a running `handd` is asked to hold the hand
//! (`{"cmd":"calibrating"}` on its control socket), so that the patient's calibration
//! contractions do not move it; it stays held until a model is deployed and `handctl arm`
//! follows. Behind a small trait ([`DaemonLink`]) so that the rest of the calibration does not
//! depend on how the request travels.

use std::io::{BufRead, BufReader, Write};
use std::os::unix::net::UnixStream;
use std::path::{Path, PathBuf};
use std::time::Duration;

use driver::protocol::Reply;

/// How long to wait for handd's reply.
const REPLY_WAIT: Duration = Duration::from_secs(5);

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
        let reply = match ask(&self.path, r#"{"cmd":"calibrating"}"#) {
            Ok(r) => r,
            Err(e) if e.kind() == std::io::ErrorKind::ConnectionRefused => {
                return Ok(HoldOutcome::NoDaemon(self.path.clone()))
            }
            Err(e) => return Err(format!("{}: {e}", self.path.display())),
        };
        parse_reply(&reply)
    }
}

/// One request line and the reply line.
fn ask(path: &Path, line: &str) -> std::io::Result<String> {
    let mut s = UnixStream::connect(path)?;
    s.set_read_timeout(Some(REPLY_WAIT))?;
    s.write_all(line.as_bytes())?;
    s.write_all(b"\n")?;
    let mut reply = String::new();
    BufReader::new(&s).read_line(&mut reply)?;
    Ok(reply)
}

/// handd's reply, as `driver::protocol::Reply`.
fn parse_reply(reply: &str) -> Result<HoldOutcome, String> {
    match serde_json::from_str::<Reply>(reply.trim()) {
        Ok(Reply::Ok { message, .. }) => Ok(HoldOutcome::Held(message)),
        Ok(Reply::Refused { reason }) => Err(format!(
            "handd refused to hold the hand for calibration: {reason} (a handd without the \
             calibrating request is older than this handctl: update it, or stop it with \
             `handctl stop` before calibrating)"
        )),
        Err(e) => Err(format!("handd answered {reply:?}: {e}")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn replies_are_read_as_the_daemon_writes_them() {
        let ok = serde_json::to_string(&Reply::Ok {
            message: "held".into(),
            status: None,
        })
        .expect("json");
        assert_eq!(parse_reply(&ok), Ok(HoldOutcome::Held("held".into())));
        let no = serde_json::to_string(&Reply::Refused {
            reason: "unknown cmd".into(),
        })
        .expect("json");
        assert!(parse_reply(&no)
            .expect_err("refused")
            .contains("unknown cmd"));
        let mut gone = SocketLink {
            path: "/nonexistent/handd.sock".into(),
        };
        assert!(matches!(gone.calibrating(), Ok(HoldOutcome::NoDaemon(_))));
    }
}
