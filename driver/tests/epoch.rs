//! Issue 16 on the in-memory bus: no stale setpoint can move a finger. The real daemon loop
//! and the simulated controllers; a stale ACTIVE setpoint (old epoch, right CRC, alive counter
//! in sequence: the worst case of a frame left in a queue) is injected after a bus recovery.

mod common;

use common::Rig;
use driver::engine::Command;
use driver::safety::{DaemonState, Fault};
use hand_dbc::messages::{FingerMode, FingerSetpoint};
use hand_model::dbc::seal;
use hand_model::faults::FaultPlan;
use hand_model::finger::FingerState;
use hand_model::patient::Script;

const ONSET: u64 = 2_000_000;
const TICK: u64 = 50_000;
const FINGER: usize = 1;

/// handd's last setpoint for `f` on the bus.
fn last_setpoint(r: &Rig, f: usize) -> FingerSetpoint {
    r.seen
        .iter()
        .rev()
        .find(|(_, fr)| fr.raw_id() == FingerSetpoint::IDS[f])
        .map(|(_, fr)| FingerSetpoint::decode(fr.raw_id(), fr.data()).expect("decodes"))
        .expect("handd sent setpoints")
}

/// An ACTIVE setpoint of `epoch` for `FINGER`, with the alive counter after handd's last one
/// and the right CRC: the controller's E2E check accepts it. Its force (20 N) has the sign of
/// `velocity`: a controller moves only when they agree.
fn inject(r: &mut Rig, epoch: u16, velocity: f64) {
    let last = last_setpoint(r, FINGER);
    let force = 20.0_f64.copysign(velocity);
    let mut frame = FingerSetpoint::new(FINGER, FingerMode::Active, force, velocity, epoch)
        .expect("in range")
        .to_frame();
    let counter = (last.counter() + 1) & 0x0F;
    seal(&mut frame, FingerSetpoint::E2E[FINGER], counter, false);
    r.probe.send(&frame).expect("the bus is on");
}

fn angle(r: &Rig) -> f64 {
    r.world
        .fingers()
        .nth(FINGER)
        .expect("finger")
        .physics()
        .angle_rad
}

fn ignored(r: &Rig) -> u64 {
    r.world
        .fingers()
        .nth(FINGER)
        .expect("finger")
        .epoch_gate()
        .ignored()
}

/// After the bus comes back: a stale frame of `old` leaves the finger where it is and is
/// counted; the same frame in the current epoch moves it (the control).
fn stale_is_ignored_and_current_moves(r: &mut Rig, old: u16) {
    let current = r.runner.engine().epoch(FINGER);
    assert_ne!(
        current, old,
        "handd came back in the epoch of before the bus-off"
    );
    // Just after a tick: the counter of handd's last frame is the controller's last one.
    let t = r.clock_now().div_ceil(TICK) * TICK + 1_000;
    r.run_until(t);
    let (p0, n0) = (angle(r), ignored(r));
    let v = if p0 < 0.8 { 4.0 } else { -4.0 };
    inject(r, old, v);
    r.run_until(t + 40_000);
    assert_eq!(angle(r), p0, "a stale ACTIVE setpoint moved the finger");
    assert_eq!(
        ignored(r),
        n0 + 1,
        "the controller counts the stale frame it ignored"
    );
    // The stale frame was a second sender in handd's stream: handd's next frame repeats its
    // counter, and Profile 1's sync counter holds back the two after it (150 ms without a
    // trusted setpoint), so the controller brakes by itself and retires handd's epoch too;
    // handd's safe stops then bind a new one. The control goes in the epoch the controller
    // follows once handd's stream is trusted again.
    let settled = (t + 1_000_000).div_ceil(TICK) * TICK + 1_000;
    r.run_until(settled);
    let current = r.runner.engine().epoch(FINGER);
    let gate = r.world.fingers().nth(FINGER).expect("finger").epoch_gate();
    assert_eq!(
        gate.bound(),
        Some(current),
        "the controller follows handd's epoch"
    );
    let p0 = angle(r);
    let v = if p0 < 0.8 { 4.0 } else { -4.0 };
    inject(r, current, v);
    r.run_until(settled + 40_000);
    let moved = (angle(r) - p0).abs();
    println!("stale frame ignored; the control in epoch {current:#06x} moved {moved:.3} rad");
    assert!(
        moved > 0.02,
        "the control moved the finger only {moved} rad"
    );
}

#[test]
fn a_stale_setpoint_after_a_short_bus_off_does_not_move_the_finger() {
    let mut r = Rig::new(FaultPlan::new(), Script::resting(20_000_000));
    r.run_until(ONSET);
    assert_eq!(r.runner.engine().state(), DaemonState::Running);
    let old = r.runner.engine().epoch(FINGER);
    assert_eq!(
        last_setpoint(&r, FINGER).epoch(),
        old,
        "setpoints carry the epoch"
    );
    // 60 ms off: the controllers do not brake by themselves (150 ms), so they are still bound
    // to the old epoch when the bus comes back; the new epoch's safe stops rebind them.
    r.bus.set_bus_off(true);
    r.run_until(ONSET + 60_000);
    r.bus.set_bus_off(false);
    // The first safe stop after the gap resynchronises the E2E counter (frames lost in the
    // bus-off took their counters); the next one, at the tick after, binds the new epoch.
    r.run_until(ONSET + 2 * TICK + 1_000);
    let f = r.world.fingers().nth(FINGER).expect("finger");
    assert_eq!(f.epoch_gate().retired(), Some(old), "old epoch retired");
    assert_eq!(
        f.epoch_gate().bound(),
        Some(r.runner.engine().epoch(FINGER))
    );
    stale_is_ignored_and_current_moves(&mut r, old);
}

#[test]
fn a_stale_setpoint_after_a_long_bus_off_does_not_move_the_finger_and_arm_resumes() {
    let mut r = Rig::new(FaultPlan::new(), Script::resting(20_000_000));
    r.run_until(ONSET);
    let old = r.runner.engine().epoch(FINGER);
    // 500 ms off: every controller brakes by itself and retires the old epoch.
    r.bus.set_bus_off(true);
    r.run_until(ONSET + 500_000);
    r.bus.set_bus_off(false);
    r.run_until(ONSET + 700_000);
    stale_is_ignored_and_current_moves(&mut r, old);
    // The probe that injected those frames is a second master: handd, which reads every
    // FINGER_SETPOINT on the bus, latched it (issue 32). Arm once handd has read the last one
    // (it reads a tick's frames at the tick).
    r.run_until(r.clock_now() + TICK);
    assert!(
        r.runner.engine().faults().contains(Fault::SecondMaster),
        "{}",
        r.runner.engine().faults()
    );
    // Armed, handd runs again in its epoch and every finger follows it.
    let now = r.clock_now();
    r.runner.engine_mut().command(now, Command::Arm).unwrap();
    r.run_until(now + 1_000_000);
    assert_eq!(
        r.runner.engine().state(),
        DaemonState::Running,
        "{}",
        r.runner.engine().faults()
    );
    for f in r.world.fingers() {
        assert_eq!(f.state(), FingerState::Active, "finger {}", f.finger());
    }
}

#[test]
fn after_a_stall_that_brakes_the_controllers_handd_reopens_them_in_a_new_epoch() {
    let mut r = Rig::new(FaultPlan::new(), Script::resting(20_000_000));
    r.run_until(ONSET);
    assert_eq!(r.runner.engine().state(), DaemonState::Running);
    let begun = r.runner.engine().epochs_begun(FINGER);
    // handd stalls 300 ms (no bus fault): the world runs on, the controllers brake by
    // themselves and retire handd's epoch.
    let mut now = r.clock_now();
    while now < ONSET + 300_000 {
        now += 1_000;
        r.clock.set_us(now);
        r.world.step(now);
    }
    assert!(r.world.fingers().all(|f| f.state() == FingerState::Braked));
    // Samples were lost in the stall: SAFE until the signal is good for 500 ms again.
    r.run_until(ONSET + 1_500_000);
    assert_eq!(r.runner.engine().state(), DaemonState::Running);
    assert!(
        r.runner.engine().epochs_begun(FINGER) > begun,
        "the controllers' self-brake reports start a new epoch"
    );
    for f in r.world.fingers() {
        assert_eq!(
            f.state(),
            FingerState::Active,
            "finger {} again",
            f.finger()
        );
        assert_eq!(
            f.epoch_gate().bound(),
            Some(r.runner.engine().epoch(f.finger()))
        );
    }
}
