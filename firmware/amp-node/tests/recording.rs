//! The node core over two simulated ADS1299 serving a real 3DC recording (participant 4,
//! ../shared/data/3dc-armband-p4), with scripted lead-off, ADC saturation, a blocked CAN
//! controller, a bad status header and an SPI error. The frames go through the daemon's own
//! EMG front end (hand_dbc::emg_front), which must give back the recording's samples to the
//! LSB, with the counters, gaps and EMG_STATUS flags as scripted.
//!
//! Scaling (as tests/tests/one_path.rs): one 3DC count is taken as 1 µV; the simulated chip
//! serves `round(µV * gain * 2^23 / 4.5 V)`; the bus must then carry
//! `clamp(round(count / 2.5), -2048, 2047)` (the ADS1299's 0.067 µV LSB at gain 8 is far below
//! the 0.1 LSB margin that `count / 2.5` keeps from every rounding boundary, so the two
//! roundings cannot disagree). Bus channel `c` carries 3DC channel `c % 10`.

use std::collections::BTreeMap;
use std::path::PathBuf;

use ads1299::{Ads1299, Code, Frame, Gain, LeadOff, Status};
use ads1299_sim::SimAds1299;
use amp_node::{AmpNode, DcRemoval, NodeSettings, SampleOutcome, CHANNELS, STATUS_EVERY};
use hand_dbc::emg_front::{EmgFront, EmgFrontConfig, EmgFrontSettings, FrontSample};
use hand_dbc::messages::{AmpGain, AmpSampleRate, AmpState, EmgStatus};
use hand_dbc::CanFrame;

const GAIN: Gain = Gain::X8;
const SAMPLES: usize = 6_000;
/// Lead-off: bus channel 2 (first chip, channel 3, P side) over these periods.
const LOFF_A: std::ops::Range<usize> = 1_000..1_150;
/// Lead-off: bus channel 9 (second chip, channel 2, N side).
const LOFF_B: std::ops::Range<usize> = 2_000..2_100;
/// ADC saturation: bus channel 5 at +full scale, bus channel 10 at -full scale.
const SATURATED: std::ops::Range<usize> = 3_000..3_005;
/// The CAN controller refuses every frame.
const CAN_BLOCKED: std::ops::Range<usize> = 4_000..4_008;
/// The second chip's frame has a zeroed status word.
const BAD_HEADER: usize = 5_000;
/// The first chip's SPI transaction fails.
const SPI_ERROR: usize = 5_001;

fn data_dir() -> PathBuf {
    let d = PathBuf::from(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/data/3dc-armband-p4"
    ));
    assert!(
        d.join("P4_train_emg.npy").exists(),
        "{} is missing: this test reads the real recordings from ../shared/data",
        d.display()
    );
    d
}

/// A CAN controller that records what it sends, or refuses while `blocked`.
struct Bus {
    blocked: bool,
    now_us: u64,
    sent: Vec<(CanFrame, u64)>,
}

impl embedded_can::nb::Can for Bus {
    type Frame = CanFrame;
    type Error = embedded_can::ErrorKind;

    fn transmit(&mut self, frame: &CanFrame) -> nb::Result<Option<CanFrame>, Self::Error> {
        if self.blocked {
            return Err(nb::Error::WouldBlock);
        }
        self.sent.push((*frame, self.now_us));
        Ok(None)
    }

    fn receive(&mut self) -> nb::Result<CanFrame, Self::Error> {
        Err(nb::Error::WouldBlock)
    }
}

fn code_for_uv(uv: f64) -> Code {
    let c = (uv * f64::from(GAIN.factor()) * 8_388_608.0 / 4.5e6).round() as i32;
    Code::new(c.clamp(-0x7F_FFFF, 0x7F_FFFE)).expect("24 bit")
}

/// What the test expects of one sample period.
struct Expected {
    outcome: SampleOutcome,
    raw: [i16; CHANNELS],
    lead_off: u16,
    saturation: u16,
}

#[test]
fn node_frames_give_back_the_recording() {
    let npy = decoder::dsp::npy::read_npy(data_dir().join("P4_train_emg.npy")).expect("npy");
    assert!(
        npy.shape.len() == 2 && npy.shape[1] == 10,
        "shape {:?}",
        npy.shape
    );
    let n_rec = npy.shape[0];
    let count = |i: usize, c: usize| npy.data[i * 10 + c % 10];
    // Start 3 s before the first sample beyond the bus's +-5.12 mV, so clipping is real too.
    let spike = (0..n_rec)
        .find(|&i| (0..10).any(|c| count(i, c).abs() > 5_120.0))
        .expect("the recording has spikes beyond 5120 counts");
    let start = spike.saturating_sub(3_000).min(n_rec - SAMPLES);

    // DC-coupled: the bus must give back the recording to the LSB.
    let settings = NodeSettings::try_new(GAIN, LeadOff::Dc6nA)
        .and_then(|s| s.with_dc_removal(DcRemoval::Off))
        .expect("settings");
    let (sim_a, sim_b) = (SimAds1299::new(), SimAds1299::new());
    let mut chip_a = Ads1299::new(sim_a.clone());
    let mut chip_b = Ads1299::new(sim_b.clone());
    assert!(chip_a.init(settings.first_chip()).is_ok());
    assert!(chip_b.init(settings.second_chip()).is_ok());
    for (sim, s) in [
        (&sim_a, settings.first_chip()),
        (&sim_b, settings.second_chip()),
    ] {
        let st = sim.state();
        assert!(st.regs[0x01..0x12] == s.block_a() && st.regs[0x14..0x18] == s.block_b());
        assert!(
            st.regs[0x17] & 0x02 != 0,
            "CONFIG4.PD_LOFF_COMP: lead-off status live"
        );
        assert!(st.rdatac && st.timing_violations == 0 && st.ignored_commands == 0);
    }

    let mut node: AmpNode = AmpNode::new(&settings);
    let mut bus = Bus {
        blocked: false,
        now_us: 0,
        sent: Vec::new(),
    };
    let mut expected = Vec::with_capacity(SAMPLES);
    for i in 0..SAMPLES {
        bus.now_us = i as u64 * 1_000;
        bus.blocked = CAN_BLOCKED.contains(&i);
        let mut want = [0i16; CHANNELS];
        let mut codes = [code_for_uv(0.0); 16];
        let mut saturation = 0u16;
        for c in 0..CHANNELS {
            let uv = count(start + i, c);
            codes[c] = code_for_uv(uv);
            want[c] = (uv / 2.5).round().clamp(-2048.0, 2047.0) as i16;
            if SATURATED.contains(&i) && (c == 5 || c == 10) {
                codes[c] = if c == 5 {
                    Code::POSITIVE_FULL_SCALE
                } else {
                    Code::NEGATIVE_FULL_SCALE
                };
                want[c] = if c == 5 { 2047 } else { -2048 };
            }
            if want[c] == 2047 || want[c] == -2048 {
                saturation |= 1 << c;
            }
        }
        let loff_a: u8 = if LOFF_A.contains(&i) { 1 << 2 } else { 0 };
        let loff_b: u8 = if LOFF_B.contains(&i) { 1 << 1 } else { 0 };
        let fa = Frame {
            status: Status::new(loff_a, 0, 0),
            codes: codes[..8].try_into().expect("8"),
        };
        let mut b_codes = [code_for_uv(0.0); 8];
        b_codes[..4].copy_from_slice(&codes[8..12]);
        let fb = Frame {
            status: Status::new(0, loff_b, 0),
            codes: b_codes,
        };
        sim_a.serve(&fa);
        if i == BAD_HEADER {
            let mut bytes = fb.to_bytes();
            bytes[0] = 0x00;
            sim_b.serve_bytes(bytes);
        } else {
            sim_b.serve(&fb);
        }
        sim_a.state().fail_next = i == SPI_ERROR;
        let outcome = node.sample(&mut chip_a, &mut chip_b);
        node.drain(&mut bus);
        let read = outcome != SampleOutcome::ReadError;
        expected.push(Expected {
            outcome,
            raw: want,
            lead_off: if read {
                u16::from(loff_a) | (u16::from(loff_b) << 8)
            } else {
                0
            },
            saturation: if read { saturation } else { 0 },
        });
    }
    bus.blocked = false;
    node.drain(&mut bus);
    assert!(node.queued_frames() == 0);
    let nc = node.counters();
    let outcomes = |o| expected.iter().filter(|e| e.outcome == o).count() as u64;
    assert!(nc.periods == SAMPLES as u64 && nc.queued == outcomes(SampleOutcome::Queued));
    assert!(
        nc.dropped == outcomes(SampleOutcome::Dropped) && nc.dropped > 0,
        "{nc:?}"
    );
    assert!(
        nc.bad_headers == 1 && nc.spi_errors == 1 && nc.tx_errors == 0,
        "{nc:?}"
    );
    assert!(nc.status_dropped == 0 && node.next_counter() == SAMPLES as u8);
    // Dropped samples are whole and contiguous: the queue (12 frames = 4 samples) fills
    // while the controller refuses, then every further sample of the block is dropped, and
    // the first one after it too (it is sampled before the queue drains).
    for (i, e) in expected.iter().enumerate() {
        let dropped = e.outcome == SampleOutcome::Dropped;
        assert!(
            dropped == (CAN_BLOCKED.start + 4..=CAN_BLOCKED.end).contains(&i),
            "period {i}"
        );
    }

    // The daemon's front end.
    let front_settings = EmgFrontSettings::try_new(EmgFrontConfig::default()).expect("front");
    let mut front = EmgFront::new(&front_settings);
    let mut samples: Vec<FrontSample> = Vec::new();
    let mut statuses = Vec::new();
    for (f, t) in &bus.sent {
        if f.raw_id() == EmgStatus::ID {
            let data = f.data();
            assert!(EmgStatus::E2E.crc(data) == data[0], "status CRC");
            statuses.push(EmgStatus::decode(data).expect("status decodes"));
            continue;
        }
        front.on_frame(f, *t, &mut |s| samples.push(*s));
    }
    front.flush(&mut |s| samples.push(*s));
    let fc = front.counters();
    let lost = SAMPLES as u64 - nc.queued;
    assert!(samples.len() == SAMPLES, "{} samples out", samples.len());
    assert!(
        fc.samples_lost == lost && fc.e2e_errors == 0 && fc.gaps == 0,
        "{fc:?}"
    );
    let mut railed = 0;
    for (i, (s, e)) in samples.iter().zip(&expected).enumerate() {
        assert!(s.counter == i as u8, "period {i}: counter {}", s.counter);
        if e.outcome != SampleOutcome::Queued {
            continue;
        }
        for c in 0..CHANNELS {
            let raw = s.uv()[c] / 2.5;
            assert!(
                raw == f64::from(e.raw[c]),
                "period {i} channel {c}: bus {raw}, recording {}",
                e.raw[c]
            );
        }
        railed += e.raw.iter().filter(|&&r| r == 2047 || r == -2048).count() as u64;
    }
    assert!(
        fc.railed == railed && railed > 10,
        "railed {} vs {railed}",
        fc.railed
    );

    // EMG_STATUS every 100 periods, masks and faults over its window.
    assert!(statuses.len() == SAMPLES / usize::from(STATUS_EVERY));
    let mut seen = BTreeMap::new();
    for (k, st) in statuses.iter().enumerate() {
        let w = &expected[k * 100..(k + 1) * 100];
        let lead_off = w.iter().fold(0, |m, e| m | e.lead_off);
        let saturation = w.iter().fold(0, |m, e| m | e.saturation);
        let adc = w.iter().any(|e| e.outcome == SampleOutcome::ReadError);
        let overrun = w.iter().any(|e| e.outcome == SampleOutcome::Dropped);
        let faults = u8::from(adc) | u8::from(overrun) << 4;
        assert!(
            st.counter() == (k % 16) as u8,
            "status {k}: counter {}",
            st.counter()
        );
        assert!(st.state() == AmpState::Running && st.gain() == AmpGain::Gain8);
        assert!(st.sample_rate() == AmpSampleRate::Sr1000Hz);
        assert!(
            st.lead_off_mask() == lead_off,
            "status {k}: lead-off {:#x}",
            st.lead_off_mask()
        );
        assert!(
            st.saturation_mask() == saturation,
            "status {k}: {:#x}",
            st.saturation_mask()
        );
        assert!(
            st.faults() == faults,
            "status {k}: faults {:#x}",
            st.faults()
        );
        *seen
            .entry((lead_off != 0, saturation != 0, faults))
            .or_insert(0) += 1;
    }
    // Every scripted kind showed up in some status.
    assert!(statuses.iter().any(|s| s.lead_off_mask() == 1 << 2));
    assert!(statuses.iter().any(|s| s.lead_off_mask() == 1 << 9));
    assert!(statuses
        .iter()
        .any(|s| s.saturation_mask() & (1 << 5 | 1 << 10) == 1 << 5 | 1 << 10));
    assert!(
        statuses.iter().any(|s| s.faults() == 1) && statuses.iter().any(|s| s.faults() == 1 << 4)
    );
    assert!(seen.len() > 2, "{seen:?}");
}
