//! The technicians' control socket: a Unix socket (mode 0660, group configurable) on which
//! `handctl` sends one [`Request`](crate::protocol::Request) per connection and reads one
//! [`Reply`](crate::protocol::Reply), or subscribes to the live stream.
//!
//! Hostile or broken clients cannot hold anyone up: every connection's peer credentials
//! (SO_PEERCRED) are checked before anything is read (`access`); at most [`MAX_CONNECTIONS`]
//! are served at once, each on its own thread with a read deadline and a size cap (`server`,
//! `conn`); requests are answered one at a time by the daemon's handler, which talks to the
//! loop through a bounded channel; live subscribers get bounded queues and are dropped when
//! slow (`subscribers`). The tick never waits on any of it.

mod access;
mod client;
mod conn;
mod error;
mod server;
mod subscribers;

pub use access::{group_id, peer_of, AccessPolicy, Peer};
pub use client::{request, subscribe, Subscription};
pub use conn::{REPLY_TIMEOUT, REQUEST_DEADLINE};
pub use error::ControlError;
pub use server::{ControlServer, MAX_CONNECTIONS, THREAD_STACK_BYTES};
pub use subscribers::{
    LiveFeed, LiveModel, SharedLiveModel, LIVE_QUEUE, LIVE_SEND_BUFFER, LIVE_WRITE_TIMEOUT,
    MAX_SUBSCRIBERS,
};

#[cfg(test)]
mod tests {
    use std::fs;
    use std::io::{BufRead, BufReader, Write};
    use std::os::unix::fs::PermissionsExt;
    use std::os::unix::net::UnixStream;

    use super::*;
    use crate::protocol::{Reply, Request};

    #[test]
    fn request_and_reply_over_a_real_socket() {
        let dir = std::env::temp_dir().join(format!("handd-ctl-{}", std::process::id()));
        let path = dir.join("ctl.sock");
        let server = ControlServer::bind(&path, None).unwrap();
        let mode = fs::metadata(&path).unwrap().permissions().mode() & 0o777;
        assert_eq!(mode, 0o660);
        assert!(
            matches!(
                ControlServer::bind(&path, None),
                Err(ControlError::Setup { .. })
            ),
            "a live socket is not stolen"
        );
        std::thread::spawn(move || {
            server.serve(|req, peer| Reply::Ok {
                message: format!("{req:?} from uid {}", peer.uid),
                status: None,
            })
        });
        let reply = request(
            &path,
            &Request::Arm {
                force_rest_mismatch: false,
            },
        )
        .unwrap();
        let Reply::Ok { message, .. } = reply else {
            panic!("refused: {reply:?}")
        };
        assert!(
            message.starts_with("Arm { force_rest_mismatch: false } from uid"),
            "{message}"
        );
        // A malformed line is refused with a reason.
        let mut s = UnixStream::connect(&path).unwrap();
        s.write_all(b"{\"cmd\":\"fly\"}\n").unwrap();
        let mut answer = String::new();
        BufReader::new(&s).read_line(&mut answer).unwrap();
        assert!(
            answer.contains("refused") && answer.contains("fly"),
            "{answer}"
        );
        fs::remove_dir_all(&dir).unwrap();
    }
}
