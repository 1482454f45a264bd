//! The node's configuration: validated once, it yields both chips' register settings.

use core::fmt;

use ads1299::{BiasDrive, ChannelInput, ClockOutput, DataRate, Gain, LeadOff, Settings};
use hand_dbc_core::messages::{AmpGain, AmpSampleRate};

use crate::BusScale;

/// Why node settings were refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NodeSettingsError {
    /// EMG_STATUS.Gain (hand.dbc's AmpGain: 1, 2, 4 .. 128) cannot name this ADS1299 gain.
    GainNotOnBus {
        /// The refused gain factor.
        gain: u32,
    },
    /// A chip's settings were refused.
    Chip(ads1299::SettingsError),
}

impl fmt::Display for NodeSettingsError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::GainNotOnBus { gain } => write!(
                f,
                "gain {gain}: EMG_STATUS.Gain names powers of two only (1, 2, 4, 8 on the ADS1299)"
            ),
            Self::Chip(e) => write!(f, "chip settings: {e}"),
        }
    }
}

impl core::error::Error for NodeSettingsError {}

/// How the node gets the bus's 1 kHz from the chips.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum NodeRate {
    /// The chips convert at 1 kSPS, one conversion per bus sample: exact codes on the bus,
    /// but the chips' sinc3 filter is -3 dB at 262 Hz, inside the chain's 10-450 Hz band.
    #[default]
    Sps1000,
    /// The chips convert at 2 kSPS (sinc3 -3 dB at 524 Hz) and the node's FIR
    /// ([`crate::Decimator`]) takes every pair of conversions to one bus sample: the band kept
    /// to 450 Hz (-1.5 dB there), 15.5 ms more delay. README, "Data rate": the features' loss
    /// against the signal falls from 8.9 % (RMS, median) to 2.5 %.
    Sps2000Decimated,
}

impl NodeRate {
    /// The chips' data rate.
    pub const fn data_rate(self) -> DataRate {
        match self {
            Self::Sps1000 => DataRate::Sps1000,
            Self::Sps2000Decimated => DataRate::Sps2000,
        }
    }
}

/// The node's settings: 12 channels at the bus's 1 kHz (from 1 kSPS, or 2 kSPS decimated),
/// one gain, lead-off; both chips' register settings are built and checked here, once.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct NodeSettings {
    rate: NodeRate,
    gain: Gain,
    amp_gain: AmpGain,
    first: Settings,
    second: Settings,
}

impl NodeSettings {
    /// Settings at `gain` with `lead_off` (the reference: [`Gain::X8`], [`LeadOff::Dc6nA`];
    /// README: why); refused when EMG_STATUS cannot report the gain.
    pub fn try_new(gain: Gain, lead_off: LeadOff) -> Result<Self, NodeSettingsError> {
        Self::try_with_rate(NodeRate::Sps1000, gain, lead_off)
    }

    /// [`Self::try_new`] with the chips at `rate`.
    pub fn try_with_rate(
        rate: NodeRate,
        gain: Gain,
        lead_off: LeadOff,
    ) -> Result<Self, NodeSettingsError> {
        let amp_gain = match gain {
            Gain::X1 => AmpGain::Gain1,
            Gain::X2 => AmpGain::Gain2,
            Gain::X4 => AmpGain::Gain4,
            Gain::X8 => AmpGain::Gain8,
            Gain::X6 | Gain::X12 | Gain::X24 => {
                return Err(NodeSettingsError::GainNotOnBus {
                    gain: gain.factor(),
                })
            }
        };
        let chip = |inputs, bias, clock| {
            Settings::try_new(rate.data_rate(), gain, inputs, bias, lead_off, clock)
                .map_err(NodeSettingsError::Chip)
        };
        // The first chip: bus channels 0..8 on its channels 1..8; drives its clock out to the
        // second chip, and the bias electrode.
        let first = chip(
            [ChannelInput::Electrodes; 8],
            BiasDrive::FromUsedChannels,
            ClockOutput::On,
        )?;
        // The second chip: bus channels 8..12 on its channels 1..4, 5..8 powered down; clocked
        // by the first, no bias drive of its own.
        let mut inputs = [ChannelInput::PoweredDown; 8];
        inputs[..4].fill(ChannelInput::Electrodes);
        let second = chip(inputs, BiasDrive::Off, ClockOutput::Off)?;
        Ok(Self {
            rate,
            gain,
            amp_gain,
            first,
            second,
        })
    }

    /// How the chips' conversions become the bus's 1 kHz.
    pub fn rate(&self) -> NodeRate {
        self.rate
    }

    /// The gain.
    pub fn gain(&self) -> Gain {
        self.gain
    }

    /// The gain as EMG_STATUS reports it.
    pub fn amp_gain(&self) -> AmpGain {
        self.amp_gain
    }

    /// The rate as EMG_STATUS reports it: the bus's, whatever the chips' rate.
    pub fn amp_sample_rate(&self) -> AmpSampleRate {
        AmpSampleRate::Sr1000Hz
    }

    /// The scale from codes to the bus.
    pub fn scale(&self) -> BusScale {
        BusScale::new(self.gain)
    }

    /// The first chip's register settings (bus channels 0..8).
    pub fn first_chip(&self) -> &Settings {
        &self.first
    }

    /// The second chip's register settings (bus channels 8..12 on its channels 1..4).
    pub fn second_chip(&self) -> &Settings {
        &self.second
    }
}
