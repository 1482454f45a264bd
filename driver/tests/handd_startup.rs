//! `handd`'s startup as a new user (or systemd) meets it: a bad config is reported once, and a
//! log that does not go to a terminal carries no ANSI colour escapes; a bus that is down at
//! start keeps handd up, SAFE; SIGHUP is ignored and SIGTERM ends it cleanly.

use std::path::PathBuf;
use std::process::{Command, Output};

/// A scratch directory holding a config that does not parse.
fn bad_config(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("handd-startup-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("scratch directory");
    let path = dir.join("bad.toml");
    std::fs::write(&path, "interface = [\n").expect("write the bad config");
    path
}

/// `handd --check --config <bad>` with stderr piped, plus `extra` arguments and `env`.
fn check(name: &str, extra: &[&str], env: &[(&str, &str)]) -> (Output, String) {
    let config = bad_config(name);
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_handd"));
    cmd.arg("--check").arg("--config").arg(&config).args(extra);
    for var in ["NO_COLOR", "JOURNAL_STREAM", "RUST_LOG"] {
        cmd.env_remove(var);
    }
    cmd.envs(env.iter().copied());
    let out = cmd.output().expect("handd runs");
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    std::fs::remove_dir_all(config.parent().expect("scratch directory")).expect("clean up");
    (out, stderr)
}

fn assert_refused_once(out: &Output, stderr: &str) {
    assert_eq!(out.status.code(), Some(2), "exit status; stderr:\n{stderr}");
    assert_eq!(
        stderr.matches("refusing to start").count(),
        1,
        "the refusal is printed once:\n{stderr}"
    );
    assert_eq!(
        stderr.matches("bad.toml").count(),
        1,
        "the config error is printed once:\n{stderr}"
    );
    assert!(
        stderr.contains("TOML parse error"),
        "the error says what is wrong:\n{stderr}"
    );
}

#[test]
fn a_bad_config_is_reported_once_without_colour_on_a_pipe() {
    let (out, stderr) = check("pipe", &[], &[]);
    assert_refused_once(&out, &stderr);
    assert!(
        !stderr.contains("\x1b["),
        "no ANSI escapes when stderr is not a terminal:\n{stderr:?}"
    );
}

#[test]
fn under_systemd_the_journal_gets_no_colour() {
    let (out, stderr) = check("journal", &[], &[("JOURNAL_STREAM", "8:1234")]);
    assert_refused_once(&out, &stderr);
    assert!(
        !stderr.contains("\x1b["),
        "no ANSI escapes in the journal:\n{stderr:?}"
    );
}

#[test]
fn json_logs_carry_the_error_once_and_no_colour() {
    let (out, stderr) = check("json", &["--json-logs"], &[]);
    assert_refused_once(&out, &stderr);
    assert!(!stderr.contains("\x1b["), "no ANSI escapes:\n{stderr:?}");
    assert!(
        stderr.lines().all(|l| l.starts_with('{')),
        "every line is a JSON object:\n{stderr}"
    );
}

/// handd as a service meets it: a bus that is down at start (here an interface that does not
/// exist) and no model. Returns the child and its scratch directory.
fn start_without_bus(name: &str) -> (std::process::Child, PathBuf) {
    let dir = std::env::temp_dir().join(format!("handd-startup-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch directory");
    let group = Command::new("id").arg("-gn").output().expect("id -gn");
    let group = String::from_utf8_lossy(&group.stdout).trim().to_owned();
    let config = dir.join("handd.toml");
    std::fs::write(
        &config,
        format!(
            "interface = \"hsnocan{}\"\nmodel = \"{}\"\nstate_dir = \"{}\"\n\n[control]\n\
             socket = \"{}\"\ngroup = \"{group}\"\naudit_log = \"{}\"\n",
            std::process::id() % 10_000,
            dir.join("model.hsm").display(),
            dir.display(),
            dir.join("handctl.sock").display(),
            dir.join("audit.log").display(),
        ),
    )
    .expect("config");
    let child = Command::new(env!("CARGO_BIN_EXE_handd"))
        .arg("--config")
        .arg(&config)
        .env_remove("NOTIFY_SOCKET")
        .env_remove("RUST_LOG")
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("handd starts");
    (child, dir)
}

fn signal(child: &std::process::Child, sig: rustix::process::Signal) {
    let pid = rustix::process::Pid::from_raw(child.id() as i32).expect("a pid");
    rustix::process::kill_process(pid, sig).expect("signal sent");
}

#[test]
fn with_the_bus_down_handd_stays_up_ignores_sighup_and_stops_cleanly_on_sigterm() {
    let (mut child, dir) = start_without_bus("busdown");
    let latches = dir.join("latches");
    let t0 = std::time::Instant::now();
    while !latches.exists() && t0.elapsed() < std::time::Duration::from_secs(10) {
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    assert!(latches.exists(), "the latch file is written");
    signal(&child, rustix::process::Signal::HUP);
    std::thread::sleep(std::time::Duration::from_millis(500));
    assert!(
        child.try_wait().expect("wait").is_none(),
        "handd stays up with the bus down and after SIGHUP"
    );
    signal(&child, rustix::process::Signal::TERM);
    let out = child.wait_with_output().expect("handd exits");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(
        out.status.code(),
        Some(0),
        "a clean exit on SIGTERM:\n{stderr}"
    );
    for want in [
        "bus down at start",
        "no latch file: nothing latched",
        "SIGHUP ignored",
        "stopping: no safe stops sent (the bus is down); latches saved",
    ] {
        assert!(stderr.contains(want), "{want:?} in the log:\n{stderr}");
    }
    let text = std::fs::read_to_string(&latches).expect("latches");
    assert!(
        text.contains("latched=\nhold=free"),
        "nothing latched is kept: {text}"
    );
    std::fs::remove_dir_all(&dir).expect("clean up");
}

/// Issue 28: handd's manual page (section 8) comes from its clap definition, and `--man` reads
/// no config.
#[test]
fn handd_prints_its_manual_page() {
    let out = Command::new(env!("CARGO_BIN_EXE_handd"))
        .args(["--man", "--config", "/nonexistent/handd.toml"])
        .output()
        .expect("run handd");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let page = String::from_utf8(out.stdout).expect("utf-8");
    assert!(page.contains(".TH handd 8"), "{page}");
    for option in ["config", "check", "rt\\-priority", "tape"] {
        assert!(
            page.contains(&format!("\\fB\\-\\-{option}")),
            "--{option}: {page}"
        );
    }
}

/// Issue 26, item 1: a valid `cia402` drive table passes the config's checks, and this handd,
/// whose loop drives native fingers only, refuses it by name (also under `--check`, which
/// gates a package upgrade) instead of running a CANopen drive as a native one. A bad one is
/// refused naming the field.
#[test]
fn a_cia402_drive_passes_the_check_and_a_bad_node_is_refused_by_name() {
    let dir = std::env::temp_dir().join(format!("handd-startup-cia402-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("scratch directory");
    let table = "[fingers.index.drive]\nprofile = \"cia402\"\nmode = \"cst\"\n\
                 rated_torque_mnm = 25.0\ngear_ratio = 64.0\nmoment_arm_m = 0.04\n\
                 max_torque_permille = 1000\nmax_speed_rpm = 8000\n";
    for (node, says) in [
        (5, None),
        (2, Some("fingers.index.drive.node_id = 2 is not allowed")),
    ] {
        let path = dir.join(format!("node{node}.toml"));
        std::fs::write(&path, format!("{table}node_id = {node}\n")).expect("write the config");
        let out = Command::new(env!("CARGO_BIN_EXE_handd"))
            .arg("--check")
            .arg("--config")
            .arg(&path)
            .env_remove("RUST_LOG")
            .output()
            .expect("handd runs");
        let stderr = String::from_utf8_lossy(&out.stderr);
        match says {
            Some(says) => {
                assert_eq!(out.status.code(), Some(2), "node {node}: {stderr}");
                assert!(stderr.contains(says), "node {node}: {stderr}");
            }
            // The drive table passes; what fails is the model this scratch config lacks.
            None => {
                assert!(!stderr.contains("fingers."), "node {node}: {stderr}");
                assert!(stderr.contains("model"), "node {node}: {stderr}");
            }
        }
    }
    std::fs::remove_dir_all(&dir).expect("clean up");
}
