//! The simulated world on the bus: an sEMG amplifier node, finger motor-controller nodes and a
//! simulated patient, so that the daemon can be calibrated, run and broken without a person or
//! a prosthesis.

pub mod bus;
pub mod clock;
pub mod dbc;
pub mod emg;
pub mod error;
pub mod faults;
pub mod finger;
pub mod nodes;
pub mod patient;
pub mod scenario;
pub mod socketcan_bus;
pub mod world;

pub use bus::{MemBus, MemBusError, MemEndpoint, Received};
pub use clock::{Clock, SystemClock, VirtualClock};
pub use error::SimError;
