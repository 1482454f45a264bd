//! The client side (what `handctl` does): one request and its reply, or a subscription's
//! stream of [`Live`] lines.

use std::io::{BufRead, BufReader, Write};
use std::os::unix::net::UnixStream;
use std::path::Path;
use std::time::Duration;

use super::ControlError;
use crate::live::Live;
use crate::protocol::{Reply, Request};

/// How long `handctl` waits for a reply.
const REPLY_WAIT: Duration = Duration::from_secs(5);

fn connect(path: &Path, req: &Request) -> Result<UnixStream, ControlError> {
    let err = |source| ControlError::Connect {
        path: path.to_owned(),
        source,
    };
    let mut stream = UnixStream::connect(path).map_err(err)?;
    stream.set_read_timeout(Some(REPLY_WAIT)).map_err(err)?;
    let mut line = serde_json::to_string(req).map_err(|e| ControlError::BadReply(e.to_string()))?;
    line.push('\n');
    if let Err(e) = stream.write_all(line.as_bytes()) {
        // The daemon may have refused the connection (not in the group, too many open) and
        // closed it before the request went out: its reason is still there to read.
        if e.kind() != std::io::ErrorKind::BrokenPipe {
            return Err(err(e));
        }
    }
    Ok(stream)
}

fn read_reply(path: &Path, reader: &mut impl BufRead) -> Result<Reply, ControlError> {
    let mut answer = String::new();
    reader
        .read_line(&mut answer)
        .map_err(|source| ControlError::Connect {
            path: path.to_owned(),
            source,
        })?;
    serde_json::from_str(answer.trim())
        .map_err(|e| ControlError::BadReply(format!("{e}: {answer:?}")))
}

/// Send one request to the daemon at `path` and wait for its reply (what `handctl` does).
pub fn request(path: &Path, req: &Request) -> Result<Reply, ControlError> {
    let stream = connect(path, req)?;
    read_reply(path, &mut BufReader::new(&stream))
}

/// A live subscription: an iterator over the daemon's [`Live`] lines. It ends when the daemon
/// closes the connection (or drops the subscriber); a line that does not parse, or none within
/// a few periods, is an `Err` item.
#[derive(Debug)]
pub struct Subscription {
    reader: BufReader<UnixStream>,
    line: String,
    /// The daemon's acknowledgement ("subscribed: one line every 100 ms").
    pub message: String,
}

/// Subscribe at `path` to one [`Live`] line every `every_ms` (the daemon's default when
/// `None`). A refusal (period out of range, too many subscribers, not in the group) is
/// [`ControlError::Refused`] with the daemon's reason.
pub fn subscribe(path: &Path, every_ms: Option<u64>) -> Result<Subscription, ControlError> {
    let stream = connect(path, &Request::Subscribe { every_ms })?;
    let mut reader = BufReader::new(stream);
    let message = match read_reply(path, &mut reader)? {
        Reply::Ok { message, .. } => message,
        Reply::Refused { reason } => return Err(ControlError::Refused(reason)),
    };
    let period = Duration::from_millis(every_ms.unwrap_or(crate::protocol::DEFAULT_SUBSCRIBE_MS));
    let wait = REPLY_WAIT.max(period * 3);
    reader
        .get_ref()
        .set_read_timeout(Some(wait))
        .map_err(|source| ControlError::Connect {
            path: path.to_owned(),
            source,
        })?;
    Ok(Subscription {
        reader,
        line: String::new(),
        message,
    })
}

impl Iterator for Subscription {
    type Item = Result<Live, ControlError>;

    fn next(&mut self) -> Option<Self::Item> {
        self.line.clear();
        match self.reader.read_line(&mut self.line) {
            Ok(0) => None,
            Ok(_) => Some(
                serde_json::from_str(self.line.trim())
                    .map_err(|e| ControlError::BadReply(format!("{e}: {:?}", self.line))),
            ),
            Err(e) => Some(Err(ControlError::BadReply(format!(
                "no live line from handd: {e}"
            )))),
        }
    }
}
