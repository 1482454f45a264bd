//! The controlword (0x6040) and the device control commands (CiA 402 table 28).

/// The controlword.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Controlword(pub u16);

/// A device control command.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Command {
    /// 0bxxxx_x110: transitions 2, 6, 8.
    Shutdown,
    /// 0bxxxx_0111: transition 3.
    SwitchOn,
    /// 0bxxxx_1111: transitions 4, 16.
    EnableOperation,
    /// 0bxxxx_xx0x: transitions 7, 9, 10, 12.
    DisableVoltage,
    /// 0bxxxx_x01x: transitions 7, 10, 11.
    QuickStop,
    /// 0bxxxx_0111 in Operation enabled: transition 5.
    DisableOperation,
    /// Bit 7 rising edge: transition 15.
    FaultReset,
}

impl Command {
    /// The controlword the master sends for this command (fault reset: the bit-7 word; the
    /// edge needs a word with bit 7 clear before it, see [`Controlword::FAULT_RESET_LOW`]).
    pub fn controlword(self) -> Controlword {
        Controlword(match self {
            Self::Shutdown => 0x0006,
            Self::SwitchOn | Self::DisableOperation => 0x0007,
            Self::EnableOperation => 0x000F,
            Self::DisableVoltage => 0x0000,
            Self::QuickStop => 0x0002,
            Self::FaultReset => 0x0080,
        })
    }

    /// Whether `cw`'s bits 0-3 (and 7 for fault reset) select this command.
    pub fn matches(self, cw: Controlword) -> bool {
        let c = cw.0;
        match self {
            Self::DisableVoltage => c & 0x02 == 0,
            Self::QuickStop => c & 0x06 == 0x02,
            Self::Shutdown => c & 0x07 == 0x06,
            Self::SwitchOn | Self::DisableOperation => c & 0x0F == 0x07,
            Self::EnableOperation => c & 0x0F == 0x0F,
            Self::FaultReset => c & 0x80 != 0,
        }
    }
}

impl Controlword {
    /// Bit 7 clear, nothing else: the low half of a clean fault reset edge.
    pub const FAULT_RESET_LOW: Controlword = Controlword(0x0000);

    /// Bit 7.
    pub fn fault_reset_bit(self) -> bool {
        self.0 & 0x80 != 0
    }
}
