//! Issue 32 ("deployment safe") over vcan, the two drills its Checks ask for:
//!
//! - a second node sending FINGER_SETPOINT while handd runs the closed loop: handd latches
//!   `second_master`, every finger gets SAFE_STOP within a tick, handd sends nothing ACTIVE
//!   until `handctl arm`, and runs again after it;
//! - a calibration of a patient who moves one finger the wrong way round (`handsim --scenario
//!   cued --inverted-finger 1`): `handctl calibrate` exits 3 naming the finger and why, no
//!   model is written or deployed, handd keeps its previous model and its calibrating hold.

use std::path::Path;
use std::process::Command;
use std::time::{Duration, Instant};

use hand_dbc::messages::{CalibrationCue, FingerMode, FingerSetpoint, HandHeartbeat};
use hand_model::dbc::seal;
use handstack_tests::vcan::monitor::{now_us, writer};
use handstack_tests::vcan::procs::{handsim, DEADLINE_SLACK_MS};
use handstack_tests::vcan::{
    first_safe_stop_after, Monitor, Seen, SetpointRecord, TestConfig, VcanEnv,
};
use socketcan::{CanSocket, EmbeddedFrame, Socket};

use super::{
    active_between, arm_at, calibrated_model, wait_for_emg_after, wait_scenario_start, Rig, ALL,
    ARM_US, DRILL_SILENCE_MS, ONSET_US, RUN_S,
};

/// handd's period, µs (the suite's configs: `tick_ms = 50`).
const TICK_US: u64 = 50_000;
/// The second master's bar: handd reads a frame at the first tick whose deadline is at or
/// after its receipt (at most one period later), and that tick starts within the suite's
/// deadline slack of its deadline (a later start is a deadline miss); its safe stops leave
/// then. One tick plus the slack: 75 ms (the suite's safe-stop bar for every other fault,
/// 100 ms, includes a detection time that a received setpoint does not need).
const SECOND_MASTER_BAR_US: u64 = TICK_US + DEADLINE_SLACK_MS as u64 * 1000;
/// Rounds of the second master: a setpoint for every finger, one round per tick.
const ROUNDS: u8 = 4;
/// What the second master commands: a gentle ACTIVE flexion (force and velocity of one sign,
/// so a controller that took it would move).
const FORCE_N: f64 = 4.0;
const VELOCITY_RAD_S: f64 = 0.5;
/// When `handctl status` is asked during the latch (scenario time): after the second master's
/// last round and its controllers' reports, before `handctl arm` at [`ARM_US`].
const LATCHED_STATUS_US: u64 = 3_000_000;

/// One frame the second master wrote: its id and payload, and when it was written.
struct Sent {
    id: u32,
    data: [u8; 8],
    written_us: u64,
}

/// handd's latest setpoint per finger in `seen`: (alive counter, epoch).
fn latest_of_handd(seen: &[Seen]) -> [(u8, u16); 5] {
    ALL.map(|f| {
        seen.iter()
            .rev()
            .find_map(|s| {
                let fr = s.frame.as_ref()?;
                (fr.raw_id() == FingerSetpoint::IDS[f]).then_some(())?;
                FingerSetpoint::decode(fr.raw_id(), fr.data()).ok()
            })
            .map(|sp| (sp.counter(), sp.epoch()))
            .unwrap_or_else(|| panic!("no setpoint of handd for finger {f} before the drill"))
    })
}

/// The second master: [`ROUNDS`] rounds one tick apart, each an ACTIVE setpoint for every
/// finger in handd's current epoch with the alive counter after handd's latest and the right
/// CRC, so each would pass the controller's E2E and epoch checks (encoded by hand-dbc, sealed
/// as the simulated nodes seal theirs).
fn second_master(monitor: &Monitor, w: &CanSocket) -> Vec<Sent> {
    let latest = latest_of_handd(&monitor.snapshot());
    let mut sent = Vec::new();
    for round in 0..ROUNDS {
        for f in ALL {
            let (counter, epoch) = latest[f];
            let sp = FingerSetpoint::new(f, FingerMode::Active, FORCE_N, VELOCITY_RAD_S, epoch)
                .expect("in range");
            let mut frame = sp.to_frame();
            seal(
                &mut frame,
                FingerSetpoint::E2E[f],
                (counter + 1 + round) & 0x0F,
                false,
            );
            let out = socketcan::CanFrame::new(frame.id(), frame.data()).expect("a data frame");
            w.write_frame(&out)
                .expect("vcan takes the second master's frame");
            let mut data = [0u8; 8];
            data.copy_from_slice(frame.data());
            sent.push(Sent {
                id: frame.raw_id(),
                data,
                written_us: now_us(),
            });
        }
        std::thread::sleep(Duration::from_micros(TICK_US));
    }
    sent
}

/// Splits the monitor's setpoints into handd's and the second master's (by exact id and
/// payload); asserts that each frame written was seen exactly once, so no frame of handd's is
/// mistaken for one of them.
fn split_setpoints(seen: &[Seen], sent: &[Sent]) -> (Vec<SetpointRecord>, u64) {
    let mut handd = Vec::new();
    let mut theirs: Vec<u64> = Vec::new();
    for s in seen {
        let Some(f) = s.frame.as_ref() else { continue };
        let Some(finger) = FingerSetpoint::instance_of(f.raw_id()) else {
            continue;
        };
        let Ok(sp) = FingerSetpoint::decode(f.raw_id(), f.data()) else {
            continue;
        };
        if sent
            .iter()
            .any(|x| x.id == f.raw_id() && x.data[..] == *f.data())
        {
            theirs.push(s.time_us);
            continue;
        }
        handd.push(SetpointRecord {
            time_us: s.time_us,
            finger,
            mode: sp.mode(),
            force: sp.force(),
            velocity: sp.velocity(),
        });
    }
    assert_eq!(
        theirs.len(),
        sent.len(),
        "the monitor saw {} frames with the second master's payloads, {} were written",
        theirs.len(),
        sent.len()
    );
    (handd, theirs[0])
}

#[test]
fn h1_a_second_setpoint_sender_latches_second_master_until_arm() {
    let rig = Rig::start("second-master", DRILL_SILENCE_MS);
    let mut sim = rig.sim("sine", RUN_S, &[]);
    let w = writer(&rig.env.iface);
    let start = wait_scenario_start(&rig.monitor);
    while now_us() < start + ONSET_US {
        std::thread::sleep(Duration::from_millis(1));
    }
    let sent = second_master(&rig.monitor, &w);
    while now_us() < start + LATCHED_STATUS_US {
        std::thread::sleep(Duration::from_millis(2));
    }
    let latched = rig.cfg.status(&rig.env);
    let armed = arm_at(&rig, start + ARM_US);
    let armed_us = armed.sent_us;
    sim.wait_success(Duration::from_secs(60));
    let after = rig.cfg.status(&rig.env);
    let seen = rig.monitor.finish();
    let (sps, onset) = split_setpoints(&seen, &sent);
    assert!(
        active_between(&sps, onset - 500_000, onset) > 0,
        "second master: handd was not RUNNING before the second master's first frame"
    );
    let stopped = first_safe_stop_after(&sps, onset, &ALL)
        .expect("second master: some finger never got a safe stop");
    let dt = stopped - onset;
    // What handd wrote after the frame came: at most the tick already under way when it came
    // (written after the receipt, computed without it), then only safe stops until the arm.
    let active_after: Vec<&SetpointRecord> = sps
        .iter()
        .filter(|s| s.time_us >= onset && s.time_us < armed_us && s.mode == FingerMode::Active)
        .collect();
    let held = sps
        .iter()
        .filter(|s| s.time_us > stopped && s.time_us < armed_us)
        .count();
    let resumed = sps
        .iter()
        .find(|s| s.time_us >= armed_us && s.mode == FingerMode::Active)
        .map(|s| s.time_us)
        .expect("second master: never ACTIVE again after `handctl arm`");
    println!(
        "drill second-master: {} frames in {ROUNDS} rounds written from {:.1} ms; every finger \
         safe-stopped {:.1} ms after the first was received (bar {} ms); {} ACTIVE setpoints \
         of handd after it (all before the stop), {held} setpoints held until `handctl arm`; \
         status while latched: {} ({}); faults at the end: {}",
        sent.len(),
        (sent[0].written_us.saturating_sub(start)) as f64 * 1e-3,
        dt as f64 * 1e-3,
        SECOND_MASTER_BAR_US / 1000,
        active_after.len(),
        latched.state,
        latched.faults,
        after.faults
    );
    assert!(
        dt <= SECOND_MASTER_BAR_US,
        "second master: every finger safe-stopped {dt} us after the first foreign setpoint \
         (bar {SECOND_MASTER_BAR_US} us: one tick and the deadline slack)"
    );
    assert!(
        active_after.len() <= ALL.len() && active_after.iter().all(|s| s.time_us < stopped),
        "second master: handd sent ACTIVE setpoints after the foreign frame beyond the one tick \
         under way: {:?}",
        active_after
    );
    assert!(
        sps.iter()
            .filter(|s| s.time_us >= stopped && s.time_us < armed_us)
            .all(|s| s.mode != FingerMode::Active && s.force == 0.0 && s.velocity == 0.0),
        "second master: a setpoint other than a safe stop between the stop and `handctl arm` \
         (the fault must latch)"
    );
    assert!(
        held >= 5 * 10,
        "second master: only {held} setpoints of handd between the stop and the arm: is it \
         sending?"
    );
    assert_eq!(
        latched.state, "SAFE",
        "second master: handd's state while latched (faults {})",
        latched.faults
    );
    assert!(
        latched.faults.split(',').any(|f| f == "second_master"),
        "second master: `handctl status` does not name second_master while latched: {}",
        latched.faults
    );
    armed.check("drill second-master", resumed, &seen);
    assert!(
        !after.faults.split(',').any(|f| f == "second_master"),
        "second master: still latched after `handctl arm`: {}",
        after.faults
    );
}

/// The inverted calibration's protocol: the fewest trials the pattern gates can refuse an
/// inverted finger with. The swapped-directions gate needs the finger and at least two other
/// movements with both directions (decoder::session::patterns::MIN_REFERENCE_MOVEMENTS); one
/// repetition is enough for it (the repetition gate has nothing to compare and only notes
/// that). The phases are the suite's calibration's (calibrate.rs).
const INVERTED_PROTOCOL: &str = "repetitions = 1\nprepare_s = 1.0\nhold_s = 2.0\nrest_s = 3.0\n\
                                 relax_s = 1.5\nfingers = [\"index\", \"middle\", \"all\"]\n";
/// The inverted finger (index) as handsim's `--inverted-finger` and calibrate name it.
const INVERTED_FINGER: &str = "1";
const INVERTED_NAME: &str = "index";
/// `handctl calibrate`'s exit code for a session refused by its quality gates.
const EXIT_GATES: i32 = 3;

/// The daemon's model id in every HAND_HEARTBEAT received in [from, to).
fn heartbeat_model_ids(seen: &[Seen], from: u64, to: u64) -> std::collections::BTreeSet<u32> {
    seen.iter()
        .filter(|s| (from..to).contains(&s.time_us))
        .filter_map(|s| s.frame.as_ref())
        .filter(|f| f.raw_id() == HandHeartbeat::ID)
        .filter_map(|f| HandHeartbeat::decode(f.data()).ok())
        .map(|h| h.model_id())
        .collect()
}

/// Waits (at most 10 s) until the monitor has an ACTIVE setpoint received after `t_us`.
fn wait_for_active_after(monitor: &Monitor, t_us: u64) {
    let begun = Instant::now();
    while !handstack_tests::vcan::setpoints_of(&monitor.snapshot())
        .iter()
        .any(|s| s.time_us >= t_us && s.mode == FingerMode::Active)
    {
        assert!(
            begun.elapsed() < Duration::from_secs(10),
            "inverted calibration: handd never drove the hand with its previous model before \
             the calibration"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
}

#[test]
fn h2_a_calibration_with_an_inverted_finger_is_refused_and_nothing_is_deployed() {
    let env = VcanEnv::get();
    let previous = calibrated_model(&env).to_path_buf();
    let previous_id = driver::startup::fingerprint(&std::fs::read(&previous).expect("model"));
    let dir = env.scratch("inverted");
    let cfg = TestConfig::write(&env, &dir, &previous, 100);
    let monitor = Monitor::start(&env.iface);
    let _handd = cfg.start(&env, &dir);
    let protocol = dir.join("inverted.toml");
    std::fs::write(&protocol, INVERTED_PROTOCOL).expect("the protocol file");
    let t_patient = now_us();
    let mut patient = handsim(
        &env,
        &dir,
        "handsim-inverted",
        "cued",
        600.0,
        &["--inverted-finger", INVERTED_FINGER],
    );
    // The control: handd drives the hand with its previous model before the calibration.
    wait_for_emg_after(
        &monitor,
        t_patient,
        "the cued patient's amplifier never started",
    );
    wait_for_active_after(&monitor, t_patient);
    let before = cfg.status(&env);
    let out_dir = dir.join("cal");
    let t0 = now_us();
    let cal = run_calibrate(&env, &cfg, &protocol, &out_dir);
    let t1 = now_us();
    patient.kill();
    let after = cfg.status(&env);
    let sock = cfg.socket.display().to_string();
    let arm = Command::new(env.bin("handctl"))
        .args(["arm", "--force-rest-mismatch", "--socket", &sock])
        .output()
        .expect("handctl runs");
    let t_end = now_us();
    let seen = monitor.finish();
    let (stdout, stderr) = (
        String::from_utf8_lossy(&cal.stdout),
        String::from_utf8_lossy(&cal.stderr),
    );
    let refusal: Vec<&str> = stderr
        .lines()
        .filter(|l| l.contains(INVERTED_NAME) && l.contains("swap"))
        .collect();
    let first_cue = seen
        .iter()
        .filter(|s| s.time_us >= t0)
        .find(|s| s.frame.is_some_and(|f| f.raw_id() == CalibrationCue::ID))
        .map(|s| s.time_us)
        .expect("inverted calibration: no CALIBRATION_CUE frame on the bus");
    let sps = handstack_tests::vcan::setpoints_of(&seen);
    let during: Vec<&SetpointRecord> = sps
        .iter()
        .filter(|s| s.time_us >= first_cue && s.time_us < t_end)
        .collect();
    let active = during
        .iter()
        .filter(|s| s.mode == FingerMode::Active)
        .count();
    let ids = heartbeat_model_ids(&seen, t0, t_end);
    println!(
        "drill inverted calibration: handctl calibrate took {:.1} s and exited {:?}; its \
         refusal: {}; {} setpoints from the first cue to the end, {active} ACTIVE; heartbeat \
         model ids {ids:08x?} (previous {previous_id:08x}); handd after: {} ({}), model {}; \
         `handctl arm` after it: {:?} {}",
        (t1 - t0) as f64 * 1e-6,
        cal.status.code(),
        refusal.join(" / "),
        during.len(),
        after.state,
        after.faults,
        after.model.as_ref().map_or("none", |m| m.id.as_str()),
        arm.status.code(),
        String::from_utf8_lossy(&arm.stderr).trim()
    );
    assert_eq!(
        cal.status.code(),
        Some(EXIT_GATES),
        "inverted calibration: handctl calibrate did not exit {EXIT_GATES} (quality gates \
         refused); stdout:\n{stdout}\nstderr:\n{stderr}"
    );
    assert!(
        !refusal.is_empty(),
        "inverted calibration: calibrate's output does not name the {INVERTED_NAME} finger as \
         swapped; stderr:\n{stderr}"
    );
    assert!(
        !out_dir.join("model.hsm").exists(),
        "inverted calibration: a model file was written in {}",
        out_dir.display()
    );
    check_nothing_deployed(&before, &after, &previous, previous_id);
    assert!(
        !arm.status.success() && String::from_utf8_lossy(&arm.stderr).contains("calibrating"),
        "inverted calibration: `handctl arm` was not refused by the calibrating hold: {:?} {}{}",
        arm.status.code(),
        String::from_utf8_lossy(&arm.stdout),
        String::from_utf8_lossy(&arm.stderr)
    );
    assert!(
        during.len() >= 5 * 20 * 20,
        "inverted calibration: only {} setpoints of handd while calibrating: is it sending?",
        during.len()
    );
    assert_eq!(
        active, 0,
        "inverted calibration: ACTIVE setpoints between the first cue and the end"
    );
    assert_eq!(
        ids,
        [previous_id].into(),
        "inverted calibration: HAND_HEARTBEAT's ModelId changed"
    );
}

/// `handctl calibrate --yes` with the test's protocol; its output, whatever its exit.
fn run_calibrate(
    env: &VcanEnv,
    cfg: &TestConfig,
    protocol: &Path,
    out: &Path,
) -> std::process::Output {
    Command::new(env.bin("handctl"))
        .args([
            "calibrate",
            "--iface",
            &env.iface,
            "--out",
            &out.display().to_string(),
            "--yes",
            "--protocol",
            &protocol.display().to_string(),
            "--socket",
            &cfg.socket.display().to_string(),
        ])
        .output()
        .expect("handctl runs")
}

/// handd runs the model it ran before the calibration, and holds the hand for it.
fn check_nothing_deployed(
    before: &driver::protocol::Status,
    after: &driver::protocol::Status,
    previous: &Path,
    previous_id: u32,
) {
    let model = |s: &driver::protocol::Status| {
        s.model
            .clone()
            .expect("inverted calibration: handd reports no model")
    };
    let (b, a) = (model(before), model(after));
    assert_eq!(
        (a.path.as_str(), a.id.as_str()),
        (
            previous.display().to_string().as_str(),
            format!("{previous_id:08x}").as_str()
        ),
        "inverted calibration: handd's model after the refused calibration (before: {b:?})"
    );
    assert_eq!(a, b, "inverted calibration: handd's model changed");
    assert_eq!(
        after.state, "SAFE",
        "inverted calibration: handd is not holding the hand ({})",
        after.faults
    );
    assert!(
        after.faults.split(',').any(|f| f == "calibrating"),
        "inverted calibration: handd's calibrating hold is gone: {}",
        after.faults
    );
}
