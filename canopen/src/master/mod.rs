//! Every finger drive at once, after start-up: the cyclic exchange of a tick (RPDO1 per
//! drive, then one SYNC and handd's heartbeat), feedback from TPDO1 with its age, the faults
//! that disable a drive until `arm`, and the walk back to Operation enabled by controlword.
//!
//! - [`cyclic`]: RPDO1 and TPDO1 as fixed layouts (no allocation), [`Target`], [`Feedback`].
//! - [`fault`]: [`DriveFault`], why a drive is not driven.
//! - [`bank`]: [`DriveBank`], the drives' phases and the per-tick frames.

pub mod bank;
pub mod cyclic;
pub mod fault;

pub use bank::{BankError, BankSettings, DriveBank, DriveStatus};
pub use cyclic::{Feedback, Setpoint, Target, TorqueLimit};
pub use fault::DriveFault;
