//! A no_std driver for TI's ADS1299 (SBAS499C): 8 channels, 24 bits, for biopotentials.
//!
//! - [`registers`]: the register map and bit fields with the datasheet's names.
//! - [`command`]: the SPI opcodes.
//! - [`timing`]: the serial interface timing (tCLK, tSDECODE, reset and power-up waits).
//! - [`Settings`]: a validated configuration (data rate, gain, input mux, bias, lead-off) and
//!   the register image it writes.
//! - [`Ads1299`]: one chip on an embedded-hal 1.0 [`SpiDevice`](embedded_hal::spi::SpiDevice):
//!   reset, SDATAC, id check, configuration, RDATAC and the 27-byte frame read.
//! - [`Frame`], [`Code`], [`Status`]: one conversion: status word (lead-off P/N bits, GPIO)
//!   and eight 24-bit two's complement codes, with the saturation codes.
//! - [`wait_drdy`]: a bounded poll of the DRDY pin.
//! - [`Error`]: everything that can go wrong, named.
//!
//! Two chips for more channels share CLK and START and each get a chip select: two
//! [`Ads1299`] over two `SpiDevice`s on one bus.

#![cfg_attr(not(test), no_std)]

pub mod command;
mod device;
mod drdy;
mod error;
mod frame;
pub mod registers;
mod settings;
pub mod timing;

pub use device::Ads1299;
pub use drdy::wait_drdy;
pub use error::Error;
pub use frame::{Code, Frame, Status, FRAME_BYTES};
pub use settings::{
    BiasDrive, ChannelInput, ClockOutput, DataRate, Gain, LeadOff, Settings, SettingsError,
};
