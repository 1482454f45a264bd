//! The product: the `handd` daemon (the 50 ms control loop, its safety state machine and
//! transports) and the technician CLI `handctl`.

pub mod conditioner;
pub mod config;
pub mod control;
pub mod daemon;
pub mod demo;
pub mod engine;
pub mod protocol;
pub mod rt;
pub mod safety;
pub mod service;
pub mod socketcan_bus;
pub mod startup;
pub mod stats;
pub mod transport;
pub mod tuning;
pub mod units;

pub use conditioner::{FingerConditioner, FingerGains, Setpoint};
pub use config::{Config, ConfigError};
pub use safety::{DaemonState, Fault, FaultSet, Safety, SafetyTiming, Transition};
