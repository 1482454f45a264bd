//! The statusword (0x6041) and the power states it encodes (CiA 402 table 30).

/// The statusword.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Statusword(pub u16);

/// A CiA 402 power state.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum PowerState {
    /// Low-level power on, initialising.
    NotReadyToSwitchOn,
    /// Initialised, high voltage may be off.
    SwitchOnDisabled,
    /// High voltage may be on, drive function disabled.
    ReadyToSwitchOn,
    /// Power amplifier ready, drive function disabled.
    SwitchedOn,
    /// Drive function enabled: the drive follows its targets.
    OperationEnabled,
    /// The quick stop function is being (or has been) executed.
    QuickStopActive,
    /// A fault occurred, the fault reaction is executing.
    FaultReactionActive,
    /// Fault: drive function disabled.
    Fault,
}

/// Statusword mask and value per state, as data (the CiA 402 state table).
pub const STATE_TABLE: [(PowerState, u16, u16); 8] = [
    (PowerState::NotReadyToSwitchOn, 0x4F, 0x00),
    (PowerState::SwitchOnDisabled, 0x4F, 0x40),
    (PowerState::ReadyToSwitchOn, 0x6F, 0x21),
    (PowerState::SwitchedOn, 0x6F, 0x23),
    (PowerState::OperationEnabled, 0x6F, 0x27),
    (PowerState::QuickStopActive, 0x6F, 0x07),
    (PowerState::FaultReactionActive, 0x4F, 0x0F),
    (PowerState::Fault, 0x4F, 0x08),
];

impl Statusword {
    /// Bit 4: voltage enabled.
    pub const VOLTAGE_ENABLED: u16 = 1 << 4;
    /// Bit 7: warning.
    pub const WARNING: u16 = 1 << 7;
    /// Bit 9: remote (controlword processed).
    pub const REMOTE: u16 = 1 << 9;
    /// Bit 10: target reached.
    pub const TARGET_REACHED: u16 = 1 << 10;
    /// Bit 11: internal limit active.
    pub const INTERNAL_LIMIT: u16 = 1 << 11;

    /// The power state; `None` for a bit pattern outside the table.
    pub fn state(self) -> Option<PowerState> {
        STATE_TABLE
            .iter()
            .find(|(_, mask, value)| self.0 & mask == *value)
            .map(|(s, _, _)| *s)
    }

    /// The state bits of `state` (what a drive reports in it, other bits clear).
    pub fn of(state: PowerState) -> Self {
        let v = STATE_TABLE
            .iter()
            .find(|(s, _, _)| *s == state)
            .map_or(0, |(_, _, v)| *v);
        Self(v)
    }
}

impl core::fmt::Display for PowerState {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        let s = match self {
            Self::NotReadyToSwitchOn => "Not ready to switch on",
            Self::SwitchOnDisabled => "Switch on disabled",
            Self::ReadyToSwitchOn => "Ready to switch on",
            Self::SwitchedOn => "Switched on",
            Self::OperationEnabled => "Operation enabled",
            Self::QuickStopActive => "Quick stop active",
            Self::FaultReactionActive => "Fault reaction active",
            Self::Fault => "Fault",
        };
        f.write_str(s)
    }
}
