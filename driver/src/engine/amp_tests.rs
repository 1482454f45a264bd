//! Issue 32 item 8: the amplifier's own status decides whether its samples may drive the hand.

use hand_dbc::e2e::E2eProtector;
use hand_dbc::messages::{AmpGain, AmpSampleRate, AmpState, EmgStatus};

use super::rx::{amp_problem, AmpProblem, AMP_STATUS_SILENCE_US};
use super::Engine;
use crate::safety::Fault;

fn status(state: AmpState, rate: AmpSampleRate, faults: u8) -> EmgStatus {
    EmgStatus::new(state, rate, AmpGain::Gain1, 0, 0, faults).expect("in range")
}

#[test]
fn init_another_rate_and_a_fault_bit_are_named_an_overrun_is_not() {
    let ok = status(AmpState::Running, AmpSampleRate::Sr1000Hz, 0);
    assert_eq!(amp_problem(&ok, 1000), None);
    let init = status(AmpState::Init, AmpSampleRate::Sr1000Hz, 0);
    assert_eq!(
        amp_problem(&init, 1000),
        Some(AmpProblem::State(AmpState::Init))
    );
    let slow = status(AmpState::Running, AmpSampleRate::Sr500Hz, 0);
    let p = amp_problem(&slow, 1000).expect("a rate mismatch");
    assert_eq!(
        p.to_string(),
        "the amplifier samples at 500 Hz, the signal chain runs at 1000 Hz"
    );
    let adc = status(AmpState::Running, AmpSampleRate::Sr1000Hz, 0x01);
    assert_eq!(amp_problem(&adc, 1000), Some(AmpProblem::Fault(0x01)));
    let overrun = status(AmpState::Running, AmpSampleRate::Sr1000Hz, 0x10);
    assert_eq!(
        amp_problem(&overrun, 1000),
        None,
        "a transmit overrun is counted, not a fault"
    );
}

fn engine() -> Engine {
    super::test_support::validated_engine(1)
}

#[test]
fn an_amplifier_at_another_rate_or_with_a_silent_status_raises_signal_quality() {
    let mut e = engine();
    let mut p = E2eProtector::new(EmgStatus::E2E);
    let mut send = |e: &mut Engine, at: u64, st: EmgStatus| {
        let frame = p.protect_message(&st).expect("protects");
        e.on_frame(&frame, at);
    };
    send(
        &mut e,
        10_000,
        status(AmpState::Running, AmpSampleRate::Sr2000Hz, 0),
    );
    assert!(matches!(
        e.amp_problem(),
        Some(AmpProblem::Rate {
            amplifier_hz: 2000,
            ..
        })
    ));
    e.evaluate_faults(50_000);
    assert!(e.faults().contains(Fault::SignalQuality), "{}", e.faults());
    // A good status clears the problem; then the status falls silent.
    send(
        &mut e,
        100_000,
        status(AmpState::Running, AmpSampleRate::Sr1000Hz, 0),
    );
    assert_eq!(e.amp_problem(), None);
    e.evaluate_faults(100_000 + AMP_STATUS_SILENCE_US);
    assert_eq!(e.amp_problem(), None, "not silent yet at exactly the limit");
    e.evaluate_faults(100_000 + AMP_STATUS_SILENCE_US + 50_000);
    assert_eq!(e.amp_problem(), Some(AmpProblem::Silent));
}
