//! Every fault of the simulated world's list, on a virtual clock: the time from its onset to
//! safe-stop setpoints on the bus (or the one finger's disable), and the recovery rule.

mod common;

use common::Rig;
use driver::engine::{Command, WindowProblem};
use driver::safety::{DaemonState, Fault as DFault};
use hand_dbc::messages::FingerMode;
use hand_model::faults::{CrcTarget, Fault, FaultPlan};
use hand_model::patient::Script;
use hand_model::world::PatientMode;

const ONSET: u64 = 2_000_000;
const TICK: u64 = 50_000;

fn rig(fault: Fault, until: u64) -> Rig {
    let mut plan = FaultPlan::new();
    plan.add(fault, ONSET, until).unwrap();
    Rig::new(plan, Script::resting(20_000_000))
}

/// Runs to the onset, checks the hand was running, runs `after` more, and returns the time from
/// onset to stop of all fingers (or `finger`).
fn time_to_stop(rig: &mut Rig, after: u64, finger: Option<usize>) -> u64 {
    rig.run_until(ONSET - 1000);
    assert_eq!(
        rig.runner.engine().state(),
        DaemonState::Running,
        "running before the fault: {} {:?}",
        rig.runner.engine().faults(),
        rig.runner.engine().counters()
    );
    let before: Vec<_> = rig
        .setpoints()
        .into_iter()
        .filter(|s| s.0 > ONSET - 200_000)
        .collect();
    assert!(
        before.iter().all(|s| s.2 == FingerMode::Active),
        "all fingers active before the fault"
    );
    rig.run_until(ONSET + after);
    let t = rig
        .stopped_from(ONSET, ONSET + after, finger)
        .expect("the hand stopped after the fault");
    let dt = t.saturating_sub(ONSET);
    println!("time to stop: {} ms", dt as f64 / 1000.0);
    dt
}

#[test]
fn amplifier_silence_stops_within_100ms_and_recovers_by_itself() {
    let mut r = rig(Fault::AmplifierSilence, ONSET + 300_000);
    let dt = time_to_stop(&mut r, 250_000, None);
    assert!(dt <= 100_000, "{dt} us");
    assert!(
        r.runner.engine().faults().contains(DFault::EmgSilence)
            || r.runner.engine().faults().contains(DFault::InvalidWindow)
    );
    // The window's reason names the silence, 250 ms into it: the newest sample is that old
    // (the stale rule, two ticks, goes before the silence in progress).
    match r.runner.engine().window_problem() {
        Some(WindowProblem::Stale { age_us }) => {
            assert!((240_000..=260_000).contains(&age_us), "{age_us} us")
        }
        other => panic!("window problem {other:?} during the amplifier's silence"),
    }
    // Signal back at +300 ms; the window refills (200 ms) and must stay good for 500 ms.
    r.run_until(ONSET + 300_000 + 600_000);
    assert_eq!(
        r.runner.engine().state(),
        DaemonState::Safe,
        "not before 500 ms of good signal"
    );
    r.run_until(ONSET + 300_000 + 1_200_000);
    assert_eq!(
        r.runner.engine().state(),
        DaemonState::Running,
        "transient fault clears by itself"
    );
    assert_eq!(r.runner.engine().window_problem(), None);
}

#[test]
fn corrupted_emg_crc_stops_within_100ms() {
    let mut r = rig(
        Fault::BadCrc {
            target: CrcTarget::Emg,
            every: 1,
        },
        ONSET + 300_000,
    );
    let dt = time_to_stop(&mut r, 250_000, None);
    assert!(dt <= 100_000, "{dt} us");
    // That many errors latch: no recovery without arm.
    r.run_until(ONSET + 2_000_000);
    assert_eq!(r.runner.engine().state(), DaemonState::Safe);
    assert!(r.runner.engine().faults().contains(DFault::RepeatedE2e));
    let now = r.clock_now();
    r.runner.engine_mut().command(now, Command::Arm).unwrap();
    r.run_until(ONSET + 2_700_000);
    assert_eq!(
        r.runner.engine().state(),
        DaemonState::Running,
        "armed, good signal: running"
    );
}

#[test]
fn counter_jump_stops_within_100ms_and_recovers() {
    let mut r = rig(Fault::CounterJump { by: 40 }, ONSET + 1_000);
    let dt = time_to_stop(&mut r, 200_000, None);
    assert!(dt <= 100_000, "{dt} us");
    r.run_until(ONSET + 1_200_000);
    assert_eq!(
        r.runner.engine().state(),
        DaemonState::Running,
        "a gap is transient"
    );
}

#[test]
fn estop_stops_within_100ms_and_latches() {
    let mut r = rig(Fault::EStop, ONSET + 100_000);
    let dt = time_to_stop(&mut r, 200_000, None);
    assert!(dt <= 100_000, "{dt} us");
    r.run_until(ONSET + 3_000_000);
    assert_eq!(
        r.runner.engine().state(),
        DaemonState::Safe,
        "E-stop latches"
    );
    let now = r.clock_now();
    r.runner.engine_mut().command(now, Command::Arm).unwrap();
    r.run_until(ONSET + 3_600_000);
    assert_eq!(r.runner.engine().state(), DaemonState::Running);
}

#[test]
fn silent_finger_controller_safe_stops_that_finger_alone() {
    let mut r = rig(Fault::MotorSilent { finger: 2 }, ONSET + 500_000);
    let dt = time_to_stop(&mut r, 300_000, Some(2));
    // Taking the finger out needs 100 ms of silence by definition, then the next tick sends its
    // SAFE_STOP (never DISABLED: a controller handd cannot hear may still hear handd, and
    // DISABLED would let its finger coast).
    assert!(dt <= 100_000 + TICK, "{dt} us");
    let after: Vec<_> = r
        .setpoints()
        .into_iter()
        .filter(|s| s.0 > ONSET + 200_000 && s.0 < ONSET + 300_000)
        .collect();
    assert!(after
        .iter()
        .filter(|s| s.1 == 2)
        .all(|s| s.2 == FingerMode::SafeStop));
    assert!(
        after
            .iter()
            .filter(|s| s.1 != 2)
            .all(|s| s.2 == FingerMode::Active),
        "others go on"
    );
    r.run_until(ONSET + 1_200_000);
    assert!(
        !r.runner.engine().finger_disabled(2),
        "back after reporting again for 500 ms"
    );
}

#[test]
fn lead_off_and_saturation_stop_within_100ms() {
    for fault in [
        Fault::LeadOff { channels: 0b100 },
        Fault::Saturation { channels: 0b1 },
    ] {
        let mut r = rig(fault, ONSET + 300_000);
        let dt = time_to_stop(&mut r, 250_000, None);
        assert!(dt <= 100_000, "{fault:?}: {dt} us");
        assert!(
            r.runner.engine().faults().contains(DFault::SignalQuality),
            "{fault:?}"
        );
        r.run_until(ONSET + 1_500_000);
        assert_eq!(
            r.runner.engine().state(),
            DaemonState::Running,
            "{fault:?} is transient"
        );
    }
}

#[test]
fn tolerated_faults_keep_the_hand_running_and_are_counted() {
    for fault in [
        Fault::DropEmgFrames { every: 50 },
        Fault::RepeatEmgFrames { every: 7 },
        Fault::ReorderEmgFrames { every: 5 },
        Fault::UnknownIdBurst {
            id: 0x555,
            count: 2000,
        },
        Fault::BusFlood,
    ] {
        let mut r = rig(fault, ONSET + 500_000);
        r.run_until(ONSET + 800_000);
        let e = r.runner.engine();
        assert_eq!(e.state(), DaemonState::Running, "{fault:?}: {}", e.faults());
        let c = e.counters();
        match fault {
            Fault::DropEmgFrames { .. } => assert!(c.samples_lost > 0, "{c:?}"),
            Fault::UnknownIdBurst { count, .. } => {
                assert!(c.bad_frames >= u64::from(count), "{c:?}")
            }
            Fault::BusFlood => assert!(c.bad_frames > 1000, "{c:?}"),
            _ => {}
        }
        assert_eq!(c.deadline_misses, 0);
    }
}

#[test]
fn bus_off_stops_sending_drops_stale_setpoints_and_comes_back_safe() {
    let mut r = Rig::new(FaultPlan::new(), Script::resting(20_000_000));
    r.run_until(ONSET);
    assert_eq!(r.runner.engine().state(), DaemonState::Running);
    r.bus.set_bus_off(true);
    r.run_until(ONSET + 500_000);
    assert!(r.runner.engine().faults().contains(DFault::BusOff));
    let n_before = r.seen.len();
    let back = r.clock_now();
    r.bus.set_bus_off(false);
    r.run_until(ONSET + 1_500_000);
    // Safe stops for every finger once the reopen backoff (at most 50 ms) is over, without
    // waiting for the next tick.
    let first = r
        .stopped_from(back, ONSET + 1_500_000, None)
        .expect("safe stops after the bus came back");
    let dt = first - back;
    println!(
        "bus back -> safe stops on the bus: {} ms",
        dt as f64 / 1000.0
    );
    assert!(
        dt <= driver::daemon::REOPEN_BACKOFF_US.1 + 1_000,
        "{dt} us from the bus coming back to safe stops"
    );
    let after = r
        .setpoints()
        .into_iter()
        .filter(|s| s.0 > ONSET + 500_000)
        .collect::<Vec<_>>();
    assert!(
        r.seen.len() > n_before,
        "sending resumed after the bus came back"
    );
    assert!(!after.is_empty());
    // Every finger gets SAFE_STOP with zero force and velocity, the ones whose status frames
    // went unread while the bus was off too: never a stale ACTIVE setpoint, never DISABLED.
    assert!(
        after
            .iter()
            .all(|s| s.2 == FingerMode::SafeStop && s.3 == 0.0 && s.4 == 0.0),
        "back in SAFE, nothing stale: {:?}",
        after.iter().find(|s| s.2 != FingerMode::SafeStop)
    );
    let now = r.clock_now();
    r.runner.engine_mut().command(now, Command::Arm).unwrap();
    r.run_until(ONSET + 2_200_000);
    assert_eq!(r.runner.engine().state(), DaemonState::Running);
}

/// A rig whose daemon's receive queue holds `capacity` frames, as a kernel socket's does.
fn queue_rig(capacity: usize) -> Rig {
    Rig::with_bus(
        FaultPlan::new(),
        PatientMode::Script(Script::resting(20_000_000)),
        common::random_predictor(7),
        |t| t,
        |b| b.with_capacity(capacity),
    )
}

/// Stops the daemon (no tick, frames queue) from `ONSET` for `stall_us`, then runs 1 ms more:
/// the setpoints of the first tick after the stall.
fn first_round_after_stall(r: &mut Rig, stall_us: u64) -> Vec<(u64, usize, FingerMode, f64, f64)> {
    r.run_until(ONSET);
    assert_eq!(r.runner.engine().state(), DaemonState::Running);
    r.stall_until(ONSET + stall_us);
    let resumed = r.clock_now();
    r.run_until(resumed + 1_000);
    r.setpoints()
        .into_iter()
        .filter(|s| s.0 >= resumed)
        .collect()
}

#[test]
fn a_stalled_daemon_that_lost_frames_sends_safe_stops_not_its_backlog_then_recovers() {
    // The daemon stops for 500 ms (SIGSTOP, a stalled board) while the amplifier streams; its
    // receive queue (420 frames, about 120 ms of this bus, as the VM kernel's) overflows. Its
    // first tick after must stop the fingers, not drive them from the backlog, and the hand
    // runs again by itself once the signal is good.
    let mut r = queue_rig(420);
    let first = first_round_after_stall(&mut r, 500_000);
    assert_eq!(
        first.len(),
        5,
        "one round of setpoints after the stall: {first:?}"
    );
    assert!(
        first
            .iter()
            .all(|s| s.2 == FingerMode::SafeStop && s.3 == 0.0),
        "the first tick after the stall drove the fingers from its backlog: {first:?}"
    );
    let f = r.runner.engine().faults();
    assert!(
        f.contains(DFault::InvalidWindow) || f.contains(DFault::EmgSilence),
        "{f}"
    );
    r.run_until(ONSET + 500_000 + 1_500_000);
    assert_eq!(
        r.runner.engine().state(),
        DaemonState::Running,
        "not running again 1.5 s after the stall: {}",
        r.runner.engine().faults()
    );
}

#[test]
fn a_late_tick_that_lost_nothing_keeps_the_hand_running() {
    // 80 ms late (more than a period: the deadline it missed is skipped) with every frame
    // still queued: the window at the latest deadline is complete and fresh, so the hand
    // keeps running. A slow wake-up is not a fault.
    let mut r = queue_rig(4_096);
    let first = first_round_after_stall(&mut r, 80_000);
    assert_eq!(
        first.len(),
        5,
        "one round of setpoints after the late tick: {first:?}"
    );
    assert!(
        first.iter().all(|s| s.2 == FingerMode::Active),
        "a late tick with nothing lost stopped the hand: {first:?} ({})",
        r.runner.engine().faults()
    );
    assert_eq!(r.runner.engine().state(), DaemonState::Running);
    // Where its time went, kept for `handctl status`: all of it the wake-up (the virtual
    // clock stands still while the tick reads the 80 ms the bus queued).
    let snap = *r.runner.snapshot().lock().unwrap();
    let late: Vec<_> = snap.late_ticks().collect();
    assert_eq!(late.len() as u64, snap.counters.deadline_misses, "{late:?}");
    assert_eq!(late.len(), 1, "{late:?}");
    let slack = driver::engine::EngineSettings::default().deadline_slack_us;
    assert!(
        late[0].wake_us > slack && late[0].wake_us <= 50_000 && late[0].read_us == 0,
        "{late:?}"
    );
    assert!(
        late[0].frames > 20,
        "the read took in {} frames",
        late[0].frames
    );
}
