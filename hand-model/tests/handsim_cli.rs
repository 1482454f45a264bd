//! The `handsim` binary: scenarios on the in-memory bus, trial export, clear errors.

use std::process::Command;

fn handsim(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_handsim"))
        .args(args)
        .output()
        .expect("handsim runs")
}

#[test]
fn lists_scenarios() {
    let out = handsim(&["--list-scenarios"]);
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    for name in ["rest", "calibration", "sine", "gestures"] {
        assert!(text.contains(name), "{text}");
    }
}

#[test]
fn runs_a_scenario_with_faults_on_the_memory_bus_and_writes_trials() {
    let dir = std::env::temp_dir().join(format!("handsim-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let trials = dir.join("trials.toml");
    let out = handsim(&[
        "--mem",
        "--scenario",
        "calibration-quick",
        "--duration",
        "1",
        "--fault",
        "unknown-ids:0x7a0:5@0.5..0.6",
        "--trials-out",
        trials.to_str().expect("utf-8 path"),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("0x0100       1001"), "{text}");
    assert!(text.contains("0x07a0          5"), "{text}");
    let toml = std::fs::read_to_string(&trials).expect("trials written");
    assert_eq!(toml.matches("[[trial]]").count(), 13);
    std::fs::remove_dir_all(&dir).expect("cleanup");
}

#[test]
fn writes_a_calibration_session_directory() {
    let dir = std::env::temp_dir().join(format!("handsim-session-{}", std::process::id()));
    let out = handsim(&[
        "--mem",
        "--scenario",
        "calibration-quick",
        "--session-out",
        dir.to_str().expect("utf-8 path"),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let log = hand_dbc::candump::read_log(dir.join("frames.log")).expect("candump log");
    let meta = std::fs::read_to_string(dir.join("session.toml")).expect("session.toml");
    let value: toml::Value = toml::from_str(&meta).expect("toml");
    let trials = value["trial"].as_array().expect("trials");
    assert_eq!(trials.len(), 13);
    // The log covers every trial, and EMG arrives at 3 frames per ms throughout.
    let last_end = trials
        .iter()
        .filter_map(|t| t["end_us"].as_integer())
        .max()
        .expect("end");
    let log_end = log.last().expect("frames").time_us;
    assert!(
        log_end as i64 >= last_end,
        "log ends at {log_end}, trials at {last_end}"
    );
    let emg = log
        .iter()
        .filter(|e| (0x100..=0x102).contains(&e.frame.raw_id()))
        .count() as u64;
    assert_eq!(emg, 3 * (log_end / 1000 + 1));
    std::fs::remove_dir_all(&dir).expect("cleanup");
}

#[test]
fn a_missing_interface_is_a_clear_error() {
    let out = handsim(&[
        "--iface",
        "handsimnope0",
        "--scenario",
        "rest",
        "--duration",
        "0.1",
    ]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("handsimnope0") && err.contains("not found"),
        "{err}"
    );
}

#[test]
fn bad_arguments_are_refused() {
    for args in [
        vec!["--mem", "--scenario", "nope"],
        vec!["--mem", "--fault", "warp"],
        vec!["--mem", "--fault", "estop@2..1"],
        vec!["--mem", "--fingers", "7"],
        vec!["--scenario", "rest"],
        vec!["--session-out", "/tmp/x", "--scenario", "rest"],
        vec!["--mem", "--scenario", "cued", "--weak-trial", "255"],
        vec!["--mem", "--scenario", "cued", "--weak-trial", "-1"],
        vec!["--mem", "--scenario", "cued", "--inverted-finger", "5"],
        vec!["--mem", "--scenario", "sine", "--inverted-finger", "1"],
    ] {
        let out = handsim(&args);
        assert!(!out.status.success(), "{args:?} accepted");
        assert!(!out.stderr.is_empty(), "{args:?}: no message");
    }
}

#[test]
fn cued_scenario_rests_without_cues_and_takes_a_weak_trial_only_when_cued() {
    let out = handsim(&[
        "--mem",
        "--scenario",
        "cued",
        "--duration",
        "0.5",
        "--weak-trial",
        "3",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("scenario cued") && text.contains("0x0100        501"),
        "{text}"
    );
    let out = handsim(&["--mem", "--scenario", "rest", "--weak-trial", "3"]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("--weak-trial") && err.contains("cued"),
        "{err}"
    );
    let help = String::from_utf8_lossy(&handsim(&["--help"]).stdout).into_owned();
    assert!(
        help.contains("--weak-trial") && help.contains("CALIBRATION_CUE"),
        "{help}"
    );
}

#[test]
fn cia402_fingers_are_drive_nodes_and_a_bad_finger_is_named() {
    // Index and middle through CiA 402 drives (nodes 6 and 7): their boot-ups and heartbeats
    // are on the bus, and their native controllers' FINGER_STATUS_1 and _2 are not.
    let out = handsim(&["--mem", "--cia402", "12", "--duration", "1"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    for present in ["0x0706", "0x0707", "0x0280"] {
        assert!(text.contains(present), "{present}: {text}");
    }
    for absent in ["0x0281", "0x0282", "0x0705"] {
        assert!(!text.contains(absent), "{absent}: {text}");
    }
    let out = handsim(&["--mem", "--cia402", "7", "--duration", "1"]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("--cia402 \"7\": use finger digits 0 (thumb) to 4 (pinky)"),
        "{err}"
    );
}
