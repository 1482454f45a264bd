//! The handstack CAN bus: `hand.dbc` is the single source of truth for every frame on the
//! prosthesis's bus, and this crate owns it.
//!
//! - [`messages`]: message types generated from hand.dbc at build time, with the
//!   [`messages::decode`] dispatcher and [`messages::Message`].
//! - [`CanFrame`]: the concrete classic-CAN frame (implements [`embedded_can::Frame`]).
//! - [`e2e`]: alive counter + CRC-8 SAE J1850 protection and the receiver-side checker.
//! - [`emg`]: reassembly of 12-channel sEMG samples from the three EMG frame groups.
//! - [`busload`]: worst-case bus load computed from the DBC.
//! - [`candump`]: can-utils log reading and writing.
//!
//! Nothing here knows sockets, threads or clocks: the same code runs in the daemon, the
//! simulator, offline evaluation and replay.

pub mod busload;
pub mod candump;
pub mod e2e;
pub mod emg;
mod error;
mod frame;
mod info;
pub mod messages;

pub use error::CodecError;
pub use frame::{CanFrame, MAX_DLC};
pub use info::{MessageInfo, SignalInfo};
