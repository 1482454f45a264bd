//! Issue 31 on the in-memory bus: the real daemon loop with a model trained on a simulated
//! calibration, the simulated patient and finger controllers.
//! - A grip, then rest: under the shipped law the finger's velocity setpoint is back at rest
//!   within a stated time and the finger does not run on into its stop; under the paper's law
//!   (the control) the velocity stays wound up.
//! - One finger's controller brakes by itself in the middle of a power grip: only that finger
//!   is reopened (a new epoch, a SAFE_STOP); the other four keep their epoch, stay ACTIVE and
//!   keep their force.

mod common;

use common::Rig;
use decoder::model::Predictor;
use driver::engine::Command;
use hand_dbc::messages::FingerMode;
use hand_model::faults::{Fault, FaultPlan};
use hand_model::patient::{Intent, Script};
use hand_model::world::PatientMode;

const FINGER: usize = 1;
const GRIP_FROM: u64 = 1_500_000;
const GRIP_US: u64 = 400_000;
const REST_FROM: u64 = GRIP_FROM + GRIP_US;
const END: u64 = REST_FROM + 3_000_000;
/// The bar: from the end of the grip, the patient's muscles relax (the simulated reaction),
/// the 200 ms window empties, the label falls inside the deadband, and ω decays at the rest
/// damping (10/s: 1/e in 100 ms): the velocity setpoint is below `STILL` within 1.2 s.
const STOP_BAR_US: u64 = 1_200_000;
/// A velocity setpoint this small moves a finger less than 1 degree a second.
const STILL: f64 = 0.0175;

fn model() -> Predictor {
    common::calibrated_predictor()
}

fn rig(script: Script, faults: FaultPlan, paper: bool) -> Rig {
    let mut r = Rig::with_predictor(faults, PatientMode::Script(script), model());
    if paper {
        for f in 0..5 {
            let g = r.runner.engine().gains()[f].paper_law();
            r.runner
                .engine_mut()
                .command(0, Command::SetGains(f, g))
                .expect("gains");
        }
    }
    r
}

/// The velocity setpoints of `finger` from `from` on, and the first time from which every one
/// is below `STILL`.
fn still_from(r: &Rig, finger: usize, from: u64) -> (Option<u64>, f64) {
    let v: Vec<(u64, f64)> = r
        .setpoints()
        .into_iter()
        .filter(|s| s.1 == finger && s.0 >= from)
        .map(|s| (s.0, s.4))
        .collect();
    let last = v.last().map_or(0.0, |s| s.1);
    let moving = v.iter().rposition(|s| s.1.abs() >= STILL);
    let t = match moving {
        None => v.first().map(|s| s.0),
        Some(i) => v.get(i + 1).map(|s| s.0),
    };
    (t, last)
}

/// (still from, last velocity setpoint, peak angle after the grip, angle at the end, impacts
/// into a joint stop).
fn grip_then_rest(paper: bool) -> (Option<u64>, f64, f64, f64, u64) {
    let mut script = Script::new();
    script
        .rest(GRIP_FROM)
        .hold(Intent::finger(FINGER, 0.7), GRIP_US)
        .rest(END - REST_FROM);
    let mut r = rig(script, FaultPlan::new(), paper);
    let mut peak = 0.0f64;
    let mut at_rest_end = 0.0;
    let mut t = 0;
    while t < END {
        t += 10_000;
        r.run_until(t);
        let a = r
            .world
            .fingers()
            .nth(FINGER)
            .expect("finger")
            .physics()
            .angle_rad;
        if t >= REST_FROM {
            peak = peak.max(a);
        }
        at_rest_end = a;
    }
    let peak_v = r
        .setpoints()
        .iter()
        .filter(|s| s.1 == FINGER && s.0 < REST_FROM + 500_000)
        .map(|s| s.4.abs())
        .fold(0.0, f64::max);
    let (still, last) = still_from(&r, FINGER, REST_FROM);
    let impacts = r
        .world
        .fingers()
        .nth(FINGER)
        .expect("finger")
        .motion_stats()
        .impacts;
    let law = if paper { "paper" } else { "shipped" };
    println!(
        "{law} law: peak velocity setpoint {peak_v:.2} rad/s; still (|v| < {STILL}) {} ms after \
         the grip; last velocity {last:.3} rad/s; angle after the grip: peak {peak:.3} rad, at \
         the end {at_rest_end:.3} rad; {impacts} impacts into a stop",
        still.map_or("never".into(), |t| format!("{}", (t - REST_FROM) / 1000))
    );
    assert!(
        peak_v > 0.2,
        "{law}: the grip did not move the finger ({peak_v} rad/s)"
    );
    (still, last, peak, at_rest_end, impacts)
}

#[test]
fn after_a_grip_the_finger_stops_at_rest_and_does_not_run_into_its_stop() {
    let (still, _, peak, end, impacts) = grip_then_rest(false);
    let still = still.expect("the velocity setpoint never came back to rest");
    assert!(
        still - REST_FROM <= STOP_BAR_US,
        "still only {} ms after the grip (bar {} ms)",
        (still - REST_FROM) / 1000,
        STOP_BAR_US / 1000
    );
    let stop = hand_model::finger::FingerConfig::default().angle_max_rad;
    assert!(
        peak < stop - 0.1,
        "ran on to {peak:.3} rad (stop at {stop} rad)"
    );
    assert!(
        (end - peak).abs() < 0.05,
        "the finger drifted at rest: {peak:.3} -> {end:.3}"
    );
    assert_eq!(impacts, 0, "the finger ran into a joint stop");
    // The control: under the paper's law the velocity stays wound up at rest (the simulated
    // controller holds the finger still only because the force is zero; the first force of
    // the finger's own sign then drives it at that speed at once).
    let (still, last, _, _, _) = grip_then_rest(true);
    assert!(
        still.is_none() && last.abs() >= 0.3,
        "the paper's law came back to rest (last velocity {last:.3} rad/s): the drill cannot \
         tell the laws apart"
    );
}

#[test]
fn one_fingers_self_brake_mid_grip_leaves_the_other_four_their_force() {
    const LOSS: u64 = 3_000_000;
    const LOSS_US: u64 = 300_000;
    const BRAKED: usize = 2;
    let mut script = Script::new();
    script.rest(GRIP_FROM).hold(Intent::all(0.6), 5_000_000);
    let mut plan = FaultPlan::new();
    plan.add(Fault::SetpointLoss { finger: BRAKED }, LOSS, LOSS + LOSS_US)
        .expect("fault");
    let mut r = rig(script, plan, false);
    r.run_until(LOSS - 1_000);
    let epochs = r.runner.engine().epochs();
    let before: Vec<_> = r
        .setpoints()
        .into_iter()
        .filter(|s| s.0 > LOSS - 500_000)
        .collect();
    assert!(
        before
            .iter()
            .all(|s| s.2 == FingerMode::Active && s.3 > 0.5),
        "the power grip is on before the loss: {:?}",
        before
            .iter()
            .find(|s| s.2 != FingerMode::Active || s.3 <= 0.5)
    );
    r.run_until(LOSS + 1_500_000);
    let braked = r.world.fingers().nth(BRAKED).expect("finger");
    assert!(
        r.runner.engine().epochs_begun(BRAKED) >= 2,
        "the braked finger was not reopened"
    );
    assert_ne!(r.runner.engine().epoch(BRAKED), epochs[BRAKED]);
    assert_eq!(braked.state(), hand_model::finger::FingerState::Active);
    let after: Vec<_> = r
        .setpoints()
        .into_iter()
        .filter(|s| s.0 >= LOSS && s.0 <= LOSS + 1_500_000)
        .collect();
    let mut least = f64::INFINITY;
    for f in [0, 1, 3, 4] {
        assert_eq!(
            r.runner.engine().epoch(f),
            epochs[f],
            "finger {f}'s epoch moved"
        );
        let mine: Vec<_> = after.iter().filter(|s| s.1 == f).collect();
        assert!(mine.len() >= 25, "finger {f}: {} setpoints", mine.len());
        assert!(
            mine.iter().all(|s| s.2 == FingerMode::Active),
            "finger {f} got {:?}",
            mine.iter().find(|s| s.2 != FingerMode::Active)
        );
        least = mine.iter().map(|s| s.3).fold(least, f64::min);
    }
    let reopened = after
        .iter()
        .filter(|s| s.1 == BRAKED && s.2 == FingerMode::SafeStop)
        .count();
    println!(
        "self-brake of finger {BRAKED}: {reopened} SAFE_STOP to it, none to the others; their \
         least force {least:.2} N over the 1.5 s after the loss"
    );
    assert!(
        reopened >= 1,
        "finger {BRAKED} was not sent the new epoch's SAFE_STOP"
    );
    assert!(
        least > 0.5,
        "another finger let go: force down to {least:.2} N"
    );
}
