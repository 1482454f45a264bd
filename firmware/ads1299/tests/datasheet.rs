//! Every register constant against a transcription of SBAS499C's register map (Table 11,
//! "Register Assignments", and the per-register bit tables), and the opcodes against
//! Table 10 ("Command Definitions"). A row: address, name, reset value (xx = varies),
//! bits 7..0 (a field bit is NAMEn, a fixed bit 0 or 1).

use std::hint::black_box;

use ads1299::command;
use ads1299::registers::*;

const MAP: &str = "
00 ID         xx REV_ID2 REV_ID1 REV_ID0 1 DEV_ID1 DEV_ID0 NU_CH1 NU_CH0
01 CONFIG1    96 1 DAISY_EN CLK_EN 1 0 DR2 DR1 DR0
02 CONFIG2    C0 1 1 0 INT_CAL 0 CAL_AMP0 CAL_FREQ1 CAL_FREQ0
03 CONFIG3    60 PD_REFBUF 1 1 BIAS_MEAS BIASREF_INT PD_BIAS BIAS_LOFF_SENS BIAS_STAT
04 LOFF       00 COMP_TH2 COMP_TH1 COMP_TH0 0 ILEAD_OFF1 ILEAD_OFF0 FLEAD_OFF1 FLEAD_OFF0
05 CH1SET     61 PD1 GAIN12 GAIN11 GAIN10 SRB2 MUX12 MUX11 MUX10
0C CH8SET     61 PD8 GAIN82 GAIN81 GAIN80 SRB2 MUX82 MUX81 MUX80
0D BIAS_SENSP 00 BIASP8 BIASP7 BIASP6 BIASP5 BIASP4 BIASP3 BIASP2 BIASP1
0E BIAS_SENSN 00 BIASN8 BIASN7 BIASN6 BIASN5 BIASN4 BIASN3 BIASN2 BIASN1
0F LOFF_SENSP 00 LOFFP8 LOFFP7 LOFFP6 LOFFP5 LOFFP4 LOFFP3 LOFFP2 LOFFP1
10 LOFF_SENSN 00 LOFFM8 LOFFM7 LOFFM6 LOFFM5 LOFFM4 LOFFM3 LOFFM2 LOFFM1
11 LOFF_FLIP  00 LOFF_FLIP8 LOFF_FLIP7 LOFF_FLIP6 LOFF_FLIP5 LOFF_FLIP4 LOFF_FLIP3 LOFF_FLIP2 LOFF_FLIP1
12 LOFF_STATP 00 IN8P_OFF IN7P_OFF IN6P_OFF IN5P_OFF IN4P_OFF IN3P_OFF IN2P_OFF IN1P_OFF
13 LOFF_STATN 00 IN8N_OFF IN7N_OFF IN6N_OFF IN5N_OFF IN4N_OFF IN3N_OFF IN2N_OFF IN1N_OFF
14 GPIO       0F GPIOD4 GPIOD3 GPIOD2 GPIOD1 GPIOC4 GPIOC3 GPIOC2 GPIOC1
15 MISC1      00 0 0 SRB1 0 0 0 0 0
16 MISC2      00 0 0 0 0 0 0 0 0
17 CONFIG4    00 0 0 0 0 SINGLE_SHOT 0 PD_LOFF_COMP 0
";

/// Opcodes (first byte; RREG/WREG carry the start address in their low 5 bits).
const COMMANDS: &str = "
WAKEUP 0000_0010
STANDBY 0000_0100
RESET 0000_0110
START 0000_1000
STOP 0000_1010
RDATAC 0001_0000
SDATAC 0001_0001
RDATA 0001_0010
RREG 0010_0000
WREG 0100_0000
";

struct Row {
    address: u8,
    reset: Option<u8>,
    bits: Vec<&'static str>,
}

fn map() -> Vec<(&'static str, Row)> {
    MAP.lines()
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            let f: Vec<&'static str> = l.split_whitespace().collect();
            assert!(f.len() == 11, "row {l:?} has {} fields", f.len());
            let row = Row {
                address: u8::from_str_radix(f[0], 16).expect("hex address"),
                reset: u8::from_str_radix(f[2], 16).ok(),
                bits: f[3..].to_vec(),
            };
            (f[1], row)
        })
        .collect()
}

fn row(name: &str) -> Row {
    map()
        .into_iter()
        .find(|(n, _)| *n == name)
        .expect("register in the table")
        .1
}

/// The mask of the bits whose names start with `prefix` (bit 7 is the first column).
fn field(r: &Row, prefix: &str) -> u8 {
    r.bits
        .iter()
        .enumerate()
        .filter(|(_, b)| b.starts_with(prefix))
        .fold(0, |m, (i, _)| m | 0x80 >> i)
}

/// The fixed-1 bits.
fn ones(r: &Row) -> u8 {
    field(r, "1")
}

#[test]
fn addresses_and_reset_values() {
    let table = [
        ("ID", id::ADDRESS, None),
        ("CONFIG1", config1::ADDRESS, Some(config1::RESET)),
        ("CONFIG2", config2::ADDRESS, Some(config2::RESET)),
        ("CONFIG3", config3::ADDRESS, Some(config3::RESET)),
        ("LOFF", loff::ADDRESS, Some(loff::RESET)),
        ("CH1SET", chnset::CH1SET_ADDRESS, Some(chnset::RESET)),
        ("CH8SET", chnset::CH8SET_ADDRESS, Some(chnset::RESET)),
        (
            "BIAS_SENSP",
            channel_masks::BIAS_SENSP,
            Some(channel_masks::RESET),
        ),
        (
            "BIAS_SENSN",
            channel_masks::BIAS_SENSN,
            Some(channel_masks::RESET),
        ),
        (
            "LOFF_SENSP",
            channel_masks::LOFF_SENSP,
            Some(channel_masks::RESET),
        ),
        (
            "LOFF_SENSN",
            channel_masks::LOFF_SENSN,
            Some(channel_masks::RESET),
        ),
        (
            "LOFF_FLIP",
            channel_masks::LOFF_FLIP,
            Some(channel_masks::RESET),
        ),
        (
            "LOFF_STATP",
            channel_masks::LOFF_STATP,
            Some(channel_masks::RESET),
        ),
        (
            "LOFF_STATN",
            channel_masks::LOFF_STATN,
            Some(channel_masks::RESET),
        ),
        ("GPIO", gpio::ADDRESS, Some(gpio::RESET)),
        ("MISC1", misc1::ADDRESS, Some(misc1::RESET)),
        ("MISC2", misc2::ADDRESS, Some(misc2::RESET)),
        ("CONFIG4", config4::ADDRESS, Some(config4::RESET)),
    ];
    assert!(
        table.len() == map().len(),
        "every transcribed row is checked"
    );
    for (name, address, reset) in table {
        let r = row(name);
        assert!(
            r.address == address,
            "{name}: address {address:#04x}, datasheet {:#04x}",
            r.address
        );
        assert!(
            r.reset == reset,
            "{name}: reset {reset:?}, datasheet {:?}",
            r.reset
        );
    }
    for n in 1..=8u8 {
        assert!(chnset::address(n) == Some(chnset::CH1SET_ADDRESS + n - 1));
    }
    assert!(chnset::address(0).is_none() && chnset::address(9).is_none());
    assert!(chnset::address(8) == Some(chnset::CH8SET_ADDRESS));
    assert!(COUNT == usize::from(config4::ADDRESS) + 1);
}

#[test]
fn bit_fields() {
    let r = row("ID");
    assert!(id::REV_ID_MASK == field(&r, "REV_ID") && id::FIXED == ones(&r));
    assert!(id::DEV_ID_MASK == field(&r, "DEV_ID") && id::NU_CH_MASK == field(&r, "NU_CH"));
    // An 8-channel ADS1299 revision 1 reads 0x3E.
    assert!(id::EXPECTED_8CH == black_box(0x3E) & !id::REV_ID_MASK);
    assert!((id::NU_CH_4, id::NU_CH_6, id::NU_CH_8) == (0, 1, 2));

    let r = row("CONFIG1");
    assert!(config1::FIXED == ones(&r));
    assert!(config1::DAISY_EN == field(&r, "DAISY_EN") && config1::CLK_EN == field(&r, "CLK_EN"));
    assert!(config1::DR_MASK == field(&r, "DR"));
    // DR: fMOD / 2^(6 + DR), fMOD = 1.024 MHz.
    let drs = [
        (config1::DR_16K, 16_000),
        (config1::DR_8K, 8_000),
        (config1::DR_4K, 4_000),
        (config1::DR_2K, 2_000),
        (config1::DR_1K, 1_000),
        (config1::DR_500, 500),
        (config1::DR_250, 250),
    ];
    for (dr, sps) in drs {
        assert!(1_024_000 >> (6 + dr) == sps, "DR {dr:03b}");
    }
    assert!(row("CONFIG1").reset.map(|r| r & config1::DR_MASK) == Some(config1::DR_250));

    let r = row("CONFIG2");
    assert!(config2::FIXED == ones(&r) && config2::INT_CAL == field(&r, "INT_CAL"));
    assert!(config2::CAL_AMP0 == field(&r, "CAL_AMP0"));
    assert!(config2::CAL_FREQ_MASK == field(&r, "CAL_FREQ"));

    let r = row("CONFIG3");
    assert!(config3::FIXED == ones(&r));
    for (mask, name) in [
        (config3::PD_REFBUF, "PD_REFBUF"),
        (config3::BIAS_MEAS, "BIAS_MEAS"),
        (config3::BIASREF_INT, "BIASREF_INT"),
        (config3::PD_BIAS, "PD_BIAS"),
        (config3::BIAS_LOFF_SENS, "BIAS_LOFF_SENS"),
        (config3::BIAS_STAT, "BIAS_STAT"),
    ] {
        assert!(mask == field(&r, name), "CONFIG3.{name}");
    }

    let r = row("LOFF");
    assert!(loff::FIXED == ones(&r));
    assert!(loff::COMP_TH_MASK == field(&r, "COMP_TH"));
    assert!(loff::ILEAD_OFF_MASK == field(&r, "ILEAD_OFF"));
    assert!(loff::FLEAD_OFF_MASK == field(&r, "FLEAD_OFF"));
    let currents = [
        loff::ILEAD_OFF_6NA,
        loff::ILEAD_OFF_24NA,
        loff::ILEAD_OFF_6UA,
        loff::ILEAD_OFF_24UA,
    ];
    for (k, c) in currents.into_iter().enumerate() {
        assert!(c == (k as u8) << 2 && c & !loff::ILEAD_OFF_MASK == 0);
    }
    let freqs = [
        loff::FLEAD_OFF_DC,
        loff::FLEAD_OFF_AC_7HZ8,
        loff::FLEAD_OFF_AC_31HZ2,
        loff::FLEAD_OFF_AC_FDR_4,
    ];
    for (k, f) in freqs.into_iter().enumerate() {
        assert!(f == k as u8);
    }
    assert!(black_box(loff::COMP_TH_95) == 0, "COMP_TH 000 = 95 %");

    let r = row("CH1SET");
    assert!(chnset::PD == field(&r, "PD1") && chnset::GAIN_MASK == field(&r, "GAIN1"));
    assert!(chnset::SRB2 == field(&r, "SRB2") && chnset::MUX_MASK == field(&r, "MUX1"));
    // GAINn: 000 1, 001 2, 010 4, 011 6, 100 8, 101 12, 110 24.
    let gains = [
        chnset::GAIN_1,
        chnset::GAIN_2,
        chnset::GAIN_4,
        chnset::GAIN_6,
        chnset::GAIN_8,
        chnset::GAIN_12,
        chnset::GAIN_24,
    ];
    for (k, g) in gains.into_iter().enumerate() {
        assert!(g == (k as u8) << 4);
    }
    // MUXn: 000 normal .. 111 BIAS_DRN.
    let muxes = [
        chnset::MUX_NORMAL,
        chnset::MUX_SHORTED,
        chnset::MUX_BIAS_MEAS,
        chnset::MUX_MVDD,
        chnset::MUX_TEMP,
        chnset::MUX_TEST,
        chnset::MUX_BIAS_DRP,
        chnset::MUX_BIAS_DRN,
    ];
    for (k, m) in muxes.into_iter().enumerate() {
        assert!(m == k as u8);
    }
    assert!(row("CH1SET").reset == Some(chnset::GAIN_24 | chnset::MUX_SHORTED));

    let r = row("GPIO");
    assert!(gpio::GPIOD_MASK == field(&r, "GPIOD") && gpio::GPIOC_MASK == field(&r, "GPIOC"));
    let r = row("MISC1");
    assert!(misc1::SRB1 == field(&r, "SRB1"));
    let r = row("CONFIG4");
    assert!(config4::SINGLE_SHOT == field(&r, "SINGLE_SHOT"));
    assert!(config4::PD_LOFF_COMP == field(&r, "PD_LOFF_COMP"));
    // Channel n is bit n-1 in every per-channel mask register.
    for name in ["BIAS_SENSP", "LOFF_SENSP", "LOFF_STATP", "LOFF_STATN"] {
        let r = row(name);
        assert!(
            r.bits[7].ends_with('1') || r.bits[7].contains("IN1"),
            "{name}: channel 1 is bit 0"
        );
    }
}

#[test]
fn opcodes() {
    let ours = [
        ("WAKEUP", command::WAKEUP),
        ("STANDBY", command::STANDBY),
        ("RESET", command::RESET),
        ("START", command::START),
        ("STOP", command::STOP),
        ("RDATAC", command::RDATAC),
        ("SDATAC", command::SDATAC),
        ("RDATA", command::RDATA),
        ("RREG", command::RREG),
        ("WREG", command::WREG),
    ];
    let table: Vec<(&str, u8)> = COMMANDS
        .lines()
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            let (name, bits) = l.split_once(' ').expect("name bits");
            (
                name,
                u8::from_str_radix(&bits.replace('_', ""), 2).expect("binary"),
            )
        })
        .collect();
    assert!(table.len() == ours.len());
    for ((n, v), (tn, tv)) in ours.iter().zip(&table) {
        assert!(
            n == tn && v == tv,
            "{n} = {v:#04x}, datasheet {tn} = {tv:#04x}"
        );
    }
}
