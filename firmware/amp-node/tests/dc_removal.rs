//! The electrodes' DC offset on the bus: a 40 mV offset (a pair of gel electrodes easily has
//! that) rails every channel of a DC-coupled node, and the reference node takes it out before
//! the bus's +-5.12 mV, the sEMG on it intact.

use ads1299::{Code, Frame, Gain, LeadOff, Status};
use ads1299_sim::TakeAll;
use amp_node::{
    AmpNode, BusScale, DcRemoval, NodeSettings, NodeSettingsError, SampleOutcome, CHANNELS,
};
use hand_dbc::emg::EmgFrame;
use hand_dbc::messages::EmgStatus;
use hand_dbc::CanFrame;

/// Runs `ms` samples of a 200 µV, 80 Hz sine on every channel with a 40 mV offset from 100 ms
/// on (it settles under one LSB in 0.62 s with the reference's shift 6); returns the
/// bus values of the last 500 ms (per channel, largest |value|) and the saturation masks of
/// the statuses in them.
fn run(dc: DcRemoval, ms: usize) -> ([i16; CHANNELS], Vec<u16>) {
    let settings = NodeSettings::try_new(Gain::X8, LeadOff::Dc6nA)
        .and_then(|s| s.with_dc_removal(dc))
        .expect("settings");
    let per_code = BusScale::new(Gain::X8).uv_per_code();
    let mut node: AmpNode = AmpNode::new(&settings);
    let mut bus: TakeAll<CanFrame> = TakeAll::default();
    let mut largest = [0i16; CHANNELS];
    let mut masks = Vec::new();
    for n in 0..ms {
        let t = n as f64 / 1000.0;
        // The offset appears 100 ms in (an electrode's contact made).
        let offset = if n < 100 { 0.0 } else { 40_000.0 };
        let uv = offset + 200.0 * (std::f64::consts::TAU * 80.0 * t).sin();
        let code = Code::new((uv / per_code).round() as i32).expect("24 bit");
        let frame = Frame {
            status: Status::new(0, 0, 0),
            codes: [code; 8],
        };
        assert!(node.on_frames(&frame, &frame) == SampleOutcome::Queued);
        bus.0.clear();
        node.drain(&mut bus);
        for f in &bus.0 {
            if let Ok(Some(e)) = EmgFrame::decode(f.raw_id(), f.data()) {
                for (k, v) in e.raw().iter().enumerate() {
                    let c = 4 * usize::from(e.group()) + k;
                    if n + 500 >= ms {
                        largest[c] = largest[c].max(v.abs());
                    }
                }
            }
            if f.raw_id() == EmgStatus::ID && n + 500 >= ms {
                masks.push(
                    EmgStatus::decode(f.data())
                        .expect("status")
                        .saturation_mask(),
                );
            }
        }
    }
    (largest, masks)
}

#[test]
fn the_reference_node_takes_an_electrode_offset_off_the_bus() {
    let (coupled, masks) = run(DcRemoval::Off, 1_500);
    assert!(coupled.iter().all(|&v| v == 2047), "{coupled:?}");
    assert!(
        masks.len() == 5 && masks.iter().all(|&m| m == 0x0FFF),
        "{masks:x?}"
    );
    let (blocked, masks) = run(DcRemoval::REFERENCE, 1_500);
    // 200 µV is 80 LSB; the blocker's gain at 80 Hz is within 1 % of one.
    assert!(
        blocked.iter().all(|&v| (78..=82).contains(&v)),
        "{blocked:?}"
    );
    assert!(
        masks.len() == 5 && masks.iter().all(|&m| m == 0),
        "{masks:x?}"
    );
}

#[test]
fn shifts_outside_the_range_are_refused() {
    let s = NodeSettings::try_new(Gain::X8, LeadOff::Dc6nA).expect("settings");
    assert!(s.dc_removal() == DcRemoval::REFERENCE);
    for shift in [0, 3, 13, 255] {
        assert!(
            s.with_dc_removal(DcRemoval::HighPass { shift })
                == Err(NodeSettingsError::DcShift { shift })
        );
    }
    assert!(s.with_dc_removal(DcRemoval::HighPass { shift: 12 }).is_ok());
}
