//! Issue 14 over vcan, the suite's calibration: `handd` running with no model, the cued patient
//! (`handsim --scenario cued`) following the cues, `handctl calibrate --yes` (recording, the
//! per-trial checks, training), `handctl deploy`, `handctl arm`; then the closed-loop sine
//! tracking reaches R² >= 0.8 with the new model, and while calibrating only the hold (safe
//! stop: handd's choice, see driver/src/model_service.rs) reached the bus. Every later test
//! drives the hand with the model this calibration made.

use std::path::PathBuf;
use std::time::Duration;

use hand_dbc::messages::{CalibrationCue, FingerMode, HandHeartbeat};
use hand_model::patient::{Target, TrackingConfig};
use handstack_tests::vcan::monitor::now_us;
use handstack_tests::vcan::procs::{handctl, handsim};
use handstack_tests::vcan::{scenario_start_us, setpoints_of, statuses_of, Monitor, Seen};
use handstack_tests::vcan::{TestConfig, VcanEnv};

use super::wait_for_emg_after;

/// The protocol: rest, flexion and extension of every finger and of the whole hand, two
/// rounds (the second lets calibrate compare repetitions), short phases: about 2.5 minutes
/// (shorter relax and rest phases, 0.5 s prepare, gave a model that tracked the sine at R² 0.60
/// instead of 0.92 in one VM run; one run each, so the cause is not established).
const SHORT: &str = "repetitions = 2\nprepare_s = 1.0\nhold_s = 2.0\nrest_s = 3.0\nrelax_s = 1.5\n";
/// Training's epoch cap: emulation runs training ~50x slower than the host, and the suite's
/// closed loop needs a usable model, not the best one (early stopping ends near 80 anyway).
const EPOCHS: &str = "40";
/// The cued patient runs at least this long (the calibration ends before; it is stopped then).
const PATIENT_S: f64 = 900.0;

/// Runs the workflow in a scratch directory and returns calibrate's `--out` directory (the
/// session's files and the trained `model.hsm`), after asserting what issue 14 asks of it.
pub(super) fn calibrate_deploy_arm(env: &VcanEnv) -> PathBuf {
    let dir = env.scratch("calibrate");
    // No model file: handd starts SAFE with `no_model` and waits for a deploy.
    let cfg = TestConfig::write(env, &dir, &dir.join("no-model-yet.hsm"), 100);
    let monitor = Monitor::start(&env.iface);
    let handd = cfg.start(env, &dir);
    std::thread::sleep(Duration::from_millis(500));
    let sock = cfg.socket.display().to_string();
    let protocol = dir.join("short.toml");
    std::fs::write(&protocol, SHORT).expect("the protocol file");
    let out = dir.join("cal");
    let mut patient = handsim(env, &dir, "handsim-cued", "cued", PATIENT_S, &[]);
    let t0 = now_us();
    let cal = handctl(
        env,
        &[
            "calibrate",
            "--iface",
            &env.iface,
            "--out",
            &out.display().to_string(),
            "--yes",
            "--protocol",
            &protocol.display().to_string(),
            "--socket",
            &sock,
            "--epochs",
            EPOCHS,
        ],
    );
    let t1 = now_us();
    patient.kill();
    println!(
        "calibrate ({:.0} s):\n{}",
        (t1 - t0) as f64 * 1e-6,
        String::from_utf8_lossy(&cal.stdout)
    );
    assert_only_the_hold(&monitor.snapshot(), t0, t1);
    // With the receive buffer the install sets (net.core.rmem_max, as in the VM), nothing of
    // the session is lost while calibrate checks a trial.
    let said = String::from_utf8_lossy(&cal.stdout);
    let drops: Option<u64> = said
        .split_once(" dropped by the kernel")
        .and_then(|(before, _)| before.rsplit(' ').next())
        .and_then(|n| n.parse().ok());
    assert_eq!(
        drops,
        Some(0),
        "handctl calibrate lost frames to the kernel (or did not say): see its output above"
    );
    let model = out.join("model.hsm");
    handctl(
        env,
        &[
            "deploy",
            &model.display().to_string(),
            "--yes",
            "--socket",
            &sock,
        ],
    );
    // The patient back on the amplifier (a new handsim: the cued one is gone), then arm, as a
    // technician arms with the electrodes streaming.
    let t_sine = now_us();
    let mut sine = handsim(env, &dir, "handsim-sine", "sine", 25.0, &[]);
    wait_for_emg_after(
        &monitor,
        t_sine,
        "the sine patient's amplifier never started",
    );
    // The sine patient moves from its first sample, never at rest: the rest check before
    // arm (driver/tests/rest_check.rs) is overridden here, as a technician would, audited.
    handctl(env, &["arm", "--force-rest-mismatch", "--socket", &sock]);
    sine.wait_success(Duration::from_secs(90));
    let seen: Vec<Seen> = monitor
        .snapshot()
        .into_iter()
        .filter(|s| s.time_us >= t_sine)
        .collect();
    let id = driver::startup::fingerprint(&std::fs::read(&model).expect("the model file"));
    let heartbeat_ids: std::collections::BTreeSet<u32> = seen
        .iter()
        .filter_map(|s| s.frame.as_ref())
        .filter(|f| f.raw_id() == HandHeartbeat::ID)
        .filter_map(|f| HandHeartbeat::decode(f.data()).ok())
        .map(|h| h.model_id())
        .collect();
    assert_eq!(
        heartbeat_ids,
        [id].into(),
        "HAND_HEARTBEAT's ModelId after the deploy"
    );
    let r2 = tracking_r2(&seen);
    println!("closed loop after calibrate, deploy and arm: R² {r2:.3}");
    print_tracked_modes(&seen);
    if r2 < 0.8 {
        // Why the hand was not driven, in handd's words (its state changes with their causes).
        let log = handd.output();
        let changes: Vec<&str> = log.lines().filter(|l| l.contains("state change")).collect();
        println!(
            "handd's last state changes:\n{}",
            changes[changes.len().saturating_sub(20)..].join("\n")
        );
    }
    assert!(r2 >= 0.8, "tracking R² {r2:.3} < 0.8 after calibrate");
    out
}

/// From the first cue to calibrate's end, every FINGER_SETPOINT on the bus is the hold.
fn assert_only_the_hold(seen: &[Seen], t0: u64, t1: u64) {
    let first_cue = seen
        .iter()
        .filter(|s| s.time_us >= t0)
        .find(|s| s.frame.is_some_and(|f| f.raw_id() == CalibrationCue::ID))
        .map(|s| s.time_us)
        .expect("CALIBRATION_CUE frames on the bus");
    let during: Vec<_> = setpoints_of(seen)
        .into_iter()
        .filter(|s| s.time_us >= first_cue && s.time_us <= t1)
        .collect();
    // The hold is SAFE_STOP, for a finger whose controller fell silent (handsim starved under
    // emulation) too: handd never sends DISABLED (motor off, the finger would coast). Nothing
    // ACTIVE, HOLD or DISABLED.
    let count = |m: FingerMode| during.iter().filter(|s| s.mode == m).count();
    let (stop, disabled) = (count(FingerMode::SafeStop), count(FingerMode::Disabled));
    println!(
        "while calibrating: {} setpoints, {stop} SAFE_STOP, {disabled} DISABLED, {} ACTIVE, \
         {} HOLD",
        during.len(),
        count(FingerMode::Active),
        count(FingerMode::Hold)
    );
    assert!(
        during.len() >= 5 * 20 * 60,
        "only {} setpoints while calibrating: is handd sending?",
        during.len()
    );
    assert_eq!(disabled, 0, "handd sent DISABLED while calibrating");
    assert_eq!(
        stop,
        during.len(),
        "setpoints other than the hold while calibrating"
    );
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

/// What the tracked finger was told over the tracked part of the sine: the first ACTIVE
/// setpoint after the scenario's start and the share of ACTIVE ones (a low R² with a late or
/// interrupted ACTIVE is the daemon's state, not the model).
fn print_tracked_modes(seen: &[Seen]) {
    let start = scenario_start_us(seen);
    let finger = TrackingConfig::default().finger;
    let mine: Vec<_> = setpoints_of(seen)
        .into_iter()
        .filter(|s| s.finger == finger && s.time_us >= start)
        .collect();
    let first_active = mine
        .iter()
        .find(|s| s.mode == FingerMode::Active)
        .map(|s| (s.time_us - start) as f64 * 1e-3);
    let tracked: Vec<_> = mine
        .iter()
        .filter(|s| s.time_us >= start + 4_000_000)
        .collect();
    let active = tracked
        .iter()
        .filter(|s| s.mode == FingerMode::Active)
        .count();
    println!(
        "tracked finger: first ACTIVE {first_active:?} ms after the sine's start; {active} of {} \
         setpoints ACTIVE after its first 4 s",
        tracked.len()
    );
}
