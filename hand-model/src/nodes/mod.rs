//! The simulated nodes on the bus. Each is stepped with `poll(now_us, &mut bus)`: it reads
//! what arrived, advances its own model to `now_us` and transmits whatever became due, so the
//! same node runs on a virtual clock over a [`crate::bus::MemBus`] in tests and in real time
//! over SocketCAN in `handsim`.

pub mod amp_board;
pub mod amplifier;
pub mod drive;
pub mod epoch;
pub mod injector;
pub mod motor;
pub mod setpoints;

pub use amp_board::AmpBoard;
pub use amplifier::{AmplifierNode, AmplifierNodeConfig};
pub use drive::{DriveFingerConfig, DriveFingerNode};
pub use epoch::EpochGate;
pub use injector::FaultInjector;
pub use motor::FingerNode;
pub use setpoints::{SetpointCorruption, SetpointSource};

use embedded_can::nb::Can;

use crate::dbc::CanFrame;

/// Any transport a node can run on.
pub trait Bus: Can<Frame = CanFrame> {}
impl<T: Can<Frame = CanFrame>> Bus for T {}

/// A node's transmit and receive counts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct NodeStats {
    /// Frames handed to the bus.
    pub tx_frames: u64,
    /// Frames the bus refused because its transmit queue was full (dropped).
    pub tx_would_block: u64,
    /// Frames the bus refused with an error (bus-off, interface down).
    pub tx_errors: u64,
    /// Frames received and looked at.
    pub rx_frames: u64,
}

impl NodeStats {
    /// Transmits `frame`, counting the outcome. Never blocks and never fails: a node on a
    /// broken bus keeps running its model (a real controller does not stop its control loop
    /// because a transmit failed).
    pub fn transmit<B: Bus>(&mut self, bus: &mut B, frame: &CanFrame) {
        match bus.transmit(frame) {
            Ok(_) => self.tx_frames += 1,
            Err(nb::Error::WouldBlock) => self.tx_would_block += 1,
            Err(nb::Error::Other(_)) => self.tx_errors += 1,
        }
    }

    /// The next received frame, or `None` when nothing is waiting (receive errors end the
    /// drain; they are transient on SocketCAN and impossible on the in-memory bus).
    pub fn receive<B: Bus>(&mut self, bus: &mut B) -> Option<CanFrame> {
        match bus.receive() {
            Ok(f) => {
                self.rx_frames += 1;
                Some(f)
            }
            Err(_) => None,
        }
    }
}

/// The 11-bit id of a frame (extended ids map to `u32::MAX`, which no hand.dbc message has).
pub fn std_id(frame: &CanFrame) -> u32 {
    if frame.is_extended() {
        u32::MAX
    } else {
        frame.raw_id()
    }
}
