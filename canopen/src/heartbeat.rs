//! Heartbeat: handd's own producer (driven by the loop's `now`) and the consumer that tracks
//! each drive's heartbeat against its timeout.

use crate::frame::CanFrame;
use crate::ids::NodeId;
use crate::nmt::{ErrorControl, NmtState};

/// Produces the heartbeat of `node` once per period of the caller's clock.
#[derive(Clone, Debug)]
pub struct HeartbeatProducer {
    node: NodeId,
    period_us: u64,
    next_us: Option<u64>,
}

impl HeartbeatProducer {
    /// A producer for `node` (handd's own id) every `period_us`.
    pub fn new(node: NodeId, period_us: u64) -> Self {
        Self {
            node,
            period_us,
            next_us: None,
        }
    }

    /// The heartbeat frame reporting `state`.
    pub fn frame(&self, state: NmtState) -> CanFrame {
        ErrorControl {
            node: self.node,
            state,
        }
        .frame()
    }

    /// The heartbeat if one is due at `now` (the first call always sends; late calls send one).
    pub fn poll(&mut self, now_us: u64, state: NmtState) -> Option<CanFrame> {
        match self.next_us {
            Some(next) if now_us < next => None,
            _ => {
                self.next_us = Some(now_us.saturating_add(self.period_us));
                Some(self.frame(state))
            }
        }
    }
}

/// What the consumer knows of one node.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HeartbeatStatus {
    /// No heartbeat yet (CiA 301: monitoring starts with the first one).
    Unseen,
    /// Heard within the timeout, in this NMT state.
    Alive(NmtState),
    /// The timeout passed since the last heartbeat.
    Lost,
}

/// What a received error-control frame meant to the consumer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HeartbeatEvent {
    /// A boot-up message: the node (re)started.
    BootUp(NodeId),
    /// A heartbeat with a state other than the last one seen.
    StateChanged(NodeId, NmtState),
}

#[derive(Clone, Copy, Debug)]
struct Watch {
    node: NodeId,
    timeout_us: u64,
    last_us: Option<u64>,
    state: Option<NmtState>,
    lost: bool,
}

/// Tracks the heartbeat of every watched node.
#[derive(Clone, Debug, Default)]
pub struct HeartbeatConsumer {
    watches: Vec<Watch>,
}

impl HeartbeatConsumer {
    /// An empty consumer.
    pub fn new() -> Self {
        Self::default()
    }

    /// Watches `node` with `timeout_us` (replacing an earlier watch of it).
    pub fn watch(&mut self, node: NodeId, timeout_us: u64) {
        self.watches.retain(|w| w.node != node);
        self.watches.push(Watch {
            node,
            timeout_us,
            last_us: None,
            state: None,
            lost: false,
        });
    }

    /// Offers a frame; frames that are not error control of a watched node are ignored.
    pub fn on_frame(&mut self, f: &CanFrame, now_us: u64) -> Option<HeartbeatEvent> {
        let ec = ErrorControl::decode(f).ok()?;
        let w = self.watches.iter_mut().find(|w| w.node == ec.node)?;
        w.last_us = Some(now_us);
        w.lost = false;
        let changed = w.state != Some(ec.state);
        w.state = Some(ec.state);
        if ec.is_boot_up() {
            Some(HeartbeatEvent::BootUp(ec.node))
        } else {
            changed.then_some(HeartbeatEvent::StateChanged(ec.node, ec.state))
        }
    }

    /// Checks every watch at `now`; `lost` is called once for each node that just timed out.
    pub fn poll(&mut self, now_us: u64, mut lost: impl FnMut(NodeId)) {
        for w in &mut self.watches {
            if let Some(last) = w.last_us {
                if !w.lost && now_us.saturating_sub(last) > w.timeout_us {
                    w.lost = true;
                    lost(w.node);
                }
            }
        }
    }

    /// The status of `node` (as of the last [`HeartbeatConsumer::poll`]); `None` if unwatched.
    pub fn status(&self, node: NodeId) -> Option<HeartbeatStatus> {
        let w = self.watches.iter().find(|w| w.node == node)?;
        Some(match (w.lost, w.state) {
            (true, _) => HeartbeatStatus::Lost,
            (false, None) => HeartbeatStatus::Unseen,
            (false, Some(s)) => HeartbeatStatus::Alive(s),
        })
    }
}
