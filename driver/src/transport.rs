//! How the daemon reaches the bus. The control logic ([`crate::engine`]) sees frames and
//! times only; a [`Transport`] delivers received frames with their receive time and sends
//! frames, and reports the bus's health as errors. Backends: SocketCAN
//! ([`crate::socketcan_bus`], kernel receive timestamps) and, with the `sim` feature, the
//! in-memory bus of `hand-model` (`crate::mem_transport`, its own per-frame receive times).
//!
//! Receive times must be each frame's own: a transport that stamped a whole batch with the
//! time it was read would make the EMG reassembler see 50 ms gaps between batches.

use hand_dbc::CanFrame;

/// Why a transport call failed.
#[derive(Debug, thiserror::Error)]
pub enum TransportError {
    /// The controller is bus-off.
    #[error("CAN controller is bus-off")]
    BusOff,
    /// The interface's transmit queue is full (ENOBUFS): the frame was not queued. On a real
    /// controller this happens whenever the bus is busy or nobody ACKs; it is not a dead bus.
    #[error("CAN transmit queue full: frame not queued")]
    QueueFull,
    /// The interface is down or gone.
    #[error("CAN interface is down: {0}")]
    Down(String),
    /// Any other I/O error.
    #[error("CAN I/O error: {0}")]
    Io(#[from] std::io::Error),
}

/// The CAN controller's error state (ISO 11898-1 fault confinement), as its error frames
/// report it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ControllerState {
    /// Error-active: error counters below 96.
    #[default]
    ErrorActive,
    /// Error warning: a counter at 96 or more.
    Warning,
    /// Error-passive: a counter at 128 or more. The node still sends and receives, but its
    /// frames may go unacknowledged; what happens when the amplifier or the controllers power
    /// up after the board, brown out, or motor EMI hits the bus. Transient: it clears when the
    /// controller is error-active again.
    ErrorPassive,
    /// Bus-off: the controller left the bus (transmit counter above 255).
    BusOff,
}

impl ControllerState {
    /// A stable lower-case name.
    pub fn name(self) -> &'static str {
        match self {
            ControllerState::ErrorActive => "error_active",
            ControllerState::Warning => "warning",
            ControllerState::ErrorPassive => "error_passive",
            ControllerState::BusOff => "bus_off",
        }
    }
}

/// Every class of bus error since start, counted (`handctl status` shows them).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
pub struct BusCounters {
    /// Error frames reporting error warning (a counter at 96).
    pub warning: u64,
    /// Error frames reporting error-passive.
    pub passive: u64,
    /// Bus-off reports.
    pub bus_off: u64,
    /// Controller restarts after bus-off (CAN_ERR_RESTARTED).
    pub restarted: u64,
    /// Transmissions nobody acknowledged (CAN_ERR_ACK).
    pub no_ack: u64,
    /// Receive or transmit overflows in the controller (frames lost in hardware).
    pub controller_overflow: u64,
    /// Protocol violations and bus errors.
    pub protocol: u64,
    /// Other error frames (lost arbitration, transceiver, transmit timeout).
    pub other: u64,
    /// Frames the interface's transmit queue refused (ENOBUFS), counted by the daemon.
    pub tx_queue_full: u64,
    /// Reopen attempts that failed.
    pub reopen_failures: u64,
    /// Steps of the wall clock seen in the receive stamps ([`crate::rx_times`]): followed,
    /// counted, never a fault.
    #[serde(default)]
    pub clock_steps: u64,
    /// Frames the kernel dropped because the receive queue was full (SO_RXQ_OVFL; a tick
    /// that started late or a stalled daemon): lost before handd read them, not on the bus.
    /// 0 from transports without a kernel queue (in memory).
    #[serde(default)]
    pub kernel_drops: u64,
}

/// The bus's health now.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct BusHealth {
    /// The controller's error state.
    pub state: ControllerState,
    /// Every error class, counted.
    pub counters: BusCounters,
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
    /// The controller's error state and error counts (a transport without a controller is
    /// always error-active).
    fn health(&self) -> BusHealth {
        BusHealth::default()
    }
}
