//! The start-up sequence and the data read, byte by byte against mock SPI transaction
//! scripts (embedded-hal-mock), and the named errors.

use ads1299::timing::{T_RESET_NS, T_SCCS_NS, T_SDECODE_NS};
use ads1299::{
    wait_drdy, Ads1299, BiasDrive, ChannelInput, ClockOutput, DataRate, Error, Gain, LeadOff,
    Settings,
};
use embedded_hal::spi::{ErrorKind, ErrorType, Operation, SpiDevice};
use embedded_hal_mock::eh1::delay::NoopDelay;
use embedded_hal_mock::eh1::digital::{Mock as PinMock, State, Transaction as PinT};
use embedded_hal_mock::eh1::spi::{Mock as SpiMock, Transaction as T};

/// 4 tCLK and 18 tCLK at 2.048 MHz, from the datasheet, in ns (rounded up).
const DECODE: u32 = 1_956;
const RESET_WAIT: u32 = 8_802;

fn command(op: u8, wait: u32) -> Vec<T<u8>> {
    vec![
        T::transaction_start(),
        T::write(op),
        T::delay(wait),
        T::transaction_end(),
    ]
}

/// WREG/RREG framing: each byte, then tSDECODE (the last one tSCCS: both are 4 tCLK).
fn wreg(start: u8, values: &[u8]) -> Vec<T<u8>> {
    let mut bytes = vec![0x40 | start, values.len() as u8 - 1];
    bytes.extend_from_slice(values);
    let mut t = vec![T::transaction_start()];
    for b in &bytes {
        t.push(T::write(*b));
        t.push(T::delay(DECODE));
    }
    t.push(T::transaction_end());
    t
}

fn rreg(start: u8, values: &[u8]) -> Vec<T<u8>> {
    let mut t = vec![
        T::transaction_start(),
        T::write(0x20 | start),
        T::delay(DECODE),
        T::write(values.len() as u8 - 1),
        T::delay(DECODE),
    ];
    for v in values {
        t.push(T::read(*v));
        t.push(T::delay(DECODE));
    }
    t.push(T::transaction_end());
    t
}

/// The node's first chip: 1 kSPS, gain 8, all eight channels on electrodes, bias drive,
/// DC lead-off at 6 nA, clock out.
fn first_chip() -> Settings {
    Settings::try_new(
        DataRate::Sps1000,
        Gain::X8,
        [ChannelInput::Electrodes; 8],
        BiasDrive::FromUsedChannels,
        LeadOff::Dc6nA,
        ClockOutput::On,
    )
    .expect("valid")
}

/// CONFIG1 F4 = 1 (fixed), DAISY_EN 1, CLK_EN 1, 10 (fixed), DR 100 (1 kSPS).
/// CONFIG2 C0 = fixed bits only (no test signal).
/// CONFIG3 EC = PD_REFBUF, 11 (fixed), BIASREF_INT, PD_BIAS.
/// LOFF 00 = 95 %, 6 nA, DC. CHnSET 40 = powered, gain 8 (100), SRB2 open, MUX normal.
/// BIAS_SENSP/N, LOFF_SENSP/N FF, LOFF_FLIP 00; GPIO 0F, MISC1 00, MISC2 00, CONFIG4 02.
const BLOCK_A: [u8; 17] = [
    0xF4, 0xC0, 0xEC, 0x00, 0x40, 0x40, 0x40, 0x40, 0x40, 0x40, 0x40, 0x40, 0xFF, 0xFF, 0xFF, 0xFF,
    0x00,
];
const BLOCK_B: [u8; 4] = [0x0F, 0x00, 0x00, 0x02];

fn start_up_script(id: u8) -> Vec<T<u8>> {
    let mut s = command(0x06, RESET_WAIT);
    s.extend(command(0x11, DECODE));
    s.extend(rreg(0x00, &[id]));
    s
}

#[test]
fn timing_constants_meet_the_datasheet() {
    // tCLK = 1 / 2.048 MHz = 488.28 ns.
    assert!(f64::from(T_SDECODE_NS) >= 4.0 * 488.28 && T_SDECODE_NS == DECODE);
    assert!(f64::from(T_SCCS_NS) >= 4.0 * 488.28);
    assert!(f64::from(T_RESET_NS) >= 18.0 * 488.28 && T_RESET_NS == RESET_WAIT);
}

#[test]
fn start_up_byte_by_byte() {
    let mut script = start_up_script(0x3E);
    script.extend(wreg(0x01, &BLOCK_A));
    script.extend(rreg(0x01, &BLOCK_A));
    script.extend(wreg(0x14, &BLOCK_B));
    script.extend(rreg(0x14, &BLOCK_B));
    script.extend(command(0x10, DECODE));
    let mut spi = SpiMock::new(&script);
    let mut adc = Ads1299::new(spi.clone());
    assert!(adc.init(&first_chip()) == Ok(()));
    spi.done();
}

#[test]
fn second_chip_differs_only_where_it_should() {
    // 12 channels: the second chip uses channels 1..4, takes the first chip's clock and
    // leaves the bias drive to it.
    let mut inputs = [ChannelInput::PoweredDown; 8];
    inputs[..4].fill(ChannelInput::Electrodes);
    let s = Settings::try_new(
        DataRate::Sps1000,
        Gain::X8,
        inputs,
        BiasDrive::Off,
        LeadOff::Dc6nA,
        ClockOutput::Off,
    )
    .expect("valid");
    let a = s.block_a();
    // CONFIG1 D4: no CLK_EN. CONFIG3 E0: no bias buffer. CH5..8SET C1: PD, gain 8, shorted.
    let expected = [
        0xD4, 0xC0, 0xE0, 0x00, 0x40, 0x40, 0x40, 0x40, 0xC1, 0xC1, 0xC1, 0xC1, 0x00, 0x00, 0x0F,
        0x0F, 0x00,
    ];
    assert!(a == expected, "{a:02x?}");
    assert!(s.block_b() == BLOCK_B);
    assert!(s.used_mask() == 0x0F);
}

#[test]
fn no_used_channel_is_refused() {
    let r = Settings::try_new(
        DataRate::Sps1000,
        Gain::X8,
        [ChannelInput::Shorted; 8],
        BiasDrive::Off,
        LeadOff::Off,
        ClockOutput::Off,
    );
    assert!(r == Err(ads1299::SettingsError::NoChannelUsed));
}

#[test]
fn wrong_id_is_named() {
    // An ADS1298 (DEV_ID 10) answers 0x92.
    let script = start_up_script(0x92);
    let mut spi = SpiMock::new(&script);
    let mut adc = Ads1299::new(spi.clone());
    assert!(adc.init(&first_chip()) == Err(Error::WrongId { found: 0x92 }));
    spi.done();
}

#[test]
fn a_register_that_does_not_stick_is_named() {
    let mut script = start_up_script(0x3E);
    script.extend(wreg(0x01, &BLOCK_A));
    let mut back = BLOCK_A;
    back[2] = 0x60; // CONFIG3 stayed at its reset value
    script.extend(rreg(0x01, &back));
    let mut spi = SpiMock::new(&script);
    let mut adc = Ads1299::new(spi.clone());
    let r = adc.init(&first_chip());
    assert!(
        r == Err(Error::Verify {
            address: 0x03,
            wrote: 0xEC,
            read: 0x60
        }),
        "{r:?}"
    );
    spi.done();
}

#[test]
fn data_frame_and_bad_header() {
    let mut good = vec![0xC0, 0x10, 0x20]; // LOFF_STATP 0x01, LOFF_STATN 0x02
    for c in 0..8u8 {
        good.extend_from_slice(&[0x7F * (c % 2), 0xFF, c]);
    }
    good[3..6].copy_from_slice(&[0x80, 0x00, 0x00]);
    let bad = vec![0x00; 27];
    let script = [
        T::transaction_start(),
        T::read_vec(good),
        T::transaction_end(),
        T::transaction_start(),
        T::read_vec(bad),
        T::transaction_end(),
    ];
    let mut spi = SpiMock::new(&script);
    let mut adc = Ads1299::new(spi.clone());
    let f = adc.read_frame().expect("a good frame");
    assert!(f.status.loff_statp() == 0x01 && f.status.loff_statn() == 0x02);
    assert!(f.codes[0].is_saturated() && f.codes[0].get() == -0x80_0000);
    assert!(f.codes[1].get() == 0x7F_FF01 && !f.codes[1].is_saturated());
    assert!(f.codes[2].get() == 0x00_FF02);
    assert!(adc.read_frame() == Err(Error::BadHeader { first: 0x00 }));
    spi.done();
}

#[test]
fn drdy_wait_is_bounded() {
    let mut pin = PinMock::new(&[
        PinT::get(State::High),
        PinT::get(State::High),
        PinT::get(State::Low),
    ]);
    let r: Result<(), Error<ErrorKind>> = wait_drdy(&mut pin, &mut NoopDelay::new(), 1_000, 5);
    assert!(r == Ok(()));
    pin.done();
    let mut pin = PinMock::new(&[
        PinT::get(State::High),
        PinT::get(State::High),
        PinT::get(State::High),
    ]);
    let r: Result<(), Error<ErrorKind>> = wait_drdy(&mut pin, &mut NoopDelay::new(), 1_000, 3);
    assert!(r == Err(Error::DrdyTimeout));
    pin.done();
}

/// An SPI device whose every transaction fails.
struct Broken;

impl ErrorType for Broken {
    type Error = ErrorKind;
}

impl SpiDevice for Broken {
    fn transaction(&mut self, _: &mut [Operation<'_, u8>]) -> Result<(), ErrorKind> {
        Err(ErrorKind::Overrun)
    }
}

#[test]
fn spi_errors_are_named() {
    let mut adc = Ads1299::new(Broken);
    assert!(adc.init(&first_chip()) == Err(Error::Spi(ErrorKind::Overrun)));
    assert!(adc.read_frame() == Err(Error::Spi(ErrorKind::Overrun)));
    let shown = format!("{}", Error::<ErrorKind>::WrongId { found: 0x92 });
    assert!(shown.contains("0x92") && shown.contains("0x1e"), "{shown}");
    // Register commands outside 1..=17 registers are refused before any SPI traffic.
    assert!(adc.write_registers(0x01, &[0; 18]) == Err(Error::Length { len: 18 }));
    assert!(adc.read_registers(0x01, &mut []) == Err(Error::Length { len: 0 }));
}
