//! The no_std, no-alloc core of handstack's amplifier node: two ADS1299 (12 channels) in,
//! hand.dbc's EMG frames out over any [`embedded_can::nb::Can`].
//!
//! - [`NodeSettings`]: the node's configuration, validated once: the two chips' register
//!   settings, the bus scale and the chips' rate ([`NodeRate`]).
//! - [`Decimator`]: at 2 kSPS, the FIR that takes each pair of conversions to one bus sample.
//! - [`BusScale`]: ADS1299 codes to the bus's 2.5 uV LSB, exact integer arithmetic.
//! - [`DcBlock`]: the electrodes' DC offset taken out before the bus's 12 bits
//!   ([`DcRemoval`]).
//! - [`AmpNode`]: per sample, the two data frames become EMG_SAMPLES_G0..G2 (8-bit sample
//!   counter and CRC through `hand-dbc-core`, the daemon's own codec) in a fixed transmit
//!   queue; every 100 samples an EMG_STATUS with the lead-off and saturation masks. A full
//!   queue drops the whole sample and the counter still advances, so the daemon's gap rule
//!   sees the loss.
//! - [`TxQueue`]: the fixed-size frame queue between the sampler and the CAN controller.
//!
//! See README.md for the reference hardware, the register settings and what was tested only
//! on the host.

#![cfg_attr(not(test), no_std)]

mod dc_block;
mod decimator;
mod node;
mod settings;
mod tx_queue;
mod units;

pub use dc_block::DcBlock;
pub use decimator::{Decimator, TAPS, TAPS_Q15};
pub use node::{AmpNode, NodeCounters, SampleOutcome, CHANNELS, STATUS_EVERY};
pub use settings::{DcRemoval, NodeRate, NodeSettings, NodeSettingsError};
pub use tx_queue::TxQueue;
pub use units::{BusSample, BusScale, VREF_UV};
