//! Live tuning end to end on the in-memory bus: `handctl tune` (the real binary) talks to the
//! control socket while the loop runs; the finger controller's reported force changes by the
//! expected ratio within two ticks, the config file holds the new value, the audit log has the
//! change, and `handctl status` shows it. A bad value is refused with the range and changes
//! nothing.

// The in-memory rig of driver's own loop tests, shared rather than copied.
#[path = "../../driver/tests/common/mod.rs"]
mod common;

use std::process::{Command, Stdio};
use std::sync::mpsc;

use common::Rig;
use driver::config::Config;
use driver::control::ControlServer;
use driver::service::ControlHandler;
use hand_dbc::messages::FingerStatus;
use hand_model::faults::FaultPlan;
use hand_model::patient::{Intent, Script};

fn reported_index_forces(rig: &Rig, from_us: u64) -> Vec<(u64, f64)> {
    rig.seen
        .iter()
        .filter(|(t, f)| *t >= from_us && FingerStatus::instance_of(f.raw_id()) == Some(1))
        .filter_map(|(t, f)| Some((*t, FingerStatus::decode(f.raw_id(), f.data()).ok()?.force())))
        .collect()
}

#[test]
fn tune_changes_the_force_by_the_ratio_within_two_ticks_and_persists() {
    let dir = std::env::temp_dir().join(format!("handd-tune-e2e-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let config_path = dir.join("handd.toml");
    let mut config = Config::default();
    config.control.socket = dir.join("ctl.sock");
    config.control.group = None;
    config.control.audit_log = dir.join("audit.log");
    config.save_atomic(&config_path).unwrap();

    // A steady index flexion, so the label is steady.
    let mut script = Script::new();
    script
        .rest(500_000)
        .hold(Intent::finger(1, 0.8), 30_000_000);
    let mut rig = Rig::new(FaultPlan::new(), script);
    let (tx, rx) = mpsc::sync_channel(driver::service::COMMAND_QUEUE);
    rig.runner.set_commands(rx);
    let handler = ControlHandler::new(
        config.clone(),
        config_path.clone(),
        rig.runner.snapshot(),
        tx,
    );
    let server = ControlServer::bind(&config.control.socket, None).unwrap();
    let mut handler = handler;
    std::thread::spawn(move || server.serve(move |req, peer| handler.handle(req, peer)));

    rig.run_until(3_000_000);
    let before = reported_index_forces(&rig, 2_000_000);
    let mean_before = before.iter().map(|x| x.1).sum::<f64>() / before.len() as f64;
    assert!(
        mean_before.abs() > 0.5,
        "the index finger pushes before tuning: {mean_before} N"
    );

    let handctl = env!("CARGO_BIN_EXE_handctl");
    let sock = config.control.socket.to_str().unwrap();
    let mut child = Command::new(handctl)
        .args(["tune", "--finger", "index", "--kf", "5", "--socket", sock])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Keep the loop running while handctl waits for its answer.
    let mut t = 3_000_000;
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        t += 1000;
        rig.run_until(t);
        std::thread::sleep(std::time::Duration::from_micros(200));
        assert!(t < 60_000_000, "handctl tune did not return");
    };
    let out = child.wait_with_output().unwrap();
    assert!(status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let said = String::from_utf8_lossy(&out.stdout).to_string();
    assert!(said.contains("kf 10 -> 5"), "{said}");

    // The command reaches the loop at its next tick; two ticks later the reported force has
    // followed (the controller reports at 50 Hz).
    let applied_at = rig.clock_now();
    rig.run_until(applied_at + 2 * 50_000 + 20_000);
    let after = reported_index_forces(&rig, applied_at + 2 * 50_000);
    let ratio = after[0].1 / mean_before;
    println!(
        "force before {mean_before:.2} N, two ticks after tuning {:.2} N: ratio {ratio:.3}",
        after[0].1
    );
    assert!(
        (ratio - 0.5).abs() < 0.1,
        "expected half the force, ratio {ratio}"
    );

    assert_eq!(Config::load(&config_path).unwrap().fingers.index.kf, 5.0);
    let audit = std::fs::read_to_string(dir.join("audit.log")).unwrap();
    assert!(audit.contains("finger=index kf=10->5"), "{audit}");

    // Out of range: refused, with the range, nothing changed.
    let out = Command::new(handctl)
        .args(["tune", "--finger", "index", "--kf", "400", "--socket", sock])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let e = String::from_utf8_lossy(&out.stderr);
    assert!(
        e.contains("0 to 40") && e.contains("nothing changed"),
        "{e}"
    );
    assert_eq!(Config::load(&config_path).unwrap().fingers.index.kf, 5.0);

    // status shows the new gain.
    let mut child = Command::new(handctl)
        .args(["status", "--json", "--socket", sock])
        .stdout(Stdio::piped())
        .spawn()
        .unwrap();
    let mut t = rig.clock_now();
    while child.try_wait().unwrap().is_none() {
        t += 1000;
        rig.run_until(t);
    }
    let out = child.wait_with_output().unwrap();
    let status: driver::protocol::Status = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(status.state, "RUNNING");
    assert_eq!(status.fingers[1].kf, 5.0);
    std::fs::remove_dir_all(&dir).unwrap();
}
