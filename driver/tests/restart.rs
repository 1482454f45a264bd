//! handd as a service, on the simulator and a virtual clock: a restart (a new engine and loop,
//! restored from the latch file the old one's writer kept) never undoes an E-stop, a stop or
//! the calibrating hold, and resumes when nothing was latched; a bus that is down at start is
//! waited for, SAFE; the last round before exit is safe stops, each opening a new epoch, so a
//! stale setpoint of the epoch the fingers ran in moves nothing before the next daemon starts.

mod common;

use std::path::{Path, PathBuf};
use std::sync::atomic::Ordering;
use std::time::Duration;

use common::{random_predictor, Rig};
use decoder::dsp::ChainConfig;
use driver::daemon::Runner;
use driver::engine::{Command, Engine, EngineSettings, Hold};
use driver::mem_transport::MemTransport;
use driver::persist::{self, LatchStore, Latches, Restored};
use driver::safety::{ArmError, DaemonState, Fault as DFault};
use hand_dbc::messages::{FingerMode, FingerSetpoint};
use hand_model::dbc::seal;
use hand_model::faults::{Fault, FaultPlan};
use hand_model::patient::Script;
use hand_model::{Clock, VirtualClock};

type Loop = Runner<MemTransport<VirtualClock>, VirtualClock>;

const WAIT: Duration = Duration::from_secs(5);

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("handd-restart-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("scratch directory");
    persist::latch_path(&d)
}

/// A new daemon on the rig's bus, as handd starts one: validated, the latch file read and its
/// latches restored, its writer started. Returns the loop and the control side's store.
fn start_daemon(rig: &Rig, file: &Path) -> (Loop, LatchStore) {
    let now = rig.clock.now_us();
    let restored = persist::load(file);
    let chain = ChainConfig::default().validate().expect("chain");
    let mut engine = Engine::new(&chain, random_predictor(7), EngineSettings::default(), now);
    engine.validated(now);
    engine.restore(now, restored.latches());
    let (publisher, store) =
        persist::spawn_writer(file.to_owned(), restored.on_disk()).expect("writer");
    let transport = MemTransport::new(rig.bus.endpoint(), rig.clock.clone());
    let runner = Runner::new(engine, transport, rig.clock.clone(), 50_000).with_latches(publisher);
    (runner, store)
}

/// The rig with its daemon replaced by one keeping its latches in `file`.
fn rig(plan: FaultPlan, file: &Path) -> (Rig, LatchStore) {
    let mut rig = Rig::new(plan, Script::resting(60_000_000));
    let (runner, store) = start_daemon(&rig, file);
    rig.runner = runner;
    (rig, store)
}

/// "Kills" the daemon (its loop is dropped; its writer has saved what it published) and starts
/// a new one from the file, like systemd 1 s later. Returns the restart time.
fn restart(rig: &mut Rig, file: &Path, store: &mut LatchStore) -> u64 {
    let t = rig.clock.now_us() + 1_000_000;
    rig.run_until(t); // the old daemon keeps running until then; the bus goes on
    let (runner, s) = start_daemon(rig, file);
    rig.runner = runner;
    *store = s;
    t
}

fn assert_only_stops(rig: &Rig, from: u64, to: u64, what: &str) {
    let sps: Vec<_> = rig
        .setpoints()
        .into_iter()
        .filter(|s| s.0 >= from && s.0 <= to)
        .collect();
    assert!(
        sps.len() >= 5 * 10,
        "{what}: setpoints keep going out ({})",
        sps.len()
    );
    assert!(
        sps.iter()
            .all(|s| s.2 == FingerMode::SafeStop && s.3 == 0.0 && s.4 == 0.0),
        "{what}: only safe stops until arm"
    );
}

fn assert_runs(rig: &Rig, from: u64, to: u64, what: &str) {
    assert_eq!(
        rig.runner.engine().state(),
        DaemonState::Running,
        "{what}: {}",
        rig.runner.engine().faults()
    );
    let active = rig
        .setpoints()
        .into_iter()
        .filter(|s| s.0 >= from && s.0 <= to && s.2 == FingerMode::Active)
        .count();
    assert!(active > 0, "{what}: the fingers are driven again");
}

/// The first setpoint each finger got after `from` (a daemon started then).
fn first_modes(rig: &Rig, from: u64) -> Vec<FingerMode> {
    (0..5)
        .map(|f| {
            rig.setpoints()
                .into_iter()
                .find(|s| s.0 > from && s.1 == f)
                .expect("a setpoint")
                .2
        })
        .collect()
}

fn arm(rig: &mut Rig) -> Result<(), ArmError> {
    let now = rig.clock.now_us();
    rig.runner.engine_mut().command(now, Command::Arm)
}

#[test]
fn an_estop_latched_before_a_crash_holds_after_the_restart_until_arm() {
    let file = scratch("estop");
    let mut plan = FaultPlan::new();
    plan.add(Fault::EStop, 2_000_000, 2_100_000).expect("plan");
    let (mut rig, mut store) = rig(plan, &file);
    rig.run_until(1_900_000);
    assert_eq!(rig.runner.engine().state(), DaemonState::Running);
    rig.run_until(2_300_000);
    assert!(rig.runner.engine().faults().contains(DFault::EStop));
    assert!(
        store.wait_written(|l| l.faults.contains(DFault::EStop), WAIT),
        "the E-stop latch reaches the file"
    );
    let t = restart(&mut rig, &file, &mut store);
    rig.run_until(t + 3_000_000);
    assert_only_stops(&rig, t, t + 3_000_000, "E-stop after the restart");
    assert_eq!(rig.runner.engine().state(), DaemonState::Safe);
    assert!(rig.runner.engine().faults().contains(DFault::EStop));
    arm(&mut rig).expect("arm");
    let armed = rig.clock.now_us();
    rig.run_until(armed + 2_000_000);
    assert_runs(&rig, armed, armed + 2_000_000, "after arm");
    assert!(
        store.wait_written(Latches::is_empty, WAIT),
        "arm clears the file's latches too"
    );
}

#[test]
fn a_technicians_stop_holds_after_the_restart_until_arm() {
    let file = scratch("stop");
    let (mut rig, mut store) = rig(FaultPlan::new(), &file);
    rig.run_until(2_000_000);
    assert_eq!(rig.runner.engine().state(), DaemonState::Running);
    let now = rig.clock.now_us();
    rig.runner
        .engine_mut()
        .command(now, Command::Stop)
        .expect("stop");
    rig.run_until(2_100_000);
    assert!(store.wait_written(|l| l.faults.contains(DFault::StopRequested), WAIT));
    let t = restart(&mut rig, &file, &mut store);
    rig.run_until(t + 3_000_000);
    assert_only_stops(&rig, t, t + 3_000_000, "stop after the restart");
    assert!(rig.runner.engine().faults().contains(DFault::StopRequested));
    arm(&mut rig).expect("arm");
    let armed = rig.clock.now_us();
    rig.run_until(armed + 2_000_000);
    assert_runs(&rig, armed, armed + 2_000_000, "after arm");
}

#[test]
fn the_calibrating_hold_survives_a_restart_and_needs_a_deploy_then_arm() {
    let file = scratch("hold");
    let (mut rig, mut store) = rig(FaultPlan::new(), &file);
    rig.run_until(2_000_000);
    let now = rig.clock.now_us();
    rig.runner
        .engine_mut()
        .command(now, Command::Calibrating)
        .expect("hold");
    rig.run_until(2_100_000);
    assert!(store.wait_written(|l| l.hold == Hold::Calibrating, WAIT));
    let t = restart(&mut rig, &file, &mut store);
    rig.run_until(t + 2_000_000);
    assert_eq!(rig.runner.engine().hold(), Hold::Calibrating);
    assert_eq!(
        arm(&mut rig),
        Err(ArmError::Calibrating),
        "arm is refused until a deploy"
    );
    rig.run_until(t + 3_000_000);
    assert_only_stops(&rig, t, t + 3_000_000, "the hold after the restart");
    let (tx, rx) = std::sync::mpsc::sync_channel(1);
    let now = rig.clock.now_us();
    rig.runner
        .engine_mut()
        .command(now, Command::swap(random_predictor(8), 0x0088, tx))
        .expect("deploy");
    assert!(rx.try_recv().expect("swapped").swapped);
    rig.run_until(t + 4_000_000);
    assert!(store.wait_written(|l| l.hold == Hold::Deployed, WAIT));
    assert_only_stops(&rig, t, t + 4_000_000, "deployed but not armed");
    arm(&mut rig).expect("arm after the deploy");
    let armed = rig.clock.now_us();
    rig.run_until(armed + 2_000_000);
    assert_runs(&rig, armed, armed + 2_000_000, "after deploy and arm");
    assert!(store.wait_written(Latches::is_empty, WAIT));
}

#[test]
fn a_restart_with_nothing_latched_resumes_in_fresh_epochs() {
    let file = scratch("resume");
    let (mut rig, mut store) = rig(FaultPlan::new(), &file);
    rig.run_until(2_000_000);
    assert_eq!(rig.runner.engine().state(), DaemonState::Running);
    assert!(
        store.wait_written(Latches::is_empty, WAIT),
        "an empty set is on disk"
    );
    let old_epochs = rig.runner.engine().epochs();
    let t = restart(&mut rig, &file, &mut store);
    rig.run_until(t + 100_000);
    assert_eq!(
        first_modes(&rig, t),
        vec![FingerMode::SafeStop; 5],
        "every finger gets a safe stop first in the new epoch"
    );
    assert_ne!(rig.runner.engine().epochs(), old_epochs, "fresh epochs");
    rig.run_until(t + 2_000_000);
    assert_runs(&rig, t, t + 2_000_000, "the restarted daemon");
}

#[test]
fn a_corrupt_latch_file_starts_safe_with_stop_requested() {
    let file = scratch("corrupt");
    std::fs::write(&file, "handd-latches 1\nlatched=est").expect("a torn file");
    assert!(matches!(persist::load(&file), Restored::Unusable(_)));
    let (mut rig, store) = rig(FaultPlan::new(), &file);
    rig.run_until(2_000_000);
    assert_only_stops(&rig, 0, 2_000_000, "a corrupt file");
    assert!(rig.runner.engine().faults().contains(DFault::StopRequested));
    assert!(
        store.wait_written(|l| l.faults.contains(DFault::StopRequested), WAIT),
        "the file is rewritten whole"
    );
}

#[test]
fn with_the_bus_down_at_start_handd_stays_up_safe_and_runs_once_it_is_back() {
    let mut rig = Rig::new(FaultPlan::new(), Script::resting(60_000_000));
    let now = rig.clock.now_us();
    let chain = ChainConfig::default().validate().expect("chain");
    let mut engine = Engine::new(&chain, random_predictor(7), EngineSettings::default(), now);
    engine.validated(now);
    let transport = MemTransport::new(rig.bus.endpoint(), rig.clock.clone());
    let link = transport.link();
    link.store(false, Ordering::Release);
    rig.runner = Runner::new(engine, transport, rig.clock.clone(), 50_000).with_bus_down();
    assert_eq!(
        rig.runner.engine().state(),
        DaemonState::Safe,
        "SAFE from the start"
    );
    rig.run_until(3_000_000);
    assert!(!rig.runner.bus_ok());
    assert_eq!(rig.runner.engine().state(), DaemonState::Safe);
    assert!(
        rig.setpoints().is_empty(),
        "nothing is sent on a bus that is down"
    );
    assert!(
        rig.runner.engine().counters().ticks >= 59,
        "the loop keeps ticking"
    );
    link.store(true, Ordering::Release);
    rig.run_until(3_100_000);
    assert!(
        rig.runner.bus_ok(),
        "reopened within a tick of the bus coming up"
    );
    assert_eq!(first_modes(&rig, 3_000_000), vec![FingerMode::SafeStop; 5]);
    rig.run_until(5_000_000);
    assert_runs(
        &rig,
        3_000_000,
        5_000_000,
        "once the bus is back, without arm",
    );
    assert!(rig.runner.engine().faults().is_empty());
}

#[test]
fn shutdown_sends_one_round_of_safe_stops_in_new_epochs_and_saves_the_latches() {
    let file = scratch("sigterm");
    let (mut rig, _store) = rig(FaultPlan::new(), &file);
    rig.run_until(2_000_000);
    assert_eq!(rig.runner.engine().state(), DaemonState::Running);
    let now = rig.clock.now_us();
    rig.runner
        .engine_mut()
        .command(now, Command::Stop)
        .expect("stop");
    // Running again after arm, so the last setpoints before the exit are ACTIVE.
    rig.run_until(2_100_000);
    arm(&mut rig).expect("arm");
    rig.run_until(4_000_000);
    assert_runs(&rig, 3_500_000, 4_000_000, "before SIGTERM");
    let before = rig.seen.len();
    let running = rig.runner.engine().epochs();
    let (sent, saved) = rig.runner.shutdown(WAIT);
    assert_eq!(sent, 5);
    assert!(saved, "the latches are on disk before exit");
    assert_eq!(persist::load(&file).on_disk(), Some(Latches::default()));
    while let Some(r) = rig.probe.receive_timestamped() {
        rig.seen.push((r.time_us.unwrap_or(0), r.frame));
    }
    let last: Vec<_> = rig.seen[before..]
        .iter()
        .filter_map(|(_, f)| FingerSetpoint::decode(f.raw_id(), f.data()).ok())
        .collect();
    assert_eq!(last.len(), 5, "one setpoint per finger");
    for m in &last {
        let f = m.instance();
        assert_eq!(
            (m.mode(), m.force(), m.velocity()),
            (FingerMode::SafeStop, 0.0, 0.0),
            "finger {f}"
        );
        assert_eq!(
            m.epoch(),
            running[f].wrapping_add(1),
            "finger {f}: the last round opens the epoch after the one it ran in"
        );
    }
}

/// The finger the stale setpoint is aimed at (index).
const STALE_FINGER: usize = 1;

/// The daemon has exited: only the simulated hand runs on, to `t_end_us`.
fn world_until(rig: &mut Rig, t_end_us: u64) {
    let mut now = rig.clock.now_us();
    while now < t_end_us {
        now += 1000;
        rig.clock.set_us(now);
        rig.world.step(now);
        while let Some(r) = rig.probe.receive_timestamped() {
            rig.seen.push((r.time_us.unwrap_or(now), r.frame));
        }
    }
}

/// An ACTIVE setpoint of `epoch` for `STALE_FINGER` with alive counter `counter` and the
/// right CRC (E2E accepts it), force of the velocity's sign (the controller moves only then).
fn inject_active(rig: &mut Rig, epoch: u16, counter: u8, velocity: f64) {
    let force = 20.0_f64.copysign(velocity);
    let mut frame = FingerSetpoint::new(STALE_FINGER, FingerMode::Active, force, velocity, epoch)
        .expect("in range")
        .to_frame();
    seal(
        &mut frame,
        FingerSetpoint::E2E[STALE_FINGER],
        counter & 0x0F,
        false,
    );
    rig.probe.send(&frame).expect("the bus is on");
}

/// Issue 29: between handd's exit and the next process's first SAFE_STOP, inside the
/// controllers' 150 ms timeout, an ACTIVE setpoint of the epoch the fingers ran in (right
/// CRC, alive counter in sequence: a frame left in a queue, or a replay) is ignored and
/// counted; the same frame in the epoch the last round opened moves the finger (the control:
/// the controller hears it and has not braked). Before the last round opened a new epoch,
/// the stale frame was followed.
#[test]
fn after_shutdown_a_stale_setpoint_of_the_running_epoch_moves_no_finger() {
    let file = scratch("sigterm-stale");
    let (mut rig, _store) = rig(FaultPlan::new(), &file);
    rig.run_until(2_000_000);
    assert_eq!(rig.runner.engine().state(), DaemonState::Running);
    let running = rig.runner.engine().epoch(STALE_FINGER);
    let (sent, _) = rig.runner.shutdown(WAIT);
    assert_eq!(sent, 5);
    let t0 = rig.clock.now_us();
    world_until(&mut rig, t0 + 5_000);
    let last = rig
        .seen
        .iter()
        .rev()
        .find_map(|(_, f)| {
            (f.raw_id() == FingerSetpoint::IDS[STALE_FINGER]).then_some(())?;
            FingerSetpoint::decode(f.raw_id(), f.data()).ok()
        })
        .expect("the last round reached the bus");
    assert_eq!(
        last.mode(),
        FingerMode::SafeStop,
        "the last round is a safe stop"
    );
    let node = |rig: &Rig| {
        let n = rig.world.fingers().nth(STALE_FINGER).expect("finger");
        (n.physics().angle_rad, n.epoch_gate().ignored())
    };
    let (p0, n0) = node(&rig);
    let v = if p0 < 0.8 { 4.0 } else { -4.0 };
    inject_active(&mut rig, running, last.counter() + 1, v);
    world_until(&mut rig, t0 + 45_000);
    let (p1, n1) = node(&rig);
    assert_eq!(
        p1, p0,
        "a stale ACTIVE setpoint of the epoch the fingers ran in moved the finger after \
         handd's last round (the round did not retire that epoch)"
    );
    assert_eq!(
        n1,
        n0 + 1,
        "the controller counts the stale frame it ignored"
    );
    assert_ne!(last.epoch(), running, "the last round opened a new epoch");
    inject_active(&mut rig, last.epoch(), last.counter() + 2, v);
    world_until(&mut rig, t0 + 85_000);
    let moved = (node(&rig).0 - p0).abs();
    println!(
        "after shutdown: stale frame of epoch {running:#06x} ignored; the control in \
         {:#06x} moved {moved:.3} rad",
        last.epoch()
    );
    assert!(
        moved > 0.02,
        "the control moved the finger only {moved} rad: the test cannot tell an ignored \
         frame from one that does not reach the controller"
    );
}
