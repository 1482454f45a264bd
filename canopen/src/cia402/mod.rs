//! CiA 402 power state machine: statusword decoding, controlword commands, the transition
//! table as data, and the master's walk to Operation enabled.

pub mod controlword;
pub mod driver;
pub mod state;
pub mod transitions;

pub use controlword::{Command, Controlword};
pub use driver::{Cia402Error, DriverStep, PowerDriver};
pub use state::{PowerState, Statusword, STATE_TABLE};
pub use transitions::{transition_for, Transition, TRANSITIONS};

/// Object indices of the CiA 402 objects this crate uses.
pub mod objects {
    use crate::ids::Index;
    /// Abort connection option code (INTEGER16).
    pub const ABORT_CONNECTION: Index = 0x6007;
    /// Controlword (UNSIGNED16).
    pub const CONTROLWORD: Index = 0x6040;
    /// Statusword (UNSIGNED16).
    pub const STATUSWORD: Index = 0x6041;
    /// Quick stop option code (INTEGER16).
    pub const QUICK_STOP_OPTION: Index = 0x605A;
    /// Modes of operation (INTEGER8).
    pub const MODES_OF_OPERATION: Index = 0x6060;
    /// Modes of operation display (INTEGER8).
    pub const MODES_DISPLAY: Index = 0x6061;
    /// Position actual value (INTEGER32, increments).
    pub const POSITION_ACTUAL: Index = 0x6064;
    /// Velocity actual value (INTEGER32).
    pub const VELOCITY_ACTUAL: Index = 0x606C;
    /// Target torque (INTEGER16, per mille of rated torque).
    pub const TARGET_TORQUE: Index = 0x6071;
    /// Max torque (UNSIGNED16, per mille of rated torque).
    pub const MAX_TORQUE: Index = 0x6072;
    /// Rated torque (UNSIGNED32, mNm).
    pub const RATED_TORQUE: Index = 0x6076;
    /// Torque actual value (INTEGER16, per mille of rated torque).
    pub const TORQUE_ACTUAL: Index = 0x6077;
    /// Target velocity (INTEGER32).
    pub const TARGET_VELOCITY: Index = 0x60FF;
    /// Interpolation time period (record: 1 value UNSIGNED8, 2 index INTEGER8).
    pub const INTERPOLATION_PERIOD: Index = 0x60C2;
    /// Supported drive modes (UNSIGNED32 bit field).
    pub const SUPPORTED_MODES: Index = 0x6502;
}

/// A mode of operation (0x6060) this subset uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Mode {
    /// 3: profile velocity.
    ProfileVelocity,
    /// 9: cyclic synchronous velocity.
    CyclicSyncVelocity,
    /// 10: cyclic synchronous torque.
    CyclicSyncTorque,
}

impl Mode {
    /// The 0x6060 value.
    pub fn value(self) -> i8 {
        match self {
            Self::ProfileVelocity => 3,
            Self::CyclicSyncVelocity => 9,
            Self::CyclicSyncTorque => 10,
        }
    }

    /// The mode's bit in 0x6502 (supported drive modes).
    pub fn supported_bit(self) -> u32 {
        1 << (self.value() - 1)
    }

    /// The target object the RPDO carries in this mode.
    pub fn target(self) -> crate::ids::Index {
        match self {
            Self::CyclicSyncTorque => objects::TARGET_TORQUE,
            Self::ProfileVelocity | Self::CyclicSyncVelocity => objects::TARGET_VELOCITY,
        }
    }
}
