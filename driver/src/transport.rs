//! How the daemon reaches the bus. The control logic ([`crate::engine`]) sees frames and
//! times only; a [`Transport`] delivers received frames with their receive time and sends
//! frames, and reports the bus's health as errors. Backends: SocketCAN
//! ([`crate::socketcan_bus`], kernel receive timestamps) and, with the `sim` feature, the
//! in-memory bus of `hand-model` (`crate::mem_transport`, its own per-frame receive times).
//!
//! Receive times must be each frame's own: a transport that stamped a whole batch with the
//! time it was read would make the EMG reassembler see 50 ms gaps between batches.

use hand_dbc::CanFrame;

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
    /// After a bus failure: drop what this transport can of the frames queued for sending and
    /// not yet on the bus (a stale setpoint should never reach a motor). What can be dropped
    /// depends on the transport: SocketCAN cannot purge the kernel's and the controller's
    /// queues (see its implementation); the setpoint epoch makes what is left harmless.
    fn drop_queued(&mut self);
    /// Try to bring the bus back (reopen the socket).
    fn reopen(&mut self) -> Result<(), TransportError>;
}
