//! The register map (SBAS499C, Table 11 "Register Assignments", and the register
//! descriptions that follow it), with the datasheet's names. One module per register: its
//! `ADDRESS`, its `RESET` value and its bit fields as masks (`_MASK` for fields wider than a
//! bit, field values as named constants). Fixed bits ("must be written as 1/0") are `FIXED`.
//! `tests/datasheet.rs` checks every constant against a transcription of the table.

/// Number of registers (ID at 00h .. CONFIG4 at 17h).
pub const COUNT: usize = 0x18;

/// ID: device identification (read only).
pub mod id {
    /// Address.
    pub const ADDRESS: u8 = 0x00;
    /// REV_ID\[2:0\]: revision (bits 7:5); varies with the silicon.
    pub const REV_ID_MASK: u8 = 0b1110_0000;
    /// Bit 4 reads 1.
    pub const FIXED: u8 = 0b0001_0000;
    /// DEV_ID\[1:0\] (bits 3:2): 11 for the ADS1299 family.
    pub const DEV_ID_MASK: u8 = 0b0000_1100;
    /// DEV_ID value of the ADS1299 family.
    pub const DEV_ID_ADS1299: u8 = 0b0000_1100;
    /// NU_CH\[1:0\] (bits 1:0): channel count.
    pub const NU_CH_MASK: u8 = 0b0000_0011;
    /// NU_CH: 4 channels (ADS1299-4).
    pub const NU_CH_4: u8 = 0b00;
    /// NU_CH: 6 channels (ADS1299-6).
    pub const NU_CH_6: u8 = 0b01;
    /// NU_CH: 8 channels (ADS1299).
    pub const NU_CH_8: u8 = 0b10;
    /// What an 8-channel ADS1299 reads, revision bits masked out: 0x1E (0x3E for revision 1).
    pub const EXPECTED_8CH: u8 = FIXED | DEV_ID_ADS1299 | NU_CH_8;
}

/// CONFIG1: daisy-chain / multiple readback, clock output, data rate.
pub mod config1 {
    /// Address.
    pub const ADDRESS: u8 = 0x01;
    /// Reset value.
    pub const RESET: u8 = 0x96;
    /// Bit 7 must be 1, bits 4:3 must be 10.
    pub const FIXED: u8 = 0b1001_0000;
    /// DAISY_EN (bit 6; the datasheet writes it DAISY_EN with a bar): 0 daisy-chain, 1 multiple
    /// readback.
    pub const DAISY_EN: u8 = 1 << 6;
    /// CLK_EN (bit 5): 1 drives the oscillator clock on the CLK pin.
    pub const CLK_EN: u8 = 1 << 5;
    /// DR\[2:0\] (bits 2:0): output data rate, fMOD / 2^(6 + DR) with fMOD = fCLK / 2.
    pub const DR_MASK: u8 = 0b0000_0111;
    /// DR: 16 kSPS.
    pub const DR_16K: u8 = 0b000;
    /// DR: 8 kSPS.
    pub const DR_8K: u8 = 0b001;
    /// DR: 4 kSPS.
    pub const DR_4K: u8 = 0b010;
    /// DR: 2 kSPS.
    pub const DR_2K: u8 = 0b011;
    /// DR: 1 kSPS.
    pub const DR_1K: u8 = 0b100;
    /// DR: 500 SPS.
    pub const DR_500: u8 = 0b101;
    /// DR: 250 SPS (reset).
    pub const DR_250: u8 = 0b110;
}

/// CONFIG2: test signal.
pub mod config2 {
    /// Address.
    pub const ADDRESS: u8 = 0x02;
    /// Reset value.
    pub const RESET: u8 = 0xC0;
    /// Bits 7:5 must be 110, bit 3 must be 0.
    pub const FIXED: u8 = 0b1100_0000;
    /// INT_CAL (bit 4): test signal generated internally.
    pub const INT_CAL: u8 = 1 << 4;
    /// CAL_AMP0 (bit 2): test signal amplitude 2 x -(VREFP - VREFN) / 2400 instead of 1 x.
    pub const CAL_AMP0: u8 = 1 << 2;
    /// CAL_FREQ\[1:0\] (bits 1:0): test signal frequency.
    pub const CAL_FREQ_MASK: u8 = 0b0000_0011;
}

/// CONFIG3: reference buffer and bias (BIAS drive) amplifier.
pub mod config3 {
    /// Address.
    pub const ADDRESS: u8 = 0x03;
    /// Reset value.
    pub const RESET: u8 = 0x60;
    /// Bits 6:5 must be 11.
    pub const FIXED: u8 = 0b0110_0000;
    /// PD_REFBUF (bit 7): 1 powers the internal reference buffer up (VREF = 4.5 V).
    pub const PD_REFBUF: u8 = 1 << 7;
    /// BIAS_MEAS (bit 4): route BIASIN to channels whose MUX is BIAS_MEAS.
    pub const BIAS_MEAS: u8 = 1 << 4;
    /// BIASREF_INT (bit 3): bias reference (AVDD + AVSS) / 2 generated internally.
    pub const BIASREF_INT: u8 = 1 << 3;
    /// PD_BIAS (bit 2): 1 powers the bias buffer up.
    pub const PD_BIAS: u8 = 1 << 2;
    /// BIAS_LOFF_SENS (bit 1): bias sense for lead-off on.
    pub const BIAS_LOFF_SENS: u8 = 1 << 1;
    /// BIAS_STAT (bit 0, read only): 1 when the bias electrode is off.
    pub const BIAS_STAT: u8 = 1 << 0;
}

/// LOFF: lead-off comparator threshold, current and frequency.
pub mod loff {
    /// Address.
    pub const ADDRESS: u8 = 0x04;
    /// Reset value.
    pub const RESET: u8 = 0x00;
    /// Bit 4 must be 0.
    pub const FIXED: u8 = 0x00;
    /// COMP_TH\[2:0\] (bits 7:5): comparator threshold; 000 = 95 % positive / 5 % negative.
    pub const COMP_TH_MASK: u8 = 0b1110_0000;
    /// COMP_TH: 95 % / 5 % (reset).
    pub const COMP_TH_95: u8 = 0b000 << 5;
    /// ILEAD_OFF\[1:0\] (bits 3:2): lead-off current magnitude.
    pub const ILEAD_OFF_MASK: u8 = 0b0000_1100;
    /// ILEAD_OFF: 6 nA.
    pub const ILEAD_OFF_6NA: u8 = 0b00 << 2;
    /// ILEAD_OFF: 24 nA.
    pub const ILEAD_OFF_24NA: u8 = 0b01 << 2;
    /// ILEAD_OFF: 6 uA.
    pub const ILEAD_OFF_6UA: u8 = 0b10 << 2;
    /// ILEAD_OFF: 24 uA.
    pub const ILEAD_OFF_24UA: u8 = 0b11 << 2;
    /// FLEAD_OFF\[1:0\] (bits 1:0): lead-off frequency.
    pub const FLEAD_OFF_MASK: u8 = 0b0000_0011;
    /// FLEAD_OFF: DC lead-off detection.
    pub const FLEAD_OFF_DC: u8 = 0b00;
    /// FLEAD_OFF: AC at 7.8 Hz.
    pub const FLEAD_OFF_AC_7HZ8: u8 = 0b01;
    /// FLEAD_OFF: AC at 31.2 Hz.
    pub const FLEAD_OFF_AC_31HZ2: u8 = 0b10;
    /// FLEAD_OFF: AC at fDR / 4.
    pub const FLEAD_OFF_AC_FDR_4: u8 = 0b11;
}

/// CH1SET..CH8SET: per-channel power-down, gain, SRB2 and input mux.
pub mod chnset {
    /// Address of CH1SET; CHnSET is at `CH1SET_ADDRESS + n - 1`.
    pub const CH1SET_ADDRESS: u8 = 0x05;
    /// Address of CH8SET.
    pub const CH8SET_ADDRESS: u8 = 0x0C;
    /// Reset value (powered, gain 24, SRB2 open, input shorted).
    pub const RESET: u8 = 0x61;
    /// PDn (bit 7): 1 powers the channel down.
    pub const PD: u8 = 1 << 7;
    /// GAINn\[2:0\] (bits 6:4): PGA gain.
    pub const GAIN_MASK: u8 = 0b0111_0000;
    /// GAIN: 1.
    pub const GAIN_1: u8 = 0b000 << 4;
    /// GAIN: 2.
    pub const GAIN_2: u8 = 0b001 << 4;
    /// GAIN: 4.
    pub const GAIN_4: u8 = 0b010 << 4;
    /// GAIN: 6.
    pub const GAIN_6: u8 = 0b011 << 4;
    /// GAIN: 8.
    pub const GAIN_8: u8 = 0b100 << 4;
    /// GAIN: 12.
    pub const GAIN_12: u8 = 0b101 << 4;
    /// GAIN: 24 (reset).
    pub const GAIN_24: u8 = 0b110 << 4;
    /// SRB2 (bit 3): 1 connects the channel's P input to SRB2.
    pub const SRB2: u8 = 1 << 3;
    /// MUXn\[2:0\] (bits 2:0): channel input.
    pub const MUX_MASK: u8 = 0b0000_0111;
    /// MUX: normal electrode input.
    pub const MUX_NORMAL: u8 = 0b000;
    /// MUX: input shorted (offset or noise measurement).
    pub const MUX_SHORTED: u8 = 0b001;
    /// MUX: BIAS_MEAS (with CONFIG3.BIAS_MEAS).
    pub const MUX_BIAS_MEAS: u8 = 0b010;
    /// MUX: MVDD supply measurement.
    pub const MUX_MVDD: u8 = 0b011;
    /// MUX: temperature sensor.
    pub const MUX_TEMP: u8 = 0b100;
    /// MUX: test signal.
    pub const MUX_TEST: u8 = 0b101;
    /// MUX: BIAS_DRP (positive electrode is the driver).
    pub const MUX_BIAS_DRP: u8 = 0b110;
    /// MUX: BIAS_DRN (negative electrode is the driver).
    pub const MUX_BIAS_DRN: u8 = 0b111;

    /// The address of CHnSET for channel `n` (1..=8), `None` otherwise.
    pub const fn address(n: u8) -> Option<u8> {
        if n >= 1 && n <= 8 {
            Some(CH1SET_ADDRESS + n - 1)
        } else {
            None
        }
    }
}

/// Channel bit masks (bit n-1 = channel n): BIAS_SENSP, BIAS_SENSN, LOFF_SENSP, LOFF_SENSN,
/// LOFF_FLIP, LOFF_STATP, LOFF_STATN.
pub mod channel_masks {
    /// BIAS_SENSP: positive inputs that derive the bias.
    pub const BIAS_SENSP: u8 = 0x0D;
    /// BIAS_SENSN: negative inputs that derive the bias.
    pub const BIAS_SENSN: u8 = 0x0E;
    /// LOFF_SENSP: lead-off detection on the positive inputs.
    pub const LOFF_SENSP: u8 = 0x0F;
    /// LOFF_SENSN: lead-off detection on the negative inputs.
    pub const LOFF_SENSN: u8 = 0x10;
    /// LOFF_FLIP: lead-off current direction flipped.
    pub const LOFF_FLIP: u8 = 0x11;
    /// LOFF_STATP (read only): positive electrode off, per channel.
    pub const LOFF_STATP: u8 = 0x12;
    /// LOFF_STATN (read only): negative electrode off, per channel.
    pub const LOFF_STATN: u8 = 0x13;
    /// Reset value of all of them.
    pub const RESET: u8 = 0x00;
}

/// GPIO: the four general-purpose pins.
pub mod gpio {
    /// Address.
    pub const ADDRESS: u8 = 0x14;
    /// Reset value (all four inputs).
    pub const RESET: u8 = 0x0F;
    /// GPIOD\[4:1\] (bits 7:4): pin data.
    pub const GPIOD_MASK: u8 = 0b1111_0000;
    /// GPIOC\[4:1\] (bits 3:0): 1 = input.
    pub const GPIOC_MASK: u8 = 0b0000_1111;
}

/// MISC1: SRB1.
pub mod misc1 {
    /// Address.
    pub const ADDRESS: u8 = 0x15;
    /// Reset value.
    pub const RESET: u8 = 0x00;
    /// SRB1 (bit 5): connects SRB1 to all channels' negative inputs.
    pub const SRB1: u8 = 1 << 5;
}

/// MISC2: reserved.
pub mod misc2 {
    /// Address.
    pub const ADDRESS: u8 = 0x16;
    /// Reset value.
    pub const RESET: u8 = 0x00;
}

/// CONFIG4: single-shot and the lead-off comparators.
pub mod config4 {
    /// Address.
    pub const ADDRESS: u8 = 0x17;
    /// Reset value.
    pub const RESET: u8 = 0x00;
    /// SINGLE_SHOT (bit 3): 1 single-shot, 0 continuous conversion.
    pub const SINGLE_SHOT: u8 = 1 << 3;
    /// PD_LOFF_COMP (bit 1; the datasheet writes it with a bar): 1 powers the lead-off
    /// comparators up, so LOFF_STATP/N (and the status word) are live.
    pub const PD_LOFF_COMP: u8 = 1 << 1;
}
