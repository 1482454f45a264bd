//! A simulated ADS1299: an embedded-hal `SpiDevice` with the chip's register file, its
//! command decoder (RESET, SDATAC, RDATAC, START, RREG, WREG) and a queue of data frames
//! (codes) it serves in RDATAC mode. It also checks the serial timing the datasheet asks for:
//! at least 4 tCLK between the bytes of a command.
//!
//! The amplifier node's host tests drive the firmware through it, and the simulator's
//! amplifier (hand-model) serves its simulated patient's EMG through it to the firmware's own
//! node core, so every in-memory and vcan test runs the node's code.
//!
//! - [`SimAds1299`]: the chip, an embedded-hal `SpiDevice`.
//! - [`TakeAll`]: a CAN controller that takes every frame the node hands it (the node's
//!   `drain` into a bus that never fills), for the node's tests and the simulator's board.

mod can;
mod chip;

pub use can::TakeAll;
pub use chip::{SimAds1299, SimState};
