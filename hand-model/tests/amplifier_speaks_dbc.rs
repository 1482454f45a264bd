//! The amplifier's frames are what hand.dbc says: hand-dbc's own reassembler rebuilds the
//! synthesiser's samples bit for bit, every E2E check passes, and the ADC range is the DBC's.

mod common;

use common::Harness;
use hand_dbc::e2e::{E2eChecker, E2eStatus};
use hand_dbc::emg::{EmgAssembler, EmgConfig, EmgFrame, EMG_LSB_UV};
use hand_dbc::messages::{EmgSamplesG0, EmgSamplesG1, EmgSamplesG2, EmgStatus};
use hand_model::emg::{ChannelFaults, EmgSynth, ADC_MAX, ADC_MIN};
use hand_model::faults::{Fault, FaultPlan};
use hand_model::nodes::{AmplifierNode, AmplifierNodeConfig};
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
    // The same synthesiser, driven directly, gives the same counts.
    let cfg = AmplifierNodeConfig::default();
    let mut synth = EmgSynth::try_new(cfg.signal.clone()).expect("valid");
    let act = cfg.drive.activation(&intent);
    for (k, got) in samples.iter().enumerate() {
        let want = synth.next_sample(&act, ChannelFaults::default()).counts;
        assert_eq!(*got, want, "sample {k}");
    }
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
    // EMG_STATUS at 10 Hz: at 0, 100, ..., 900 ms.
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
