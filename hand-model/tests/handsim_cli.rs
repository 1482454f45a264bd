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
    ] {
        let out = handsim(&args);
        assert!(!out.status.success(), "{args:?} accepted");
        assert!(!out.stderr.is_empty(), "{args:?}: no message");
    }
}
