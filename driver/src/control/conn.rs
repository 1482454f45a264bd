//! One connection: read one request line within a deadline and a size cap (never more than
//! [`MAX_REQUEST_BYTES`] + 1 bytes are read), answer it, or hand the socket to a
//! subscription. Every bad request gets a refusal naming what was wrong.

use std::io::{ErrorKind, Read};
use std::os::unix::net::UnixStream;
use std::time::{Duration, Instant};

use super::access::Peer;
use super::server::{send_reply, Shared};
use super::subscribers;
use crate::protocol::{parse_request_bytes, Reply, Request, MAX_REQUEST_BYTES};

/// How long a client has to send its whole request line.
pub const REQUEST_DEADLINE: Duration = Duration::from_secs(1);
/// How long writing a reply may take before the client is given up.
pub const REPLY_TIMEOUT: Duration = Duration::from_secs(1);

/// Why no request line was read.
enum ReadFailure {
    /// Longer than [`MAX_REQUEST_BYTES`]: refused unread.
    TooLong,
    /// Nothing complete within [`REQUEST_DEADLINE`]; how many bytes had come.
    Timeout(usize),
    /// The client went away or the socket failed.
    Gone,
}

/// Reads one line (without its newline) into `buf`, within `deadline`. A client that closes
/// its side after a request without a newline is answered too.
fn read_line<'a>(
    mut stream: &UnixStream,
    buf: &'a mut [u8; MAX_REQUEST_BYTES + 1],
    deadline: Instant,
) -> Result<&'a [u8], ReadFailure> {
    let mut len = 0;
    loop {
        let left = deadline.saturating_duration_since(Instant::now());
        if left.is_zero() {
            return Err(ReadFailure::Timeout(len));
        }
        stream
            .set_read_timeout(Some(left))
            .map_err(|_| ReadFailure::Gone)?;
        match stream.read(&mut buf[len..]) {
            Ok(0) if len == 0 => return Err(ReadFailure::Gone),
            Ok(0) => return Ok(&buf[..len]),
            Ok(n) => {
                if let Some(nl) = buf[len..len + n].iter().position(|&b| b == b'\n') {
                    return Ok(&buf[..len + nl]);
                }
                len += n;
                if len > MAX_REQUEST_BYTES {
                    return Err(ReadFailure::TooLong);
                }
            }
            Err(e) if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut) => {
                return Err(ReadFailure::Timeout(len))
            }
            Err(e) if e.kind() == ErrorKind::Interrupted => {}
            Err(_) => return Err(ReadFailure::Gone),
        }
    }
}

/// The request on `stream`, or the refusal to send instead (`None`: the client is gone).
fn read_request(stream: &UnixStream) -> Option<Result<Request, String>> {
    let mut buf = [0u8; MAX_REQUEST_BYTES + 1];
    let reason = match read_line(stream, &mut buf, Instant::now() + REQUEST_DEADLINE) {
        Ok(line) => return Some(parse_request_bytes(line)),
        Err(ReadFailure::Gone) => return None,
        Err(ReadFailure::TooLong) => format!(
            "request longer than {MAX_REQUEST_BYTES} bytes: refused without reading the rest"
        ),
        Err(ReadFailure::Timeout(0)) => format!(
            "no request within {} ms: send one JSON line such as {{\"cmd\":\"status\"}}",
            REQUEST_DEADLINE.as_millis()
        ),
        Err(ReadFailure::Timeout(n)) => format!(
            "incomplete request: {n} bytes without a newline within {} ms",
            REQUEST_DEADLINE.as_millis()
        ),
    };
    Some(Err(reason))
}

/// Serves one admitted connection to its end.
pub(super) fn serve_connection(stream: UnixStream, peer: Peer, shared: &Shared) {
    let reply = match read_request(&stream) {
        None => return,
        Some(Err(reason)) => {
            tracing::info!(
                uid = peer.uid,
                pid = peer.pid,
                "control request refused: {reason}"
            );
            Reply::Refused { reason }
        }
        Some(Ok(Request::Subscribe { every_ms })) => {
            return subscribers::serve_subscriber(stream, peer, every_ms, shared.hub.as_deref())
        }
        Some(Ok(req)) => shared.handle(req, peer),
    };
    send_reply(&stream, &reply, REPLY_TIMEOUT);
}
