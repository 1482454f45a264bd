//! The product: the `handd` daemon (the 50 ms control loop, its safety state machine and
//! transports, the control socket). The technician's CLI `handctl` is its own crate
//! (`handctl/`), a client of this one.
//!
//! Features (none by default, which is the daemon's build): `sim` adds the demo and the
//! in-memory transport on the simulator (`hand-model`). `handd` neither needs nor links it.

pub mod bus_load;
pub mod can_recv;
pub mod conditioner;
pub mod config;
pub mod control;
pub mod daemon;
#[cfg(feature = "sim")]
pub mod demo;
pub mod deploy;
pub mod drive_config;
pub mod engine;
pub mod live;
#[cfg(feature = "sim")]
pub mod mem_transport;
pub mod model_service;
pub mod persist;
pub mod planned_load;
pub mod protocol;
pub mod rest_check;
pub mod rt;
pub mod rx_times;
pub mod safety;
pub mod service;
pub mod socketcan_bus;
pub mod startup;
pub mod stats;
pub mod tape;
pub mod transport;
pub mod tuning;
pub mod units;

pub use conditioner::{FingerConditioner, FingerGains, Setpoint};
pub use config::{Config, ConfigError};
pub use safety::{DaemonState, Fault, FaultSet, Safety, SafetyTiming, Transition};
