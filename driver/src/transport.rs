//! How the daemon reaches the bus. The control logic ([`crate::engine`]) sees frames and
//! times only; a [`Transport`] delivers received frames with their receive time and sends
//! frames, and reports the bus's health as errors. Backends: the in-memory bus of `hand-model`
//! (with its own per-frame receive times) and SocketCAN ([`crate::socketcan_bus`], kernel
//! receive timestamps).
//!
//! Receive times must be each frame's own: a transport that stamped a whole batch with the
//! time it was read would make the EMG reassembler see 50 ms gaps between batches.

use hand_dbc::CanFrame;
use hand_model::{Clock, MemBusError, MemEndpoint};

/// Why the bus cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum TransportError {
    /// The controller is bus-off.
    #[error("CAN controller is bus-off")]
    BusOff,
    /// The controller is error-passive: its frames may not be seen reliably.
    #[error("CAN controller is error-passive")]
    ErrorPassive,
    /// The interface is down or gone.
    #[error("CAN interface is down: {0}")]
    Down(String),
    /// Any other I/O error.
    #[error("CAN I/O error: {0}")]
    Io(#[from] std::io::Error),
}

/// A received frame and its receive time, µs on the daemon's clock.
pub type Timestamped = (CanFrame, u64);

/// The daemon's view of a CAN bus.
pub trait Transport {
    /// The next received frame, without blocking; `Ok(None)` when none is waiting.
    fn try_recv(&mut self) -> Result<Option<Timestamped>, TransportError>;
    /// Send one frame now.
    fn send(&mut self, frame: &CanFrame) -> Result<(), TransportError>;
    /// Drop every frame queued for sending and not yet on the bus (after bus-off, a stale
    /// setpoint must never reach a motor).
    fn drop_queued(&mut self);
    /// Try to bring the bus back (reopen the socket).
    fn reopen(&mut self) -> Result<(), TransportError>;
}

/// The in-memory bus: receive times come from the bus's clock, or from `clock` if it has none.
pub struct MemTransport<K: Clock> {
    endpoint: MemEndpoint<CanFrame>,
    clock: K,
}

impl<K: Clock> MemTransport<K> {
    /// Wraps an endpoint.
    pub fn new(endpoint: MemEndpoint<CanFrame>, clock: K) -> Self {
        Self { endpoint, clock }
    }
}

impl<K: Clock> Transport for MemTransport<K> {
    fn try_recv(&mut self) -> Result<Option<Timestamped>, TransportError> {
        Ok(self
            .endpoint
            .receive_timestamped()
            .map(|r| (r.frame, r.time_us.unwrap_or_else(|| self.clock.now_us()))))
    }

    fn send(&mut self, frame: &CanFrame) -> Result<(), TransportError> {
        self.endpoint.send(frame).map_err(|e| match e {
            MemBusError::BusOff => TransportError::BusOff,
            other => TransportError::Down(other.to_string()),
        })
    }

    fn drop_queued(&mut self) {
        // The in-memory bus delivers at once: nothing is ever queued for sending.
    }

    fn reopen(&mut self) -> Result<(), TransportError> {
        Ok(())
    }
}
