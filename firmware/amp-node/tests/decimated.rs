//! The node at 2 kSPS: the chips at DR 2 kSPS, every pair of conversions one bus sample
//! through the decimating FIR, the bus still at 1 kHz (EMG_STATUS says 1000 Hz); a failed read
//! costs that pair's sample and nothing else.

use ads1299::{Code, Frame, Gain, LeadOff, Status};
use amp_node::{AmpNode, BusScale, DcRemoval, NodeRate, NodeSettings, SampleOutcome, TAPS};
use hand_dbc::CanFrame;
use hand_dbc_core::emg::EmgFrame;

/// A controller that takes every frame.
#[derive(Default)]
struct Sink {
    sent: Vec<CanFrame>,
}

impl embedded_can::nb::Can for Sink {
    type Frame = CanFrame;
    type Error = embedded_can::ErrorKind;

    fn transmit(&mut self, frame: &CanFrame) -> nb::Result<Option<CanFrame>, Self::Error> {
        self.sent.push(*frame);
        Ok(None)
    }

    fn receive(&mut self) -> nb::Result<CanFrame, Self::Error> {
        Err(nb::Error::WouldBlock)
    }
}

fn frame(v: i32) -> Frame {
    Frame {
        status: Status::new(0, 0, 0),
        codes: [Code::new(v).expect("24 bit"); 8],
    }
}

fn settings(rate: NodeRate) -> NodeSettings {
    // DC-coupled: these tests compare the bus with the chips' codes to the LSB.
    NodeSettings::try_with_rate(rate, Gain::X8, LeadOff::Dc6nA)
        .and_then(|s| s.with_dc_removal(DcRemoval::Off))
        .expect("settings")
}

/// Group 0's (counter, channel 0) of every EMG frame sent.
fn channel0(sent: &[CanFrame]) -> Vec<(u8, i16)> {
    sent.iter()
        .filter_map(|f| EmgFrame::decode(f.raw_id(), f.data()).ok().flatten())
        .filter(|e| e.group() == 0)
        .map(|e| (e.counter(), e.raw()[0]))
        .collect()
}

#[test]
fn the_chips_run_at_2_ksps_and_the_bus_at_1_khz() {
    let s = settings(NodeRate::Sps2000Decimated);
    for chip in [s.first_chip(), s.second_chip()] {
        assert_eq!(chip.data_rate(), ads1299::DataRate::Sps2000);
    }
    // CONFIG1 (SBAS499C, "CONFIG1: Configuration Register 1"): DR[2:0] = 011 for 2 kSPS;
    // the first chip drives CLK.
    assert_eq!(s.first_chip().block_a()[0], 0xF3);
    assert_eq!(s.second_chip().block_a()[0], 0xD3);
    assert_eq!(
        settings(NodeRate::Sps1000).first_chip().data_rate(),
        ads1299::DataRate::Sps1000
    );
    assert_eq!(
        s.amp_sample_rate(),
        hand_dbc_core::messages::AmpSampleRate::Sr1000Hz
    );
}

#[test]
fn every_pair_of_conversions_is_one_sample_and_a_constant_comes_through_exactly() {
    // 1 mV at gain 8: code = 1000 uV * 8 * 2^23 / 4.5 V.
    let code = (1_000.0 * 8.0 * f64::from(1 << 23) / 4.5e6).round() as i32;
    let want = BusScale::new(Gain::X8).to_bus(Code::new(code).unwrap()).raw;
    let mut node: AmpNode = AmpNode::new(&settings(NodeRate::Sps2000Decimated));
    let mut bus = Sink::default();
    let mut outcomes = Vec::new();
    for _ in 0..400 {
        outcomes.push(node.on_frames(&frame(code), &frame(code)));
        node.drain(&mut bus);
    }
    for pair in outcomes.chunks(2) {
        assert_eq!(pair, [SampleOutcome::Filtering, SampleOutcome::Queued]);
    }
    let c = node.counters();
    assert!(
        c.conversions == 400 && c.periods == 200 && c.queued == 200,
        "{c:?}"
    );
    let got = channel0(&bus.sent);
    assert_eq!(got.len(), 200);
    // Counters in step, one per bus sample; after the FIR filled (TAPS conversions), exact.
    for (i, (counter, _)) in got.iter().enumerate() {
        assert_eq!(*counter, i as u8);
    }
    assert!(
        got[TAPS / 2 + 1..].iter().all(|&(_, v)| v == want),
        "want {want}: {got:?}"
    );
}

#[test]
fn what_would_alias_is_stopped_before_the_bus() {
    // 2 mV at 800 Hz, converted at 2 kSPS: at 1 kSPS it would alias to 200 Hz, in the band.
    let amp = 2_000.0 * 8.0 * f64::from(1 << 23) / 4.5e6;
    let mut node: AmpNode = AmpNode::new(&settings(NodeRate::Sps2000Decimated));
    let mut bus = Sink::default();
    for n in 0..2_000 {
        let x = amp * (2.0 * std::f64::consts::PI * 800.0 * f64::from(n) / 2_000.0).sin();
        node.on_frames(&frame(x.round() as i32), &frame(x.round() as i32));
        node.drain(&mut bus);
    }
    let got = channel0(&bus.sent);
    // 2 mV is 800 LSB on the bus; -60 dB leaves under one LSB.
    let worst = got[TAPS..].iter().map(|&(_, v)| v.abs()).max().unwrap();
    assert!(worst <= 1, "800 Hz leaks {worst} LSB onto the bus");
}

#[test]
fn a_failed_read_costs_its_pairs_sample_only() {
    let mut node: AmpNode = AmpNode::new(&settings(NodeRate::Sps2000Decimated));
    let mut bus = Sink::default();
    let mut outcomes = Vec::new();
    for n in 0..40 {
        let o = if n == 10 || n == 21 {
            // The first of pair 5, the second of pair 10.
            node.on_read_error()
        } else {
            node.on_frames(&frame(1_000), &frame(1_000))
        };
        outcomes.push(o);
        node.drain(&mut bus);
    }
    assert_eq!(outcomes[10], SampleOutcome::ReadError);
    assert_eq!(
        outcomes[11],
        SampleOutcome::ReadError,
        "pair 5 has no sample"
    );
    assert_eq!(outcomes[20], SampleOutcome::Filtering);
    assert_eq!(
        outcomes[21],
        SampleOutcome::ReadError,
        "pair 10 has no sample"
    );
    let c = node.counters();
    assert!(
        c.conversions == 40 && c.periods == 20 && c.queued == 18,
        "{c:?}"
    );
    let counters: Vec<u8> = channel0(&bus.sent).iter().map(|&(c, _)| c).collect();
    let want: Vec<u8> = (0..20).filter(|&p| p != 5 && p != 10).collect();
    assert_eq!(counters, want, "the counter jumps over the lost samples");
}
