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

    // The command reaches the loop at a tick about when handctl has its answer; from there the
    // gain ramps (ramp_s 1 s across its whole range, 0 to 40: 2 per tick, so 10 -> 5 takes
    // three ticks) and the force follows it down without a jump, to half (the controller
    // reports at 50 Hz). Where in the ramp a given tick falls depends on when the answer
    // came, so the test reads the whole ramp.
    let applied_at = rig.clock_now();
    rig.run_until(applied_at + 8 * 50_000);
    let after = reported_index_forces(&rig, applied_at);
    let settled = after
        .iter()
        .filter(|(t, _)| *t >= applied_at + 4 * 50_000)
        .map(|x| x.1 / mean_before)
        .collect::<Vec<_>>();
    println!(
        "force before {mean_before:.2} N; after tuning, from the answer on: {:?}",
        after
            .iter()
            .map(|x| (x.1 * 100.0).round() / 100.0)
            .collect::<Vec<_>>()
    );
    assert!(
        !settled.is_empty() && settled.iter().all(|r| (r - 0.5).abs() < 0.05),
        "expected half the force four ticks after the answer: ratios {settled:?}"
    );
    let mut last = mean_before;
    for (t, f) in &after {
        assert!(
            *f <= last + 0.1 && *f >= last - 2.1,
            "the force jumped or rose at {t} us: {last:.2} -> {f:.2} N"
        );
        last = *f;
    }

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

/// A ResDD for the bus's 12 channels with random weights (`seed`), `chain` and a passing
/// verification record, saved to `path`; returns its bytes.
fn saved_model(path: &std::path::Path, chain: decoder::dsp::ChainConfig, seed: u64) -> Vec<u8> {
    use decoder::model::verify::{Method, VerificationRecord};
    use decoder::model::{
        AnyModel, ModelKind, ModelSpec, Normalizer, TrainedModel, TrainingSummary,
    };
    let n_in = 8 * chain.channels;
    let spec = ModelSpec::default();
    let model = AnyModel::random(ModelKind::ResDd, &spec, n_in, 5, seed).unwrap();
    let norm = Normalizer::from_scales(vec![100.0; n_in]).unwrap();
    let summary = TrainingSummary::untrained(ModelKind::ResDd);
    let record = VerificationRecord {
        method: Method::Exact,
        tolerance: 0.01,
        rays: 500,
        reversing: 0,
        worst: Some(decoder::model::verify::WorstRay {
            trial: "trial 1 (index flexion, repetition 1)".into(),
            finger: 1,
            amount: 0.0,
            from_k: 0.0,
            to_k: 0.0,
        }),
        forced: false,
    };
    TrainedModel::new(model, spec, norm, chain, summary)
        .unwrap()
        .with_verification(record)
        .unwrap()
        .save(path)
        .unwrap();
    std::fs::read(path).unwrap()
}

/// Runs `handctl ARGS` while the loop ticks on (a deploy waits for its tick); returns whether
/// it succeeded and what it printed (stdout, then stderr).
fn handctl_while_ticking(rig: &mut Rig, args: &[&str]) -> (bool, String) {
    let (code, text) = handctl_code_while_ticking(rig, args);
    (code == Some(0), text)
}

/// [`handctl_while_ticking`] with the exit code; stdin is not a terminal, as in a script.
fn handctl_code_while_ticking(rig: &mut Rig, args: &[&str]) -> (Option<i32>, String) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_handctl"))
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut t = rig.clock_now();
    while child.try_wait().unwrap().is_none() {
        t += 1000;
        rig.run_until(t);
        std::thread::sleep(std::time::Duration::from_micros(200));
    }
    let out = child.wait_with_output().unwrap();
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    (out.status.code(), text)
}

/// HAND_HEARTBEAT's model ids seen from `from_us` on, with their times.
fn heartbeat_ids(rig: &Rig, from_us: u64) -> Vec<(u64, u32)> {
    use hand_dbc::messages::HandHeartbeat;
    rig.seen
        .iter()
        .filter(|(t, f)| *t >= from_us && f.raw_id() == HandHeartbeat::ID)
        .filter_map(|(t, f)| Some((*t, HandHeartbeat::decode(f.data()).ok()?.model_id())))
        .collect()
}

/// Issue 14 on the in-memory bus: the calibrating hold (safe stops only, `arm` refused until a
/// deploy, then `arm` moves the hand again), `handctl deploy` of a corrupted and of a
/// mismatched file refused with the reason while the old model keeps driving, a good model
/// swapped in at a tick boundary with no tick missed (HAND_HEARTBEAT's id changes, the config
/// names the installed copy), and `handctl rollback` bringing the previous id back; each
/// action audited with uid and pid.
#[test]
fn calibrating_hold_deploy_refusals_swap_and_rollback() {
    use driver::control::request;
    use driver::engine::Command as LoopCommand;
    use driver::protocol::{Reply, Request};
    use driver::startup::fingerprint;
    use hand_dbc::messages::FingerMode;

    let dir = std::env::temp_dir().join(format!("handd-deploy-e2e-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let config_path = dir.join("handd.toml");
    let mut config = Config::default();
    config.control.socket = dir.join("ctl.sock");
    config.control.group = None;
    config.control.audit_log = dir.join("audit.log");
    config.model = dir.join("model.hsm");
    config.save_atomic(&config_path).unwrap();
    let chain = decoder::dsp::ChainConfig::default();
    let id_a = fingerprint(&saved_model(&config.model, chain.clone(), 7));
    let good = dir.join("new.hsm");
    let id_b = fingerprint(&saved_model(&good, chain.clone(), 8));
    assert_ne!(id_a, id_b);
    let mut bytes = std::fs::read(&good).unwrap();
    let mid = bytes.len() / 2;
    bytes[mid] ^= 0x40;
    std::fs::write(dir.join("corrupt.hsm"), &bytes).unwrap();
    let other = decoder::dsp::ChainConfig {
        window_ms: 250.0,
        ..chain.clone()
    };
    saved_model(&dir.join("other.hsm"), other, 9);

    let mut script = Script::new();
    script
        .rest(500_000)
        .hold(Intent::finger(1, 0.8), 60_000_000);
    let mut rig = Rig::new(FaultPlan::new(), script);
    // The loop starts on model A, swapped in as a deploy would.
    let loaded = driver::startup::load_model(&config.model, 50).unwrap();
    let (back, _returned) = mpsc::sync_channel(1);
    rig.runner
        .engine_mut()
        .command(0, LoopCommand::swap(loaded.model.predictor(), id_a, back))
        .unwrap();
    let (tx, rx) = mpsc::sync_channel(driver::service::COMMAND_QUEUE);
    rig.runner.set_commands(rx);
    let live = std::sync::Arc::new(std::sync::Mutex::new(driver::control::LiveModel::default()));
    let mut handler = ControlHandler::new(
        config.clone(),
        config_path.clone(),
        rig.runner.snapshot(),
        tx,
    )
    .with_model(loaded.status(&config.model))
    .with_live_model(std::sync::Arc::clone(&live));
    let server = ControlServer::bind(&config.control.socket, None).unwrap();
    std::thread::spawn(move || server.serve(move |req, peer| handler.handle(req, peer)));
    let sock = config.control.socket.clone();
    let s = sock.to_str().unwrap();
    // What the live lines (`handctl monitor`) say of the running model.
    let live_id = || live.lock().unwrap().info.id.clone();

    // A swap over a running model latches model_swapped: arm once the signal is validated.
    rig.run_until(700_000);
    assert!(rig
        .runner
        .engine()
        .faults()
        .contains(driver::safety::Fault::ModelSwapped));
    rig.runner
        .engine_mut()
        .command(700_000, LoopCommand::Arm)
        .unwrap();
    rig.run_until(2_000_000);
    assert!(heartbeat_ids(&rig, 0).iter().all(|h| h.1 == id_a));
    let ask = |req: Request| request(&sock, &req).unwrap();

    // The hold: safe stops only from the next tick, arm refused.
    let held_from = rig.clock_now();
    assert!(matches!(ask(Request::Calibrating), Reply::Ok { .. }));
    match ask(Request::Arm {
        force_rest_mismatch: false,
    }) {
        Reply::Refused { reason } => assert!(reason.contains("calibrating"), "{reason}"),
        r => panic!("arm during the hold: {r:?}"),
    }
    rig.run_until(held_from + 1_000_000);
    let modes_seen = |rig: &Rig, from: u64, to: u64| -> Vec<FingerMode> {
        rig.setpoints()
            .iter()
            .filter(|p| p.0 > from && p.0 <= to)
            .map(|p| p.2)
            .collect()
    };
    assert!(
        modes_seen(&rig, 1_000_000, held_from).contains(&FingerMode::Active),
        "the hand moved before the hold"
    );
    match ask(Request::Status) {
        Reply::Ok {
            status: Some(st), ..
        } => {
            assert!(
                st.state == "SAFE" && st.faults.contains("calibrating"),
                "{st:?}"
            )
        }
        r => panic!("status: {r:?}"),
    }

    // Bad models: refused with the reason, the old id stays on the bus.
    let (ok, said) = handctl_while_ticking(
        &mut rig,
        &[
            "deploy",
            dir.join("corrupt.hsm").to_str().unwrap(),
            "--socket",
            s,
        ],
    );
    assert!(!ok && said.contains("checksum"), "{said}");
    let (ok, said) = handctl_while_ticking(
        &mut rig,
        &[
            "deploy",
            dir.join("other.hsm").to_str().unwrap(),
            "--socket",
            s,
        ],
    );
    assert!(
        !ok && said.contains("window_ms: model 250.0, running 200.0"),
        "{said}"
    );
    let (ok, said) = handctl_while_ticking(
        &mut rig,
        &[
            "deploy",
            dir.join("absent.hsm").to_str().unwrap(),
            "--socket",
            s,
        ],
    );
    assert!(!ok && said.contains("absent.hsm"), "{said}");
    assert_eq!(Config::load(&config_path).unwrap().model, config.model);

    // The good one: swapped at a tick, the config names its installed copy, still held.
    let before = rig.runner.engine().counters();
    let deploy_at = rig.clock_now();
    // Both files record no patient: a script without --yes fails at once, nothing changed.
    let (code, said) =
        handctl_code_while_ticking(&mut rig, &["deploy", good.to_str().unwrap(), "--socket", s]);
    assert_eq!(code, Some(5), "{said}");
    assert!(
        said.contains("this model is for unknown patient") && said.contains("pass --yes"),
        "{said}"
    );
    assert_eq!(Config::load(&config_path).unwrap().model, config.model);
    // A hand-written request cannot skip the question: handd refuses it too.
    let path = good.to_str().unwrap().to_owned();
    match ask(Request::Deploy {
        path: path.clone(),
        force: false,
        confirmed: false,
        check_only: false,
    }) {
        Reply::Refused { reason } => assert!(reason.contains("confirmation"), "{reason}"),
        r => panic!("an unconfirmed deploy: {r:?}"),
    }
    let (ok, said) = handctl_while_ticking(
        &mut rig,
        &["deploy", good.to_str().unwrap(), "--yes", "--socket", s],
    );
    assert!(ok, "{said}");
    assert!(said.contains(&format!("{id_b:08x}")), "{said}");
    rig.run_until(rig.clock_now() + 500_000);
    let ids = heartbeat_ids(&rig, held_from);
    let first_b = ids
        .iter()
        .position(|h| h.1 == id_b)
        .expect("the new id on the bus");
    assert!(
        ids[..first_b].iter().all(|h| h.1 == id_a) && ids[first_b..].iter().all(|h| h.1 == id_b)
    );
    assert!(ids[first_b].0 >= deploy_at);
    assert_eq!(live_id(), format!("{id_b:08x}"), "the live lines' model");
    // No tick missed: the setpoints of every 50 ms tick are on the bus across the swap.
    let ticks: Vec<u64> = rig
        .setpoints()
        .iter()
        .filter(|p| p.1 == 0 && p.0 >= deploy_at)
        .map(|p| p.0)
        .collect();
    assert!(ticks.windows(2).all(|w| w[1] - w[0] == 50_000), "{ticks:?}");
    let after = rig.runner.engine().counters();
    assert_eq!(after.deadline_misses, before.deadline_misses);
    let installed = dir.join(format!("model-{id_b:08x}.hsm"));
    assert_eq!(Config::load(&config_path).unwrap().model, installed);
    assert_eq!(fingerprint(&std::fs::read(&installed).unwrap()), id_b);
    let until = rig.clock_now();
    assert!(modes_seen(&rig, held_from + 50_000, until)
        .iter()
        .all(|m| *m == FingerMode::SafeStop));

    // arm now releases the hand.
    assert!(
        matches!(
            ask(Request::Arm {
                force_rest_mismatch: false,
            }),
            Reply::Ok { .. }
        ),
        "arm after the deploy"
    );
    rig.run_until(until + 2_000_000);
    assert!(modes_seen(&rig, until, rig.clock_now()).contains(&FingerMode::Active));

    // rollback: model A's id again, and the config names A's file.
    let back_at = rig.clock_now();
    let (ok, said) = handctl_while_ticking(&mut rig, &["rollback", "--socket", s]);
    assert!(ok, "{said}");
    rig.run_until(rig.clock_now() + 300_000);
    assert_eq!(
        heartbeat_ids(&rig, back_at + 100_000).last().unwrap().1,
        id_a
    );
    assert_eq!(Config::load(&config_path).unwrap().model, config.model);
    assert_eq!(live_id(), format!("{id_a:08x}"), "the live lines' model");
    // The rollback took over a moving hand: safe stops from the tick after it until `arm`.
    let until = rig.clock_now();
    assert!(
        modes_seen(&rig, back_at + 100_000, until)
            .iter()
            .all(|m| *m == FingerMode::SafeStop),
        "the hand moved under the rolled-back model before arm"
    );
    assert!(
        matches!(
            ask(Request::Arm {
                force_rest_mismatch: false,
            }),
            Reply::Ok { .. }
        ),
        "arm after the rollback"
    );
    rig.run_until(until + 2_000_000);
    assert!(modes_seen(&rig, until, rig.clock_now()).contains(&FingerMode::Active));
    let audit = std::fs::read_to_string(dir.join("audit.log")).unwrap();
    for want in [
        "calibrating",
        &format!("deploy path={}", good.display()),
        &format!("id={id_b:08x}"),
        "rollback",
        "uid=",
        "pid=",
    ] {
        assert!(audit.contains(want), "{want}: {audit}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
