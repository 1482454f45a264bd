//! Why a drive is not driven. Every fault latches: the drive gets the quick stop with its
//! target zeroed each tick until `arm` starts it from scratch.

use crate::cia402::{Cia402Error, PowerState};
use crate::emcy::Emcy;
use crate::startup::StartupError;
use thiserror::Error;

/// A drive's latched fault.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Error)]
pub enum DriveFault {
    /// Its start-up failed (the step and the cause inside).
    #[error(transparent)]
    Startup(#[from] StartupError),
    /// It sent an EMCY error (not an error reset).
    #[error("EMCY: {0}")]
    Emcy(Emcy),
    /// Its heartbeat stopped for longer than the consumer's timeout.
    #[error("heartbeat lost (none for {timeout_us} us)")]
    HeartbeatLost {
        /// The consumer's timeout.
        timeout_us: u64,
    },
    /// No TPDO1 for longer than the limit (three SYNC periods).
    #[error("no TPDO1 feedback for {age_us} us (limit {limit_us} us)")]
    FeedbackStale {
        /// Since the last TPDO1 (or since the drive was started).
        age_us: u64,
        /// The limit.
        limit_us: u64,
    },
    /// It left Operation enabled without handd asking (its statusword in TPDO1).
    #[error("left Operation enabled by itself: now {0}")]
    LeftOperation(PowerState),
    /// The walk back to Operation enabled (controlword by RPDO1) failed.
    #[error("re-enable: {0}")]
    Enable(#[from] Cia402Error),
    /// Its statusword reports Fault.
    #[error("statusword reports Fault")]
    DriveFault,
    /// It sent a boot-up message while configured (a power cycle or a reset): its
    /// configuration is gone.
    #[error("booted while configured (power cycle or reset); reconfigured on arm")]
    Rebooted,
    /// The bus recovered from bus-off: its NMT and CiA 402 state are unknown.
    #[error("bus-off recovery: state unknown, read again and reconfigured on arm")]
    BusRecovered,
    /// Not started yet: the bank starts a drive only on `arm` or at start.
    #[error("not started")]
    NotStarted,
}
