//! The driver's one error type.

use core::fmt;

/// Why an operation on the ADS1299 failed. `E` is the SPI device's error.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Error<E> {
    /// The SPI transaction failed.
    Spi(E),
    /// The ID register does not name an 8-channel ADS1299 (revision bits ignored).
    WrongId {
        /// What the ID register read.
        found: u8,
    },
    /// A register read back differently from what was written.
    Verify {
        /// Register address.
        address: u8,
        /// Value written.
        wrote: u8,
        /// Value read back.
        read: u8,
    },
    /// DRDY did not go low within the wait's bound.
    DrdyTimeout,
    /// The DRDY pin could not be read.
    DrdyPin,
    /// A register command for 0 or more than 17 registers (the longest writable block).
    Length {
        /// The number of registers asked for.
        len: usize,
    },
    /// A data frame whose status word does not start with the 1100 header (a read out of
    /// step with the conversions, or a chip that lost its configuration).
    BadHeader {
        /// The status word's first byte.
        first: u8,
    },
}

impl<E> From<E> for Error<E> {
    fn from(e: E) -> Self {
        Self::Spi(e)
    }
}

impl<E: fmt::Debug> fmt::Display for Error<E> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Spi(e) => write!(f, "SPI transaction failed: {e:?}"),
            Self::WrongId { found } => write!(
                f,
                "ID register reads {found:#04x}, not an 8-channel ADS1299 ({:#04x} under the \
                 revision bits 7:5)",
                crate::registers::id::EXPECTED_8CH
            ),
            Self::Length { len } => write!(f, "{len} registers in one command: 1 to 17"),
            Self::Verify {
                address,
                wrote,
                read,
            } => write!(
                f,
                "register {address:#04x} reads {read:#04x} after writing {wrote:#04x}"
            ),
            Self::DrdyTimeout => write!(f, "DRDY did not go low in time"),
            Self::DrdyPin => write!(f, "the DRDY pin could not be read"),
            Self::BadHeader { first } => write!(
                f,
                "data frame status starts with {first:#04x}, not the 1100 header"
            ),
        }
    }
}

impl<E: fmt::Debug> core::error::Error for Error<E> {}
