//! The bound socket and its accept loop: credentials first, then a cap on open connections,
//! then one short-lived thread per connection ([`super::conn`]), so a silent or hostile client
//! never delays another technician, and nothing here touches the control loop.

use std::fs;
use std::io::Write;
use std::os::unix::fs::PermissionsExt;
use std::os::unix::net::{UnixListener, UnixStream};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use super::access::{group_id, peer_of, AccessPolicy, Peer};
use super::subscribers::{Hub, LiveFeed};
use super::{conn, ControlError};
use crate::protocol::{Reply, Request};

/// Most connections served at once (subscriptions included); one more is refused at once
/// with a reason.
pub const MAX_CONNECTIONS: usize = 128;

/// Stack of every control thread: a connection's (which parses the request, runs the handler,
/// deploy included, and writes the JSON reply), the accept loop's and the live publisher's.
/// handd locks all its memory, so each thread's whole stack is resident: at Rust's default of
/// 2 MiB, two service threads alone would hold 4 MiB.
pub const THREAD_STACK_BYTES: usize = 256 * 1024;

/// How the server answers a request other than `subscribe`.
pub(super) type Handler = Box<dyn FnMut(Request, Peer) -> Reply + Send>;

/// What the connection threads share.
pub(super) struct Shared {
    pub(super) handler: Mutex<Handler>,
    pub(super) hub: Option<Arc<Hub>>,
    open: AtomicUsize,
}

impl Shared {
    /// Answers one request; the handler is held only while it runs, never while reading.
    pub(super) fn handle(&self, req: Request, peer: Peer) -> Reply {
        let mut h = self.handler.lock().unwrap_or_else(|e| e.into_inner());
        h(req, peer)
    }
}

/// Frees a connection slot when its thread ends (or is never started).
struct Slot(Arc<Shared>);

impl Drop for Slot {
    fn drop(&mut self) {
        self.0.open.fetch_sub(1, Ordering::AcqRel);
    }
}

/// The bound control socket.
#[derive(Debug)]
pub struct ControlServer {
    listener: UnixListener,
    path: PathBuf,
    policy: AccessPolicy,
    live: Option<LiveFeed>,
}

/// Writes one reply line with a short timeout, ignoring a client that went away.
pub(super) fn send_reply(mut stream: &UnixStream, reply: &Reply, timeout: Duration) {
    let Ok(mut out) = serde_json::to_string(reply) else {
        return;
    };
    out.push('\n');
    let _ = stream.set_write_timeout(Some(timeout));
    if let Err(e) = stream.write_all(out.as_bytes()) {
        tracing::debug!(error = %e, "control reply not delivered");
    }
}

fn refuse(stream: &UnixStream, reason: String) {
    send_reply(
        stream,
        &Reply::Refused { reason },
        Duration::from_millis(50),
    );
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
            live: None,
        })
    }

    /// Serve live subscriptions from `feed` (without one, `subscribe` is refused).
    pub fn with_live(mut self, feed: LiveFeed) -> Self {
        self.live = Some(feed);
        self
    }

    /// The socket's path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Serve connections until the listener fails; each request but `subscribe` goes to
    /// `handle` with the peer that sent it (one at a time). Runs on its own thread: it blocks.
    pub fn serve(self, handle: impl FnMut(Request, Peer) -> Reply + Send + 'static) {
        let hub = self.live.map(|feed| Arc::new(Hub::new(feed)));
        if let Some(hub) = &hub {
            let hub = Arc::clone(hub);
            let started = std::thread::Builder::new()
                .name("handd-live".into())
                .stack_size(THREAD_STACK_BYTES)
                .spawn(move || hub.publish_forever());
            if let Err(e) = started {
                tracing::error!(error = %e, "live publisher thread not started");
            }
        }
        let shared = Arc::new(Shared {
            handler: Mutex::new(Box::new(handle)),
            hub,
            open: AtomicUsize::new(0),
        });
        for conn in self.listener.incoming() {
            match conn {
                Ok(stream) => admit(stream, &self.policy, &shared),
                Err(e) => {
                    // Out of descriptors, most likely: let connections close before retrying.
                    tracing::warn!(error = %e, "control socket accept failed");
                    std::thread::sleep(Duration::from_millis(20));
                }
            }
        }
    }
}

/// Credentials first, then the connection cap, then a thread for the connection.
fn admit(stream: UnixStream, policy: &AccessPolicy, shared: &Arc<Shared>) {
    let Ok(peer) = peer_of(&stream) else {
        return;
    };
    if !policy.admits(&peer) {
        tracing::warn!(
            uid = peer.uid,
            gid = peer.gid,
            pid = peer.pid,
            "control request refused: not in the allowed group"
        );
        return refuse(
            &stream,
            "permission denied: you are not in handd's control group".into(),
        );
    }
    if shared.open.fetch_add(1, Ordering::AcqRel) >= MAX_CONNECTIONS {
        shared.open.fetch_sub(1, Ordering::AcqRel);
        tracing::warn!(
            uid = peer.uid,
            pid = peer.pid,
            "control connection refused: {MAX_CONNECTIONS} already open"
        );
        return refuse(
            &stream,
            format!("busy: {MAX_CONNECTIONS} control connections are open; try again"),
        );
    }
    let slot = Slot(Arc::clone(shared));
    let refusal = stream.try_clone().ok();
    let started = std::thread::Builder::new()
        .name("handd-ctl-conn".into())
        .stack_size(THREAD_STACK_BYTES)
        .spawn(move || {
            conn::serve_connection(stream, peer, &slot.0);
            drop(slot);
        });
    if let Err(e) = started {
        tracing::warn!(error = %e, "control connection thread not started");
        if let Some(s) = refusal {
            refuse(
                &s,
                "busy: handd could not start a thread for this connection".into(),
            );
        }
    }
}
