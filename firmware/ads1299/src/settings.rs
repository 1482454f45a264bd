//! The configuration of one chip, validated once, and the register image it writes.

use core::fmt;

use crate::registers::{chnset, config1, config2, config3, config4, gpio, loff, misc1, misc2};

/// Output data rate (CONFIG1.DR) with the nominal 2.048 MHz clock.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum DataRate {
    /// 250 SPS.
    Sps250,
    /// 500 SPS.
    Sps500,
    /// 1 kSPS.
    Sps1000,
    /// 2 kSPS.
    Sps2000,
    /// 4 kSPS.
    Sps4000,
    /// 8 kSPS.
    Sps8000,
    /// 16 kSPS.
    Sps16000,
}

impl DataRate {
    /// The DR\[2:0\] field value.
    pub const fn dr_bits(self) -> u8 {
        match self {
            Self::Sps250 => config1::DR_250,
            Self::Sps500 => config1::DR_500,
            Self::Sps1000 => config1::DR_1K,
            Self::Sps2000 => config1::DR_2K,
            Self::Sps4000 => config1::DR_4K,
            Self::Sps8000 => config1::DR_8K,
            Self::Sps16000 => config1::DR_16K,
        }
    }

    /// Samples per second.
    pub const fn hz(self) -> u32 {
        16_000 >> self.dr_bits()
    }
}

/// PGA gain (CHnSET.GAIN).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Gain {
    /// 1.
    X1,
    /// 2.
    X2,
    /// 4.
    X4,
    /// 6.
    X6,
    /// 8.
    X8,
    /// 12.
    X12,
    /// 24.
    X24,
}

impl Gain {
    /// The GAIN field, in place (bits 6:4).
    pub const fn bits(self) -> u8 {
        match self {
            Self::X1 => chnset::GAIN_1,
            Self::X2 => chnset::GAIN_2,
            Self::X4 => chnset::GAIN_4,
            Self::X6 => chnset::GAIN_6,
            Self::X8 => chnset::GAIN_8,
            Self::X12 => chnset::GAIN_12,
            Self::X24 => chnset::GAIN_24,
        }
    }

    /// The gain factor.
    pub const fn factor(self) -> u32 {
        match self {
            Self::X1 => 1,
            Self::X2 => 2,
            Self::X4 => 4,
            Self::X6 => 6,
            Self::X8 => 8,
            Self::X12 => 12,
            Self::X24 => 24,
        }
    }
}

/// What a channel measures.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ChannelInput {
    /// Its electrode pair, bipolar (MUX normal, SRB2 open): a used channel.
    Electrodes,
    /// Inputs shorted (offset and noise check).
    Shorted,
    /// The internal test signal.
    TestSignal,
    /// Powered down, inputs shorted (an unused channel).
    PoweredDown,
}

/// Whether this chip drives the bias (right-leg drive) electrode.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum BiasDrive {
    /// Bias buffer off (the other chip drives it).
    Off,
    /// Bias buffer on, internal reference, derived from the used channels' P and N inputs.
    FromUsedChannels,
}

/// Lead-off detection on the used channels.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum LeadOff {
    /// Comparators off (LOFF_STAT stays 0).
    Off,
    /// DC current excitation of 6 nA, comparators at 95 % / 5 %.
    Dc6nA,
    /// DC current excitation of 24 nA, comparators at 95 % / 5 %.
    Dc24nA,
}

/// Whether this chip drives its oscillator on CLK (the first chip, whose clock the second
/// uses).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ClockOutput {
    /// CLK is an input (CLKSEL low on the board) or unused.
    Off,
    /// CLK drives the internal oscillator out.
    On,
}

/// Why settings were refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SettingsError {
    /// No channel measures electrodes.
    NoChannelUsed,
}

impl fmt::Display for SettingsError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::NoChannelUsed => write!(f, "no channel is set to measure electrodes"),
        }
    }
}

impl core::error::Error for SettingsError {}

/// The validated configuration of one chip.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Settings {
    data_rate: DataRate,
    gain: Gain,
    inputs: [ChannelInput; 8],
    bias: BiasDrive,
    lead_off: LeadOff,
    clock_output: ClockOutput,
}

/// First address of the first writable block (CONFIG1).
pub(crate) const BLOCK_A_START: u8 = config1::ADDRESS;
/// Registers CONFIG1..LOFF_FLIP.
pub(crate) const BLOCK_A_LEN: usize = 17;
/// First address of the second writable block (GPIO); LOFF_STATP/N between are read only.
pub(crate) const BLOCK_B_START: u8 = gpio::ADDRESS;
/// Registers GPIO..CONFIG4.
pub(crate) const BLOCK_B_LEN: usize = 4;

impl Settings {
    /// Settings for one chip; refused when no channel measures electrodes.
    pub fn try_new(
        data_rate: DataRate,
        gain: Gain,
        inputs: [ChannelInput; 8],
        bias: BiasDrive,
        lead_off: LeadOff,
        clock_output: ClockOutput,
    ) -> Result<Self, SettingsError> {
        let s = Self {
            data_rate,
            gain,
            inputs,
            bias,
            lead_off,
            clock_output,
        };
        if s.used_mask() == 0 {
            return Err(SettingsError::NoChannelUsed);
        }
        Ok(s)
    }

    /// The data rate.
    pub fn data_rate(&self) -> DataRate {
        self.data_rate
    }

    /// The gain (every channel).
    pub fn gain(&self) -> Gain {
        self.gain
    }

    /// The channel inputs (index 0 = channel 1).
    pub fn inputs(&self) -> [ChannelInput; 8] {
        self.inputs
    }

    /// Bit n-1 set for each channel n that measures electrodes.
    pub fn used_mask(&self) -> u8 {
        self.inputs
            .iter()
            .enumerate()
            .filter(|(_, i)| **i == ChannelInput::Electrodes)
            .fold(0, |m, (c, _)| m | 1 << c)
    }

    /// CHnSET for channel `c` (0-based).
    fn chnset(&self, c: usize) -> u8 {
        let gain = self.gain.bits();
        match self.inputs[c] {
            ChannelInput::Electrodes => gain | chnset::MUX_NORMAL,
            ChannelInput::Shorted => gain | chnset::MUX_SHORTED,
            ChannelInput::TestSignal => gain | chnset::MUX_TEST,
            ChannelInput::PoweredDown => chnset::PD | gain | chnset::MUX_SHORTED,
        }
    }

    /// CONFIG1..LOFF_FLIP (addresses 01h..11h), in address order.
    pub fn block_a(&self) -> [u8; BLOCK_A_LEN] {
        let used = self.used_mask();
        let clk = match self.clock_output {
            ClockOutput::On => config1::CLK_EN,
            ClockOutput::Off => 0,
        };
        // Multiple readback (DAISY_EN = 1): each chip has its own chip select.
        let config1 = config1::FIXED | config1::DAISY_EN | clk | self.data_rate.dr_bits();
        let test = self.inputs.contains(&ChannelInput::TestSignal);
        // Internal test signal, 1 x amplitude, fCLK / 2^21 (about 1 Hz), when a channel uses it.
        let config2 = config2::FIXED | if test { config2::INT_CAL } else { 0 };
        let (bias_bits, bias_sense) = match self.bias {
            BiasDrive::FromUsedChannels => (config3::BIASREF_INT | config3::PD_BIAS, used),
            BiasDrive::Off => (0, 0),
        };
        let config3 = config3::FIXED | config3::PD_REFBUF | bias_bits;
        let (loff_reg, loff_sense) = match self.lead_off {
            LeadOff::Off => (
                loff::COMP_TH_95 | loff::ILEAD_OFF_6NA | loff::FLEAD_OFF_DC,
                0,
            ),
            LeadOff::Dc6nA => (
                loff::COMP_TH_95 | loff::ILEAD_OFF_6NA | loff::FLEAD_OFF_DC,
                used,
            ),
            LeadOff::Dc24nA => (
                loff::COMP_TH_95 | loff::ILEAD_OFF_24NA | loff::FLEAD_OFF_DC,
                used,
            ),
        };
        [
            config1,
            config2,
            config3,
            loff_reg,
            self.chnset(0),
            self.chnset(1),
            self.chnset(2),
            self.chnset(3),
            self.chnset(4),
            self.chnset(5),
            self.chnset(6),
            self.chnset(7),
            bias_sense, // BIAS_SENSP
            bias_sense, // BIAS_SENSN
            loff_sense, // LOFF_SENSP
            loff_sense, // LOFF_SENSN
            0,          // LOFF_FLIP: default current directions
        ]
    }

    /// GPIO..CONFIG4 (addresses 14h..17h), in address order.
    pub fn block_b(&self) -> [u8; BLOCK_B_LEN] {
        let config4 = match self.lead_off {
            LeadOff::Off => 0,
            // Continuous conversion, lead-off comparators powered: LOFF_STATP/N are live.
            LeadOff::Dc6nA | LeadOff::Dc24nA => config4::PD_LOFF_COMP,
        };
        [
            gpio::RESET,  // GPIO: all inputs (unused)
            misc1::RESET, // MISC1: SRB1 open (bipolar channels)
            misc2::RESET, // MISC2: reserved
            config4,
        ]
    }
}
