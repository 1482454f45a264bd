//! The amplifier's frames are what hand.dbc says: hand-dbc's own reassembler rebuilds the
//! synthesiser's samples bit for bit, every E2E check passes, and the ADC range is the DBC's.

mod common;

use amp_node::{BusScale, DcBlock, DcRemoval};
use common::Harness;
use hand_dbc::e2e::{E2eChecker, E2eStatus};
use hand_dbc::emg::{EmgAssembler, EmgConfig, EmgFrame, EMG_LSB_UV};
use hand_dbc::messages::{EmgSamplesG0, EmgSamplesG1, EmgSamplesG2, EmgStatus};
use hand_model::emg::{ChannelFaults, EmgSynth, ADC_MAX, ADC_MIN};
use hand_model::faults::{Fault, FaultPlan};
use hand_model::nodes::amp_board::BOARD_GAIN;
use hand_model::nodes::{AmpBoard, AmplifierNode, AmplifierNodeConfig};
use hand_model::patient::Intent;

#[test]
fn adc_range_and_lsb_are_the_dbc_ones() {
    assert_eq!(f64::from(ADC_MIN) * EMG_LSB_UV, EmgSamplesG0::EMG0_MIN);
    assert_eq!(f64::from(ADC_MAX) * EMG_LSB_UV, EmgSamplesG0::EMG0_MAX);
    assert_eq!(AmplifierNodeConfig::default().signal.lsb_uv, EMG_LSB_UV);
}

/// Runs the amplifier for `ms` ms with `plan`, returns the harness.
fn run(plan: FaultPlan, intent: Intent, ms: u64) -> Harness {
    let mut h = Harness::new();
    let mut ep = h.bus.endpoint();
    let mut amp = AmplifierNode::try_new(AmplifierNodeConfig::default()).expect("valid");
    amp.set_faults(plan);
    amp.set_intent(intent);
    h.run(ms * 1000, |t| amp.poll(t, &mut ep));
    h
}

fn reassemble(h: &Harness) -> (Vec<[i16; 12]>, EmgAssembler) {
    let mut asm = EmgAssembler::try_new(EmgConfig::default()).expect("valid");
    let mut out = Vec::new();
    for r in &h.log {
        if let Ok(Some(f)) = EmgFrame::decode(r.frame.raw_id(), r.frame.data()) {
            asm.push(&f, r.time_us.expect("clock"), &mut |s| out.push(s.raw));
        }
    }
    asm.flush(&mut |s| out.push(s.raw));
    (out, asm)
}

#[test]
fn hand_dbc_reassembles_the_synthesised_samples_bit_for_bit() {
    let intent = Intent::finger(1, 0.6);
    let h = run(FaultPlan::new(), intent, 999);
    let (samples, asm) = reassemble(&h);
    assert_eq!(samples.len(), 1000);
    assert_eq!(asm.stats().lost_frames, 0);
    // The same synthesiser, driven directly, through the chip's code, the firmware's DC
    // blocker and scale gives the same counts; the same DC blocker in f64 on the µV, rounded
    // once to the bus's LSB, differs from them by at most one LSB, on few values.
    let cfg = AmplifierNodeConfig::default();
    let mut synth = EmgSynth::try_new(cfg.signal.clone()).expect("valid");
    let act = cfg.drive.activation(&intent);
    let scale = BusScale::new(BOARD_GAIN);
    let DcRemoval::HighPass { shift } = DcRemoval::REFERENCE else {
        panic!("the reference removes DC")
    };
    let mut block = DcBlock::<12>::new(shift);
    let mut dc: Option<[f64; 12]> = None;
    let mut uv = [0.0; 12];
    let mut differ = 0;
    for (k, got) in samples.iter().enumerate() {
        synth.next_uv(&act, ChannelFaults::default(), &mut uv);
        let codes = uv.map(AmpBoard::code);
        let want = block.to_bus(&codes, scale).map(|v| v.raw);
        assert_eq!(*got, want, "sample {k}");
        let d = dc.get_or_insert(uv);
        for c in 0..12 {
            let float = ((uv[c] - d[c]) / EMG_LSB_UV).round() as i16;
            d[c] += (uv[c] - d[c]) / f64::from(1u32 << shift);
            assert!(
                (got[c] - float).abs() <= 1,
                "sample {k}: {} against {float}",
                got[c]
            );
            differ += usize::from(got[c] != float);
        }
    }
    println!("{differ} of 12,000 values one LSB off the f64 reference");
    assert!(
        differ < 12_000 / 20,
        "{differ} values off the f64 reference"
    );
    // Every frame passes its E2E check in sequence.
    for (id, profile) in [
        (EmgSamplesG0::ID, EmgSamplesG0::E2E),
        (EmgSamplesG1::ID, EmgSamplesG1::E2E),
        (EmgSamplesG2::ID, EmgSamplesG2::E2E),
        (EmgStatus::ID, EmgStatus::E2E),
    ] {
        let mut checker = E2eChecker::try_new(profile, 1).expect("valid");
        let frames = h.with_id(id);
        assert!(!frames.is_empty());
        for (t, f) in frames {
            assert_eq!(
                checker.check_frame(Some(&f)),
                E2eStatus::Ok,
                "id {id:#x} at {t}"
            );
        }
    }
    // EMG_STATUS at 10 Hz, after every 100th sample: at 99, 199, ..., 999 ms.
    assert_eq!(h.with_id(EmgStatus::ID).len(), 10);
}

#[test]
fn dropped_frames_are_counted_as_lost_by_the_reassembler() {
    let mut plan = FaultPlan::new();
    plan.add(Fault::DropEmgFrames { every: 7 }, 100_000, 200_000)
        .expect("valid");
    let h = run(plan, Intent::REST, 299);
    let (samples, asm) = reassemble(&h);
    assert_eq!(samples.len(), 300, "lost frames are bridged, not skipped");
    // Frames 301..=600 are in the window (3 per sample from sample 100): every 7th of them.
    let dropped = (301..=600u64).filter(|n| n % 7 == 0).count() as u64;
    assert_eq!(asm.stats().lost_frames, dropped);
}

/// A stalled simulator (a poll 400 ms late) skips the backlog through the node core: the
/// sample counter jumps over it, the statuses that fell due are sent, and each whose periods
/// were missed says samples were dropped in the amplifier (Faults bit 4); nothing stale
/// reaches the bus.
#[test]
fn a_stalled_simulator_skips_its_backlog_as_the_node_reports_it() {
    let mut h = Harness::new();
    let mut ep = h.bus.endpoint();
    let mut amp = AmplifierNode::try_new(AmplifierNodeConfig::default()).expect("valid");
    let mut polls = 0;
    h.run(700_000, |t| {
        // Polled every ms but from 200 to 600 ms, when the process stood still.
        if !(200_000..600_000).contains(&t) {
            polls += 1;
            amp.poll(t, &mut ep);
        }
    });
    assert!(polls > 0 && amp.samples_dropped() > 0);
    let (samples, asm) = reassemble(&h);
    let skipped = amp.samples_dropped();
    assert_eq!(skipped, 400, "the samples due from 200 to 599 ms");
    assert_eq!(amp.board().counters().missed, skipped);
    assert_eq!(samples.len() as u64 + skipped, 701);
    assert!(
        asm.stats().lost_frames > 0 || asm.stats().gaps > 0,
        "{:?}",
        asm.stats()
    );
    let statuses: Vec<EmgStatus> = h
        .with_id(EmgStatus::ID)
        .into_iter()
        .map(|(_, f)| EmgStatus::decode(f.data()).expect("valid"))
        .collect();
    assert_eq!(statuses.len(), 7, "every 100 periods, missed or not");
    let flagged: Vec<bool> = statuses.iter().map(|s| s.faults() & 0x10 != 0).collect();
    assert_eq!(
        flagged,
        [false, false, true, true, true, true, false],
        "the statuses due at periods 300 to 600 cover the stall"
    );
}
