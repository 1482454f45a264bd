//! Issue 32, item 2 on the in-memory bus: a FINGER_SETPOINT that handd reads was sent by
//! another node (SocketCAN, like the in-memory bus, does not loop a socket's own frames back),
//! so the hand goes SAFE within a tick and stays there until `arm`.

mod common;

use common::Rig;
use driver::engine::Command;
use driver::safety::{DaemonState, Fault};
use hand_dbc::messages::{FingerMode, FingerSetpoint};
use hand_model::dbc::seal;
use hand_model::faults::FaultPlan;
use hand_model::patient::Script;

const ONSET: u64 = 2_000_000;
const TICK: u64 = 50_000;

#[test]
fn a_second_setpoint_sender_sends_the_hand_safe_within_a_tick_until_armed() {
    let mut r = Rig::new(FaultPlan::new(), Script::resting(20_000_000));
    r.run_until(ONSET);
    assert_eq!(r.runner.engine().state(), DaemonState::Running);
    assert!(!r.runner.engine().faults().contains(Fault::SecondMaster));
    // A well-formed setpoint of handd's own current epoch, right CRC: only its sender is wrong.
    let f = 2;
    let epoch = r.runner.engine().epoch(f);
    let mut frame = FingerSetpoint::new(f, FingerMode::Hold, 5.0, 0.0, epoch)
        .expect("in range")
        .to_frame();
    seal(&mut frame, FingerSetpoint::E2E[f], 3, false);
    let sent = r.clock_now();
    r.probe.send(&frame).expect("the bus is on");
    r.run_until(sent + TICK);
    let e = r.runner.engine();
    assert_eq!(e.state(), DaemonState::Safe, "{}", e.faults());
    assert!(e.faults().contains(Fault::SecondMaster), "{}", e.faults());
    let stopped = r
        .stopped_from(sent, sent + TICK, None)
        .expect("handd sent setpoints in the tick");
    assert!(
        stopped <= sent + TICK,
        "every finger stopped at {stopped} µs, frame at {sent} µs"
    );
    // Latched: still SAFE a second later, with nothing else wrong.
    r.run_until(sent + 1_000_000);
    assert_eq!(r.runner.engine().state(), DaemonState::Safe);
    assert!(r.runner.engine().faults().contains(Fault::SecondMaster));
    // A technician's arm clears it; the hand runs again after the recovery time.
    let now = r.clock_now();
    r.runner
        .engine_mut()
        .command(now, Command::Arm)
        .expect("arm");
    r.run_until(now + 1_000_000);
    assert_eq!(r.runner.engine().state(), DaemonState::Running);
    assert!(!r.runner.engine().faults().contains(Fault::SecondMaster));
}
