//! SPI opcodes (SBAS499C, Table 10 "Command Definitions").

/// Wake up from standby.
pub const WAKEUP: u8 = 0x02;
/// Enter standby.
pub const STANDBY: u8 = 0x04;
/// Reset the device (registers to their reset values).
pub const RESET: u8 = 0x06;
/// Start or restart (synchronise) conversions.
pub const START: u8 = 0x08;
/// Stop conversions.
pub const STOP: u8 = 0x0A;
/// Enable read data continuous mode (the reset default).
pub const RDATAC: u8 = 0x10;
/// Stop read data continuous mode: needed before any register access.
pub const SDATAC: u8 = 0x11;
/// Read data by command.
pub const RDATA: u8 = 0x12;
/// Read registers: first byte `001r rrrr` (start address), second `000n nnnn` (count - 1).
pub const RREG: u8 = 0x20;
/// Write registers: first byte `010r rrrr` (start address), second `000n nnnn` (count - 1).
pub const WREG: u8 = 0x40;
