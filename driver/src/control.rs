//! The technicians' control socket: a Unix socket (mode 0660, group configurable) on which
//! `handctl` sends one [`Request`] per connection and reads one [`Reply`].
//!
//! Every connection's peer credentials (SO_PEERCRED) are checked: root, the daemon's own user
//! and members of the configured group may connect; anyone else is refused and logged. The
//! server thread never touches the control loop's state directly: it hands each request to a
//! handler (the daemon passes a closure that talks to the loop through a channel).

use std::fs;
use std::io::{BufRead, BufReader, Read, Write};
use std::os::unix::fs::PermissionsExt;
use std::os::unix::net::{UnixListener, UnixStream};
use std::path::{Path, PathBuf};
use std::time::Duration;

use crate::protocol::{parse_request, Reply, Request, MAX_REQUEST_BYTES};

/// Who is on the other end of a connection.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Peer {
    /// Effective user id.
    pub uid: u32,
    /// Effective group id.
    pub gid: u32,
    /// Process id.
    pub pid: i32,
}

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
}

/// Who may connect.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct AccessPolicy {
    /// The daemon's user id.
    pub daemon_uid: u32,
    /// The allowed group's id, if any.
    pub group_gid: Option<u32>,
}

impl AccessPolicy {
    /// Whether `peer` may use the socket; `supplementary` lists the peer's extra groups.
    pub fn allows(&self, peer: &Peer, supplementary: &[u32]) -> bool {
        peer.uid == 0
            || peer.uid == self.daemon_uid
            || self
                .group_gid
                .is_some_and(|g| peer.gid == g || supplementary.contains(&g))
    }
}

/// The id of group `name`, from `/etc/group`.
pub fn group_id(name: &str) -> Result<u32, ControlError> {
    let text = fs::read_to_string("/etc/group").unwrap_or_default();
    text.lines()
        .filter_map(|l| {
            let mut it = l.split(':');
            let n = it.next()?;
            let _pw = it.next()?;
            let gid = it.next()?.parse::<u32>().ok()?;
            (n == name).then_some(gid)
        })
        .next()
        .ok_or_else(|| ControlError::NoSuchGroup(name.to_owned()))
}

/// The supplementary groups of process `pid`, from `/proc/PID/status` (empty if unknown).
fn supplementary_groups(pid: i32) -> Vec<u32> {
    fs::read_to_string(format!("/proc/{pid}/status"))
        .ok()
        .and_then(|s| {
            s.lines().find_map(|l| l.strip_prefix("Groups:")).map(|g| {
                g.split_whitespace()
                    .filter_map(|x| x.parse().ok())
                    .collect()
            })
        })
        .unwrap_or_default()
}

/// The peer's credentials of a connected stream.
pub fn peer_of(stream: &UnixStream) -> std::io::Result<Peer> {
    let c = rustix::net::sockopt::socket_peercred(stream)?;
    Ok(Peer {
        uid: c.uid.as_raw(),
        gid: c.gid.as_raw(),
        pid: c.pid.as_raw_nonzero().get(),
    })
}

/// The bound control socket.
#[derive(Debug)]
pub struct ControlServer {
    listener: UnixListener,
    path: PathBuf,
    policy: AccessPolicy,
}

impl ControlServer {
    /// Bind the socket at `path` (creating its directory), give it mode 0660 and, if a group is
    /// named, that group. A stale socket left by a killed daemon is replaced; a live one (another
    /// daemon answering) is an error.
    pub fn bind(path: &Path, group: Option<&str>) -> Result<Self, ControlError> {
        let setup = |what, source| ControlError::Setup {
            path: path.to_owned(),
            what,
            source,
        };
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            fs::create_dir_all(dir).map_err(|e| setup("creating its directory", e))?;
        }
        if path.exists() {
            if UnixStream::connect(path).is_ok() {
                return Err(setup(
                    "another daemon is answering on it",
                    std::io::Error::from(std::io::ErrorKind::AddrInUse),
                ));
            }
            fs::remove_file(path).map_err(|e| setup("removing a stale socket", e))?;
        }
        let group_gid = group.map(group_id).transpose()?;
        let listener = UnixListener::bind(path).map_err(|e| setup("bind", e))?;
        fs::set_permissions(path, fs::Permissions::from_mode(0o660))
            .map_err(|e| setup("chmod 0660", e))?;
        if let Some(gid) = group_gid {
            std::os::unix::fs::chown(path, None, Some(gid)).map_err(|e| setup("chgrp", e))?;
        }
        Ok(Self {
            listener,
            path: path.to_owned(),
            policy: AccessPolicy {
                daemon_uid: rustix::process::geteuid().as_raw(),
                group_gid,
            },
        })
    }

    /// The socket's path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Serve connections until the listener fails; each request goes to `handle` with the
    /// peer that sent it. Runs on its own thread: it blocks.
    pub fn serve(self, mut handle: impl FnMut(Request, Peer) -> Reply) {
        for conn in self.listener.incoming() {
            let Ok(stream) = conn else { continue };
            if let Err(e) = self.one(stream, &mut handle) {
                tracing::warn!(error = %e, "control connection failed");
            }
        }
    }

    fn one(
        &self,
        mut stream: UnixStream,
        handle: &mut impl FnMut(Request, Peer) -> Reply,
    ) -> std::io::Result<()> {
        stream.set_read_timeout(Some(Duration::from_secs(2)))?;
        stream.set_write_timeout(Some(Duration::from_secs(2)))?;
        let peer = peer_of(&stream)?;
        let reply = if !self.policy.allows(&peer, &supplementary_groups(peer.pid)) {
            tracing::warn!(
                uid = peer.uid,
                gid = peer.gid,
                pid = peer.pid,
                "control request refused: not in the allowed group"
            );
            Reply::Refused {
                reason: "permission denied: you are not in handd's control group".into(),
            }
        } else {
            let mut line = String::new();
            let mut reader = BufReader::new((&stream).take(MAX_REQUEST_BYTES as u64 + 1));
            reader.read_line(&mut line)?;
            match parse_request(&line) {
                Ok(req) => handle(req, peer),
                Err(reason) => Reply::Refused { reason },
            }
        };
        let mut out = serde_json::to_string(&reply).map_err(std::io::Error::other)?;
        out.push('\n');
        stream.write_all(out.as_bytes())
    }
}

/// Send one request to the daemon at `path` and wait for its reply (what `handctl` does).
pub fn request(path: &Path, req: &Request) -> Result<Reply, ControlError> {
    let connect = |source| ControlError::Connect {
        path: path.to_owned(),
        source,
    };
    let mut stream = UnixStream::connect(path).map_err(connect)?;
    stream
        .set_read_timeout(Some(Duration::from_secs(5)))
        .map_err(connect)?;
    let mut line = serde_json::to_string(req).map_err(|e| ControlError::BadReply(e.to_string()))?;
    line.push('\n');
    stream.write_all(line.as_bytes()).map_err(connect)?;
    let mut answer = String::new();
    BufReader::new(&stream)
        .read_line(&mut answer)
        .map_err(connect)?;
    serde_json::from_str(answer.trim())
        .map_err(|e| ControlError::BadReply(format!("{e}: {answer:?}")))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn policy_allows_root_owner_and_group_members_only() {
        let p = AccessPolicy {
            daemon_uid: 1000,
            group_gid: Some(50),
        };
        let peer = |uid, gid| Peer { uid, gid, pid: 1 };
        assert!(p.allows(&peer(0, 0), &[]));
        assert!(p.allows(&peer(1000, 1000), &[]));
        assert!(p.allows(&peer(1001, 50), &[]));
        assert!(p.allows(&peer(1001, 1001), &[7, 50]));
        assert!(!p.allows(&peer(1001, 1001), &[7]));
        let no_group = AccessPolicy {
            group_gid: None,
            ..p
        };
        assert!(!no_group.allows(&peer(1001, 50), &[50]));
    }

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
        let reply = request(&path, &Request::Arm).unwrap();
        let Reply::Ok { message, .. } = reply else {
            panic!("refused: {reply:?}")
        };
        assert!(message.starts_with("Arm from uid"), "{message}");
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

    #[test]
    fn unknown_group_is_an_error() {
        assert!(matches!(
            group_id("no-such-group-handstack"),
            Err(ControlError::NoSuchGroup(_))
        ));
        assert_eq!(group_id("root").unwrap(), 0);
    }
}
