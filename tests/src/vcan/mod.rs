//! The vcan suite's helpers: separate processes (handd, handsim, handctl) on a real SocketCAN
//! interface, watched by a monitor socket with kernel receive timestamps.

pub mod analysis;
pub mod env;
pub mod monitor;
pub mod procs;
pub mod replay;
pub mod stall;
pub mod stream_breaks;

pub use analysis::{
    first_safe_stop_after, scenario_start_us, setpoints_of, statuses_of, SetpointRecord,
    StatusRecord,
};
pub use env::VcanEnv;
pub use monitor::{Monitor, Seen};
pub use procs::{Proc, TestConfig};
