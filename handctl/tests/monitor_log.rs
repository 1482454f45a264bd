//! `handctl monitor --log` (the real binary) renders, into ratatui's test backend at 80x24, the
//! values an independent computation gets from the same candump log: every channel's RMS
//! (cantools decoding the log's text, scipy filtering, numpy RMS over the last 200 ms:
//! `handctl/ref/monitor_reference.py`) and every finger's label (the last HAND_DIAG, decoded
//! by cantools). The log is recorded from the real daemon loop driving the simulated hand on
//! the in-memory bus (a random-weight model: the labels only need to be the daemon's).

// The in-memory rig of driver's own loop tests, shared rather than copied.
#[path = "../../driver/tests/common/mod.rs"]
mod common;

use std::path::PathBuf;
use std::process::Command;

use common::Rig;
use hand_dbc::candump::LogWriter;
use hand_dbc::hand::FINGER_NAMES;
use hand_model::faults::FaultPlan;
use hand_model::patient::{Intent, Script};
use serde_json::Value;

fn python() -> PathBuf {
    if let Some(p) = std::env::var_os("HANDSTACK_PYTHON") {
        return PathBuf::from(p);
    }
    let fallback = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../.venv/bin/python"));
    assert!(
        fallback.exists(),
        "no Python for the reference ({} missing): run ./scripts/test (it creates .venv) or \
         set HANDSTACK_PYTHON to a python with numpy, scipy, cantools",
        fallback.display()
    );
    fallback
}

/// 4 s of the closed loop (rest, then an index flexion) as a candump log.
fn record(path: &std::path::Path) {
    let mut script = Script::new();
    script
        .rest(1_000_000)
        .hold(Intent::finger(1, 0.8), 4_000_000);
    let mut rig = Rig::new(FaultPlan::new(), script);
    rig.run_until(3_950_000);
    let mut log = LogWriter::new(Vec::new());
    for (t, f) in &rig.seen {
        log.write_frame(1_700_000_000_000_000 + t, "vcan0", f)
            .expect("in memory");
    }
    std::fs::write(path, log.into_inner()).expect("write the log");
}

/// The screen's channel rows: `│ c   rms bar flags │`, by channel.
fn channel_rms(screen: &[String]) -> Vec<f64> {
    let mut out = Vec::new();
    for row in screen {
        let inner = row.trim_start_matches('│');
        let mut tokens = inner.split_whitespace();
        let (Some(c), Some(v)) = (tokens.next(), tokens.next()) else {
            continue;
        };
        if c.parse::<usize>() == Ok(out.len()) && row.starts_with('│') {
            if let Ok(v) = v.parse::<f64>() {
                out.push(v);
            }
        }
    }
    out
}

/// The screen's label of each finger (the finger table's second column).
fn labels(screen: &[String]) -> Vec<f64> {
    FINGER_NAMES
        .iter()
        .map(|name| {
            let row = screen
                .iter()
                .find_map(|r| {
                    let at = r
                        .find(&format!(" {name} "))
                        .or_else(|| r.find(&format!(">{name} ")))?;
                    Some(&r[at + 1..])
                })
                .unwrap_or_else(|| panic!("no row for {name}:\n{}", screen.join("\n")));
            let label = row.split_whitespace().nth(1).expect("a label column");
            label
                .parse()
                .unwrap_or_else(|e| panic!("{name}: label {label:?}: {e}"))
        })
        .collect()
}

/// The monitor's screen (80x24, from ratatui's test backend) at the end of `log`.
fn screen_of(log: &std::path::Path) -> Vec<String> {
    let out = Command::new(env!("CARGO_BIN_EXE_handctl"))
        .args([
            "monitor",
            "--log",
            log.to_str().unwrap(),
            "--fast",
            "--screen",
            "80x24",
        ])
        .output()
        .expect("run handctl monitor");
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        out.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let screen: Vec<String> = stdout.lines().take(24).map(str::to_owned).collect();
    println!("{}", screen.join("\n"));
    assert!(
        stdout.contains("monitor used"),
        "the CPU use is printed: {stdout}"
    );

    screen
}

/// The reference's figures for `log`.
fn reference_of(log: &std::path::Path) -> Value {
    let reference = Command::new(python())
        .arg(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/ref/monitor_reference.py"
        ))
        .arg(log)
        .arg(concat!(env!("CARGO_MANIFEST_DIR"), "/../can-dbc/hand.dbc"))
        .output()
        .expect("run the reference");
    assert!(
        reference.status.success(),
        "{}",
        String::from_utf8_lossy(&reference.stderr)
    );
    serde_json::from_slice(&reference.stdout).expect("JSON")
}

fn numbers(v: &Value) -> Vec<f64> {
    let a = v.as_array().unwrap_or_else(|| panic!("not an array: {v}"));
    a.iter().map(|x| x.as_f64().expect("a number")).collect()
}

#[test]
fn the_screen_from_a_log_shows_what_scipy_and_cantools_get_from_it() {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("monitor-log-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let log = dir.join("frames.log");
    record(&log);

    let screen = screen_of(&log);
    let r = reference_of(&log);
    assert!(r["samples"].as_u64().unwrap() > 3500, "{r}");

    let want = numbers(&r["rms_uv"]);
    let got = channel_rms(&screen);
    assert_eq!(
        got.len(),
        12,
        "12 channel rows on the screen:\n{}",
        screen.join("\n")
    );
    for (c, (g, w)) in got.iter().zip(&want).enumerate() {
        // One decimal on screen.
        assert!(
            (g - w).abs() <= 0.05 + 1e-9,
            "channel {c}: screen {g} µV, scipy {w} µV"
        );
    }
    assert!(
        want.iter().any(|&w| w > 5.0),
        "the log has real EMG: {want:?}"
    );

    let want = numbers(&r["labels"]);
    let got = labels(&screen);
    for (f, (g, w)) in got.iter().zip(&want).enumerate() {
        assert!(
            (g - w).abs() < 1e-9,
            "{}: screen {g}, HAND_DIAG {w}",
            FINGER_NAMES[f]
        );
    }
    assert!(
        want.iter().any(|&l| l != 0.0),
        "the daemon decodes something: {want:?}"
    );
    assert!(
        screen.iter().any(|r| r.contains("RUNNING")),
        "the heartbeat's state:\n{}",
        screen.join("\n")
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// `monitor --log --config`: the CiA 402 drives handd's config names, from their own frames
/// in the log (heartbeat, TPDO1, EMCY); a `--config` that cannot be read is refused.
#[test]
fn the_drives_of_the_config_are_shown_from_their_frames_in_a_log() {
    let dir = std::env::temp_dir().join(format!("handctl-monitor-drives-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("scratch directory");
    let drive = |finger: &str, node: u8| {
        format!(
            "[fingers.{finger}.drive]\nprofile = \"cia402\"\nnode_id = {node}\nmode = \"cst\"\n\
             rated_torque_mnm = 25.0\ngear_ratio = 64.0\nmoment_arm_m = 0.04\n\
             max_torque_permille = 1000\nmax_speed_rpm = 8000\n\n"
        )
    };
    let config = dir.join("handd.toml");
    std::fs::write(&config, drive("index", 6) + &drive("ring", 9)).expect("write the config");
    // 2 s of frames every 50 ms: both drives beat (operational), the index reports Operation
    // enabled in its TPDO1 (statusword 0x0637), the ring an EMCY at 1 s (0x2310: output
    // current too high, continuous) and a statusword in Fault after it.
    let mut log = String::new();
    for k in 0..40u64 {
        let t = 1_700_000_000.0 + k as f64 * 0.05;
        log += &format!("({t:.6}) vcan0 706#05\n({t:.6}) vcan0 709#05\n");
        log += &format!("({t:.6}) vcan0 186#3706000000000000\n");
        if k == 20 {
            log += &format!("({t:.6}) vcan0 089#1023010000000000\n");
        }
        let ring = if k >= 20 { "0800" } else { "3706" };
        log += &format!("({t:.6}) vcan0 189#{ring}000000000000\n");
    }
    let path = dir.join("drives.log");
    std::fs::write(&path, log).expect("write the log");
    // `handctl monitor --log` of that log, plain, with `--config` when given.
    let monitor = |config: Option<&std::path::Path>| {
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_handctl"));
        cmd.args([
            "monitor",
            "--log",
            path.to_str().unwrap(),
            "--fast",
            "--plain",
        ]);
        if let Some(c) = config {
            cmd.args(["--config", c.to_str().unwrap()]);
        }
        cmd.output().expect("run handctl monitor")
    };
    let out = monitor(Some(&config));
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        out.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let last = stdout
        .lines()
        .rfind(|l| l.contains("| drives "))
        .unwrap_or_else(|| panic!("no line shows the drives: {stdout}"));
    assert!(last.contains("index n6 Operation enabled"), "{last}");
    assert!(last.contains("ring n9 STOPPED EMCY 0x2310"), "{last}");
    // Without the config (and no default file here): no drive line.
    if !std::path::Path::new(driver::config::DEFAULT_CONFIG_PATH).exists() {
        let out = monitor(None);
        assert!(out.status.success());
        assert!(!String::from_utf8_lossy(&out.stdout).contains("| drives "));
    }
    // A --config that is not there is refused, naming it.
    let out = monitor(Some(&dir.join("missing.toml")));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("missing.toml"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).ok();
}
