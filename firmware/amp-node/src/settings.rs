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
    /// [`DcRemoval::HighPass`] with a shift outside [`DcRemoval::SHIFTS`].
    DcShift {
        /// The refused shift.
        shift: u8,
    },
}

impl fmt::Display for NodeSettingsError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::GainNotOnBus { gain } => write!(
                f,
                "gain {gain}: EMG_STATUS.Gain names powers of two only (1, 2, 4, 8 on the ADS1299)"
            ),
            Self::Chip(e) => write!(f, "chip settings: {e}"),
            Self::DcShift { shift } => write!(
                f,
                "DC removal shift {shift}: {}..={} (corner {:.2}..{:.3} Hz at 1 kHz)",
                DcRemoval::SHIFTS.start(),
                DcRemoval::SHIFTS.end(),
                DcRemoval::corner_hz(*DcRemoval::SHIFTS.start()),
                DcRemoval::corner_hz(*DcRemoval::SHIFTS.end()),
            ),
        }
    }
}

impl core::error::Error for NodeSettingsError {}

/// Whether the node takes the electrodes' DC offset out before the bus ([`crate::DcBlock`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DcRemoval {
    /// Codes go to the bus as they are (DC-coupled): only for a front end whose offsets are
    /// known to stay far inside the bus's +-5.12 mV, and for tests that compare a recording
    /// to the LSB.
    Off,
    /// A first-order DC blocker per channel at the bus's 1 kHz, pole `1 - 2^-shift`: the
    /// corner near `1000 / (2π 2^shift)` Hz, an offset step decaying with `2^shift` ms.
    HighPass {
        /// 4..=12.
        shift: u8,
    },
}

impl DcRemoval {
    /// The reference: shift 6, corner 2.5 Hz (the chain's 10 Hz band edge loses 2.2 %,
    /// 0.2 dB; 20 Hz and up within 1 % of unity), a 30 mV step of an offset below one LSB within 0.7 s.
    pub const REFERENCE: Self = Self::HighPass { shift: 6 };

    /// The shifts accepted.
    pub const SHIFTS: core::ops::RangeInclusive<u8> = 4..=12;

    /// The -3 dB corner of `shift` at the bus's 1 kHz, Hz (first order).
    pub fn corner_hz(shift: u8) -> f64 {
        1000.0 / (core::f64::consts::TAU * f64::from(1u32 << shift))
    }
}

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
    dc: DcRemoval,
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
            dc: DcRemoval::REFERENCE,
            gain,
            amp_gain,
            first,
            second,
        })
    }

    /// These settings with `dc` (the reference's is [`DcRemoval::REFERENCE`]).
    pub fn with_dc_removal(self, dc: DcRemoval) -> Result<Self, NodeSettingsError> {
        if let DcRemoval::HighPass { shift } = dc {
            if !DcRemoval::SHIFTS.contains(&shift) {
                return Err(NodeSettingsError::DcShift { shift });
            }
        }
        Ok(Self { dc, ..self })
    }

    /// How the chips' conversions become the bus's 1 kHz.
    pub fn rate(&self) -> NodeRate {
        self.rate
    }

    /// Whether the DC goes before the bus.
    pub fn dc_removal(&self) -> DcRemoval {
        self.dc
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
