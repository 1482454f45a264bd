//! The no_std, no-alloc core of the handstack bus codec, shared by the daemon (through
//! `hand-dbc`, which re-exports every module here) and the amplifier node's firmware
//! (`firmware/amp-node`), so that their frames cannot drift apart.
//!
//! - [`messages`]: the message types generated from hand.dbc by `hand-dbc-codegen` into the
//!   checked-in `core/src/messages/generated.rs`, the [`messages::decode`] dispatcher and
//!   [`messages::MESSAGES`].
//! - [`e2e`]: alive counter + CRC-8 SAE J1850, sender and receiver side.
//! - [`emg`]: the EMG frame groups ([`emg::EmgFrame`]) and the sample reassembly.
//! - [`hand`]: the hand's constants from the DBC.
//! - [`CanFrame`]: the concrete classic-CAN frame (implements [`embedded_can::Frame`]).
//!
//! Builds for `thumbv7em-none-eabihf` with neither `std` nor `alloc`
//! (`scripts/thumbv7-build`).

#![cfg_attr(not(test), no_std)]

pub mod e2e;
pub mod emg;
mod error;
mod frame;
pub mod hand;
mod info;
pub mod messages;
mod num;

pub use error::CodecError;
pub use frame::{CanFrame, MAX_DLC};
pub use info::{MessageInfo, SignalInfo};
