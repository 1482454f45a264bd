//! `arm` compares the live rest pattern with the running model's calibration (issue 32 item
//! 5), on the real loop and the simulator on a virtual clock: the control handler takes the
//! last second of RMS per channel the loop keeps in its snapshot. The calibration's levels
//! are measured first from the same loop, as from the same fitting: arm is accepted. The same
//! levels with two channels swapped (the electrodes' order differs between the calibration and
//! now) are refused naming both channels, with nothing sent to the loop; the override arms and
//! the audit log says so.

mod common;

use std::path::PathBuf;
use std::sync::mpsc;

use common::Rig;
use driver::config::Config;
use driver::control::Peer;
use driver::protocol::{Reply, Request};
use driver::service::{ControlHandler, COMMAND_QUEUE};
use hand_model::faults::FaultPlan;
use hand_model::patient::{Intent, Script};

const ROOT: Peer = Peer {
    uid: 0,
    gid: 0,
    pid: 1,
};

/// A patient at rest with some residual tone in the thumb and pinky, so that the rest level
/// differs between channels as a real forearm's does (the simulator's plain rest is the same
/// noise floor on every channel).
fn rig() -> Rig {
    let mut script = Script::new();
    script.hold(Intent([0.15, 0.0, 0.0, 0.0, 0.05]), 120_000_000);
    Rig::new(FaultPlan::new(), script)
}

/// The median per channel of the RMS the loop publishes over `ticks` ticks from now.
fn measure(rig: &mut Rig, ticks: u64) -> Vec<f64> {
    let snap = rig.runner.snapshot();
    let mut rows: Vec<Vec<f64>> = Vec::new();
    for _ in 0..ticks {
        let t = rig.clock_now() + 50_000;
        rig.run_until(t);
        let s = *snap.lock().expect("snapshot");
        rows.push(s.channel_rms_uv[..s.channels].to_vec());
    }
    (0..rows[0].len())
        .map(|c| {
            let mut v: Vec<f64> = rows.iter().map(|r| r[c]).collect();
            v.sort_by(f64::total_cmp);
            v[v.len() / 2]
        })
        .collect()
}

fn text(r: &Reply) -> String {
    match r {
        Reply::Ok { message, .. } => message.clone(),
        Reply::Refused { reason } => format!("refused: {reason}"),
    }
}

#[test]
fn arm_is_refused_with_swapped_channels_and_accepted_with_the_match() {
    let dir: PathBuf = std::env::temp_dir().join(format!("handd-restcheck-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch directory");
    let mut config = Config::default();
    config.control.audit_log = dir.join("audit.log");
    let config_path = dir.join("handd.toml");
    config.save_atomic(&config_path).expect("config");

    let mut rig = rig();
    let (tx, rx) = mpsc::sync_channel(COMMAND_QUEUE);
    rig.runner.set_commands(rx);
    rig.run_until(2_000_000);
    // The calibration's rest levels, from this fitting: five seconds of the same rest.
    let calibration = measure(&mut rig, 100);
    let (hi, lo) = {
        let order = |a: &(usize, &f64), b: &(usize, &f64)| a.1.total_cmp(b.1);
        let it = || calibration.iter().enumerate();
        (
            it().max_by(order).expect("a channel").0,
            it().min_by(order).expect("a channel").0,
        )
    };
    println!("calibration rest levels, µV: {calibration:.2?}; swapping {hi} and {lo}");
    assert!(
        calibration[hi] / calibration[lo] > 1.5 * driver::rest_check::MAX_CHANNEL_RATIO,
        "the simulated rest has a pattern to swap: {calibration:?}"
    );

    let mut handler = ControlHandler::new(
        config.clone(),
        config_path.clone(),
        rig.runner.snapshot(),
        tx.clone(),
    )
    .with_rest_levels(Some(calibration.clone()));
    let arm = |force| Request::Arm {
        force_rest_mismatch: force,
    };
    rig.run_until(rig.clock_now() + 1_000_000);
    let reply = handler.handle(arm(false), ROOT);
    let said = text(&reply);
    println!("match: {said}");
    assert!(
        matches!(reply, Reply::Ok { .. }) && said.contains("matches the calibration"),
        "{said}"
    );

    // The electrodes of the two channels swapped since the calibration.
    let mut swapped = calibration.clone();
    swapped.swap(hi, lo);
    let mut handler = ControlHandler::new(config.clone(), config_path, rig.runner.snapshot(), tx)
        .with_rest_levels(Some(swapped));
    rig.run_until(rig.clock_now() + 1_000_000);
    let reply = handler.handle(arm(false), ROOT);
    let said = text(&reply);
    println!("swapped: {said}");
    assert!(said.starts_with("refused:"), "{said}");
    for c in [hi, lo] {
        assert!(said.contains(&format!("channel {c} at ")), "{c}: {said}");
    }
    assert!(
        said.contains("--force-rest-mismatch") && said.contains("patient must be"),
        "{said}"
    );
    let audit = std::fs::read_to_string(&config.control.audit_log).expect("audit log");
    assert_eq!(audit.lines().count(), 1, "only the first arm: {audit}");

    let reply = handler.handle(arm(true), ROOT);
    let said = text(&reply);
    assert!(
        matches!(reply, Reply::Ok { .. }) && said.contains("WARNING"),
        "{said}"
    );
    let audit = std::fs::read_to_string(&config.control.audit_log).expect("audit log");
    let lines: Vec<&str> = audit.lines().collect();
    assert!(lines[0].contains(" arm rest=match level="), "{audit}");
    let (a, b) = (hi.min(lo), hi.max(lo));
    assert!(
        lines[1].contains(&format!(" arm rest=MISMATCH-forced channels={a},{b} ")),
        "{audit}"
    );
    std::fs::remove_dir_all(&dir).expect("clean up");
}
