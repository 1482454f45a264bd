//! Issue 14 over vcan (written for the VM run, which the lead runs): handd running with the
//! suite's model, the cued patient (`handsim --scenario cued`) following the cues,
//! `handctl calibrate --yes --protocol short.toml`, `handctl deploy`, `handctl arm`; then the
//! closed-loop sine tracking reaches R² >= 0.8 with the new model, and while calibrating no
//! setpoint but the hold reached the bus (from the first cue, every FINGER_SETPOINT is either
//! not ACTIVE or commands no motion).

use std::time::Duration;

use hand_dbc::messages::{CalibrationCue, FingerMode};
use hand_model::patient::{Target, TrackingConfig};
use handstack_tests::vcan::monitor::now_us;
use handstack_tests::vcan::procs::handctl;
use handstack_tests::vcan::{scenario_start_us, setpoints_of, statuses_of, Seen};

use super::Rig;

/// The protocol: every finger and the whole hand, 3 rounds, short phases (about 4 min).
const SHORT: &str = "repetitions = 3\nprepare_s = 1.0\nhold_s = 2.0\nrest_s = 3.0\nrelax_s = 1.5\n";
/// The cued patient runs at least this long (the calibration ends before).
const PATIENT_S: f64 = 600.0;

#[test]
fn i_calibrate_deploy_arm_then_the_closed_loop_tracks_a_sine() {
    let rig = Rig::start("calibrate", 100);
    let sock = rig.cfg.socket.display().to_string();
    let protocol = rig.dir.join("short.toml");
    std::fs::write(&protocol, SHORT).expect("the protocol file");
    let out = rig.dir.join("cal");
    let mut patient = rig.sim("cued", PATIENT_S, &[]);
    let t0 = now_us();
    let cal = handctl(
        &rig.env,
        &[
            "calibrate",
            "--iface",
            &rig.env.iface,
            "--out",
            &out.display().to_string(),
            "--yes",
            "--protocol",
            &protocol.display().to_string(),
            "--socket",
            &sock,
        ],
    );
    let t1 = now_us();
    patient.kill();
    println!("{}", String::from_utf8_lossy(&cal.stdout));
    let seen = rig.monitor.snapshot();
    let first_cue = seen
        .iter()
        .filter(|s| s.time_us >= t0)
        .find(|s| s.frame.is_some_and(|f| f.raw_id() == CalibrationCue::ID))
        .map(|s| s.time_us)
        .expect("CALIBRATION_CUE frames on the bus");
    let moving = setpoints_of(&seen)
        .into_iter()
        .filter(|s| s.time_us >= first_cue && s.time_us <= t1)
        .filter(|s| s.mode == FingerMode::Active && s.velocity != 0.0)
        .count();
    assert_eq!(moving, 0, "setpoints other than the hold while calibrating");
    let model = out.join("model.hsm").display().to_string();
    handctl(&rig.env, &["deploy", &model, "--socket", &sock]);
    handctl(&rig.env, &["arm", "--socket", &sock]);
    let t_sine = now_us();
    let mut sine = rig.sim("sine", 25.0, &[]);
    sine.wait_success(Duration::from_secs(90));
    let seen: Vec<Seen> = rig
        .monitor
        .snapshot()
        .into_iter()
        .filter(|s| s.time_us >= t_sine)
        .collect();
    let r2 = tracking_r2(&seen);
    println!("closed loop after calibrate + deploy + arm: R² {r2:.3}");
    assert!(r2 >= 0.8, "R² {r2:.3} < 0.8");
}

/// R² of the tracked finger's force against the 4 s sine, after 4 s of settling (as in
/// `b_closed_loop_tracks_a_sine_over_vcan`).
fn tracking_r2(seen: &[Seen]) -> f64 {
    let start = scenario_start_us(seen);
    let tracking = TrackingConfig::default();
    let (mut target, mut tracked) = (Vec::new(), Vec::new());
    for s in statuses_of(seen) {
        if s.finger == tracking.finger && s.time_us >= start + 4_000_000 {
            target.push(Target::SINE_4S.at(s.time_us - start));
            tracked.push(s.force / tracking.full_scale_force_n);
        }
    }
    assert!(target.len() > 500, "only {} status frames", target.len());
    decoder::eval::tracking_metrics(&target, &tracked)
        .expect("metrics")
        .r2
}
