//! Live subscriptions: a publisher thread reads the loop's snapshot once per tick, turns it
//! into one JSON [`Live`] line when a subscriber is due, and hands the line to each due
//! subscriber's bounded queue without waiting. Each subscriber's connection thread writes its
//! queue to the socket with a short timeout. A subscriber whose queue is full or whose socket
//! does not take a line in time is dropped with a log line; the tick never sees any of it (it
//! only `try_lock`s the snapshot).

use std::io::Write;
use std::os::unix::net::UnixStream;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc::{sync_channel, Receiver, SyncSender, TrySendError};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use super::access::Peer;
use super::conn::REPLY_TIMEOUT;
use super::server::send_reply;
use crate::daemon::SharedSnapshot;
use crate::live::{Live, ModelInfo};
use crate::protocol::{subscribe_ticks, Reply};

/// Most subscriptions at once; one more is refused with a reason.
pub const MAX_SUBSCRIBERS: usize = 32;
/// Lines waiting for one subscriber's socket; a full queue drops the subscriber.
pub const LIVE_QUEUE: usize = 4;
/// How long one line may take to enter a subscriber's socket before it is dropped.
pub const LIVE_WRITE_TIMEOUT: Duration = Duration::from_millis(250);
/// Send buffer asked for a subscriber's socket: a few lines, so one that stops reading is
/// found within about a second rather than after the kernel's default (hundreds of lines).
pub const LIVE_SEND_BUFFER: usize = 16 * 1024;

/// Which model runs, as the live lines tell it.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LiveModel {
    /// The model's id, path and kind.
    pub info: ModelInfo,
    /// The model's calibration rest level per channel, µV, when its file carries it.
    pub rest_rms_uv: Option<Vec<f64>>,
}

/// The running model's [`LiveModel`], shared by the live feed and the control handler, which
/// replaces it on every deploy and rollback.
pub type SharedLiveModel = Arc<Mutex<LiveModel>>;

/// Where the live lines come from.
#[derive(Clone)]
pub struct LiveFeed {
    /// The loop's snapshot.
    pub snapshot: SharedSnapshot,
    /// The model that runs (the control handler updates it: give it the same handle).
    pub model: SharedLiveModel,
    /// The loop's tick, µs.
    pub tick_us: u64,
}

impl std::fmt::Debug for LiveFeed {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("LiveFeed")
            .field(
                "model",
                &*self.model.lock().unwrap_or_else(|e| e.into_inner()),
            )
            .field("tick_us", &self.tick_us)
            .finish()
    }
}

struct Subscriber {
    id: u64,
    peer: Peer,
    every_ticks: u64,
    /// The tick from which the next line is due.
    due: u64,
    queue: SyncSender<Arc<str>>,
}

/// The subscribers and the feed they read.
pub(super) struct Hub {
    feed: LiveFeed,
    subs: Mutex<Vec<Subscriber>>,
    next_id: AtomicU64,
}

impl Hub {
    pub(super) fn new(feed: LiveFeed) -> Self {
        Self {
            feed,
            subs: Mutex::new(Vec::with_capacity(MAX_SUBSCRIBERS)),
            next_id: AtomicU64::new(0),
        }
    }

    fn tick_ms(&self) -> u64 {
        (self.feed.tick_us / 1000).max(1)
    }

    /// Adds a subscriber (its first line comes at the next tick), or says why not.
    fn register(&self, peer: Peer, every_ticks: u64) -> Result<(u64, Receiver<Arc<str>>), String> {
        let mut subs = self.subs.lock().unwrap_or_else(|e| e.into_inner());
        if subs.len() >= MAX_SUBSCRIBERS {
            return Err(format!(
                "busy: {MAX_SUBSCRIBERS} subscriptions are open; close one and try again"
            ));
        }
        let (queue, rx) = sync_channel(LIVE_QUEUE);
        let id = self.next_id.fetch_add(1, Ordering::Relaxed);
        subs.push(Subscriber {
            id,
            peer,
            every_ticks,
            due: 0,
            queue,
        });
        Ok((id, rx))
    }

    fn remove(&self, id: u64) {
        let mut subs = self.subs.lock().unwrap_or_else(|e| e.into_inner());
        subs.retain(|s| s.id != id);
    }

    /// Polls the snapshot twice per tick, forever, and publishes each new tick.
    pub(super) fn publish_forever(&self) {
        let mut last_tick = u64::MAX;
        let poll = Duration::from_micros((self.feed.tick_us / 2).max(1000));
        loop {
            let snap = *self.feed.snapshot.lock().unwrap_or_else(|e| e.into_inner());
            if snap.counters.ticks != last_tick {
                last_tick = snap.counters.ticks;
                self.publish(&snap);
            }
            std::thread::sleep(poll);
        }
    }

    /// Sends the line of `snap` to every subscriber due at its tick; never waits.
    fn publish(&self, snap: &crate::daemon::Snapshot) {
        let tick = snap.counters.ticks;
        let mut line: Option<Arc<str>> = None;
        let mut subs = self.subs.lock().unwrap_or_else(|e| e.into_inner());
        subs.retain_mut(|s| {
            if tick < s.due {
                return true;
            }
            s.due = tick + s.every_ticks;
            let line = line.get_or_insert_with(|| {
                let model = self.feed.model.lock().unwrap_or_else(|e| e.into_inner());
                let live = Live::from_snapshot(snap, &model.info, model.rest_rms_uv.as_deref());
                let mut text = serde_json::to_string(&live).unwrap_or_default();
                text.push('\n');
                Arc::from(text)
            });
            match s.queue.try_send(Arc::clone(line)) {
                Ok(()) => true,
                Err(TrySendError::Full(_)) => {
                    tracing::warn!(
                        uid = s.peer.uid,
                        pid = s.peer.pid,
                        "live subscriber dropped: its {LIVE_QUEUE} queued lines are unread"
                    );
                    false
                }
                Err(TrySendError::Disconnected(_)) => false,
            }
        });
    }
}

/// Answers a `subscribe` request, then writes the subscriber's lines until it closes, is too
/// slow, or is dropped.
pub(super) fn serve_subscriber(
    stream: UnixStream,
    peer: Peer,
    every_ms: Option<u64>,
    hub: Option<&Hub>,
) {
    let Some(hub) = hub else {
        let reason = "this control socket serves no live subscription".into();
        return send_reply(&stream, &Reply::Refused { reason }, REPLY_TIMEOUT);
    };
    let registered = subscribe_ticks(every_ms, hub.tick_ms())
        .and_then(|every| Ok((every, hub.register(peer, every)?)));
    let (every, (id, lines)) = match registered {
        Ok(r) => r,
        Err(reason) => {
            tracing::info!(
                uid = peer.uid,
                pid = peer.pid,
                "subscription refused: {reason}"
            );
            return send_reply(&stream, &Reply::Refused { reason }, REPLY_TIMEOUT);
        }
    };
    let period_ms = every * hub.tick_ms();
    tracing::info!(
        uid = peer.uid,
        pid = peer.pid,
        period_ms,
        "live subscriber added"
    );
    let message = format!("subscribed: one line every {period_ms} ms");
    send_reply(
        &stream,
        &Reply::Ok {
            message,
            status: None,
        },
        REPLY_TIMEOUT,
    );
    let _ = rustix::net::sockopt::set_socket_send_buffer_size(&stream, LIVE_SEND_BUFFER);
    let _ = stream.set_write_timeout(Some(LIVE_WRITE_TIMEOUT));
    write_lines(&stream, &peer, &lines);
    hub.remove(id);
    let _ = stream.shutdown(std::net::Shutdown::Both);
}

/// Writes queued lines until the queue ends (the publisher dropped the subscriber) or a write
/// fails.
fn write_lines(mut stream: &UnixStream, peer: &Peer, lines: &Receiver<Arc<str>>) {
    for line in lines {
        match stream.write_all(line.as_bytes()) {
            Ok(()) => {}
            Err(e)
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                ) =>
            {
                tracing::warn!(
                    uid = peer.uid,
                    pid = peer.pid,
                    "live subscriber dropped: a line did not fit its socket within {} ms",
                    LIVE_WRITE_TIMEOUT.as_millis()
                );
                return;
            }
            Err(e) => {
                tracing::info!(uid = peer.uid, pid = peer.pid, error = %e, "live subscriber left");
                return;
            }
        }
    }
}
