//! The tape (`driver::tape`, `handd --tape`): a run the loop recorded replays through a fresh
//! engine bit for bit, faults, commands and a bus-off with its recovery included; what reached
//! the bus is what the tape says the engine returned; and a tape that misses one input does
//! not replay (the check can fail).

mod common;

use std::path::{Path, PathBuf};
use std::time::Duration;

use common::{random_predictor, Rig};
use decoder::dsp::ChainConfig;
use driver::daemon::Runner;
use driver::engine::{Command, Engine, EngineSettings};
use driver::mem_transport::MemTransport;
use driver::safety::DaemonState;
use driver::tape::{self, End, Entry, TapeWriter};
use driver::FingerGains;
use hand_dbc::messages::FingerMode;
use hand_dbc::CanFrame;
use hand_model::faults::{CrcTarget, Fault, FaultPlan};
use hand_model::patient::Script;
use hand_model::world::PatientMode;
use hand_model::Clock;

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("handd-tape-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("scratch directory");
    d.join("tape")
}

/// The rig with its daemon replaced by one that records a tape to `path`, as `handd --tape`.
fn taped(plan: FaultPlan, path: &Path) -> (Rig, TapeWriter) {
    let mut rig = Rig::with_predictor(
        plan,
        PatientMode::Script(Script::resting(60_000_000)),
        random_predictor(7),
    );
    let now = rig.clock.now_us();
    let chain = ChainConfig::default().validate().expect("chain");
    let (recorder, writer) = tape::start(path).expect("tape");
    let mut engine = Engine::new(&chain, random_predictor(7), EngineSettings::default(), now);
    engine.record_to(recorder);
    engine.validated(now);
    let transport = MemTransport::new(rig.bus.endpoint(), rig.clock.clone());
    rig.runner = Runner::new(engine, transport, rig.clock.clone(), 50_000);
    (rig, writer)
}

fn replay(entries: &[Entry]) -> tape::Replay {
    let chain = ChainConfig::default().validate().expect("chain");
    tape::replay(
        entries,
        &chain,
        Some(random_predictor(7)),
        EngineSettings::default(),
    )
    .expect("the tape replays")
}

/// A run with a bit of everything: E2E errors, a technician's stop, arm and tune, a bus-off
/// and its recovery (safe stops between ticks), the last round before exit.
fn eventful_run(path: &Path) -> Vec<(u64, CanFrame)> {
    let mut plan = FaultPlan::new();
    plan.add(
        Fault::BadCrc {
            target: CrcTarget::Emg,
            every: 7,
        },
        2_500_000,
        2_700_000,
    )
    .expect("fault");
    let (mut rig, writer) = taped(plan, path);
    rig.run_until(2_000_000);
    assert_eq!(rig.runner.engine().state(), DaemonState::Running);
    let command = |rig: &mut Rig, at: u64, cmd: Command| {
        rig.run_until(at);
        let now = rig.clock.now_us();
        let _ = rig.runner.engine_mut().command(now, cmd);
    };
    command(&mut rig, 3_500_000, Command::Arm);
    command(&mut rig, 4_000_000, Command::Stop);
    command(&mut rig, 4_500_000, Command::Arm);
    let gains = FingerGains {
        kf: 4.0,
        ..FingerGains::default()
    };
    command(&mut rig, 4_700_000, Command::SetGains(2, gains));
    rig.run_until(5_000_000);
    rig.bus.set_bus_off(true);
    rig.run_until(5_400_000);
    rig.bus.set_bus_off(false);
    command(&mut rig, 6_500_000, Command::Arm);
    rig.run_until(8_000_000);
    assert_eq!(rig.runner.engine().state(), DaemonState::Running);
    let (sent, _) = rig.runner.shutdown(Duration::from_secs(1));
    assert_eq!(sent, 5, "the last safe stops");
    assert_eq!(rig.runner.engine().tape().map(|t| t.lost()), Some(0));
    while let Some(r) = rig.probe.receive_timestamped() {
        rig.seen.push((r.time_us.unwrap_or(0), r.frame));
    }
    let seen = std::mem::take(&mut rig.seen);
    drop(rig);
    assert!(writer.finish(), "the tape is written in full");
    seen
}

fn from_handd(f: &CanFrame) -> bool {
    matches!(f.raw_id(), 0x200..=0x204 | 0x300 | 0x301)
}

#[test]
fn a_taped_run_replays_bit_for_bit_and_is_what_reached_the_bus() {
    let path = scratch("eventful");
    let seen = eventful_run(&path);
    let entries = tape::read(&path).expect("the tape reads");
    let kinds = |pred: fn(&Entry) -> bool| entries.iter().filter(|e| pred(e)).count();
    assert_eq!(kinds(|e| matches!(e, Entry::Command { .. })), 5);
    assert!(
        kinds(|e| matches!(e, Entry::Raised { .. })) >= 1,
        "the bus-off"
    );
    assert!(kinds(|e| matches!(e, Entry::NewEpoch)) == 1, "the recovery");
    assert!(kinds(|e| matches!(e, Entry::SafeStops)) >= 1);
    assert!(kinds(|e| matches!(e, Entry::Shutdown)) == 1);
    let r = replay(&entries);
    println!(
        "tape: {} entries, {} ticks; replay matched {} rounds, {} differ",
        entries.len(),
        r.ticks,
        r.matched,
        r.differing
    );
    assert_eq!(r.end, End::Tape);
    assert!(r.ticks >= 159, "only {} ticks", r.ticks);
    assert_eq!(r.differing, 0, "first differences: {:#?}", r.differences);
    assert!(r.matched > r.ticks, "the rounds between ticks too");
    // What handd put on the bus, in order, is what the engine returned minus what the bus
    // refused while it was off: a subsequence of the tape's frames, all of them but those.
    let out: Vec<CanFrame> = entries
        .iter()
        .filter_map(|e| match e {
            Entry::Out { frame } => Some(*frame),
            _ => None,
        })
        .collect();
    let on_bus: Vec<CanFrame> = seen.iter().map(|s| s.1).filter(from_handd).collect();
    let mut k = 0;
    for f in &on_bus {
        while k < out.len() && out[k] != *f {
            k += 1;
        }
        assert!(
            k < out.len(),
            "{f:?} reached the bus but is not on the tape"
        );
        k += 1;
    }
    // The bus was off for 400 ms: at most 8 ticks of 7 frames were refused.
    let refused = out.len() - on_bus.len();
    assert!(
        refused <= 8 * 7,
        "only {} frames on the bus of {} on the tape",
        on_bus.len(),
        out.len()
    );
}

#[test]
fn a_tape_missing_one_input_or_with_another_receive_time_does_not_replay() {
    let path = scratch("tampered");
    eventful_run(&path);
    let entries = tape::read(&path).expect("the tape reads");
    // An EMG frame in the middle of the first running stretch.
    let i = entries
        .iter()
        .position(|e| matches!(e, Entry::Frame { rx_us, frame } if *rx_us > 3_000_000 && frame.raw_id() == 0x100))
        .expect("an EMG frame at 3 s");
    let mut missing = entries.clone();
    missing.remove(i);
    let r = replay(&missing);
    assert!(r.differing > 0, "a lost EMG frame went unnoticed");
    // The same frame received after the deadline of the tick that had it: moved past that
    // tick's `T` line, with its time.
    let mut late = entries.clone();
    let e = late.remove(i);
    let t = late[i..]
        .iter()
        .position(|e| matches!(e, Entry::Tick { .. }))
        .expect("a tick after it")
        + i;
    let Entry::Tick { deadline_us, .. } = late[t] else {
        unreachable!()
    };
    let Entry::Frame { frame, .. } = e else {
        unreachable!()
    };
    late.insert(
        t + 1,
        Entry::Frame {
            rx_us: deadline_us + 1,
            frame,
        },
    );
    let r = replay(&late);
    assert!(
        r.differing > 0,
        "a frame moved to the next tick went unnoticed"
    );
}

#[test]
fn a_cut_off_or_foreign_file_is_refused_or_read_up_to_the_cut() {
    let path = scratch("cut");
    eventful_run(&path);
    let text = std::fs::read_to_string(&path).expect("tape");
    // handd killed while writing: the half line at the end is left out.
    let cut = &text[..text.len() - 3];
    std::fs::write(&path, cut).expect("write");
    let entries = tape::read(&path).expect("reads up to the cut");
    assert_eq!(entries.len(), text.lines().count() - 2);
    std::fs::write(&path, "(1.000000) vcan0 100#00\n").expect("write");
    let err = tape::read(&path).expect_err("a candump log is not a tape");
    assert!(err.to_string().contains("not a handstack tape"), "{err}");
    std::fs::write(&path, format!("{}\nV 1\nT 2\n", tape::HEADER)).expect("write");
    let err = tape::read(&path).expect_err("a bad line");
    assert!(err.to_string().contains("tape line 3"), "{err}");
}

/// The loop reads the bus between ticks ([`driver::daemon::READ_EVERY_US`]) so a tick's own
/// read is short: what reached the bus is, bit for bit and at the same times, what a loop
/// reading only at its deadlines sends; and just before each deadline at most one read's
/// worth of frames waits, against a whole period's without the early reads.
#[test]
fn reading_between_ticks_changes_nothing_a_tick_sends() {
    const END_US: u64 = 3_000_000;
    let plan = || {
        let mut p = FaultPlan::new();
        p.add(
            Fault::BadCrc {
                target: CrcTarget::Emg,
                every: 3,
            },
            1_200_000,
            1_400_000,
        )
        .expect("fault");
        p
    };
    let mut early = Rig::new(plan(), Script::resting(10_000_000));
    let mut late = Rig::new(plan(), Script::resting(10_000_000));
    // Just before each deadline: the frames that wait for the tick's read.
    let waiting = |rig: &mut Rig, ticks_only: bool| {
        let mut most = 0;
        while rig.clock_now() < END_US {
            let before = rig.runner.next_deadline_us() - 1000;
            if ticks_only {
                rig.run_ticks_only_until(before);
            } else {
                rig.run_until(before);
            }
            most = most.max(rig.runner.transport().pending());
            let t = rig.clock_now() + 1000;
            if ticks_only {
                rig.run_ticks_only_until(t);
            } else {
                rig.run_until(t);
            }
        }
        most
    };
    let early_most = waiting(&mut early, false);
    let late_most = waiting(&mut late, true);
    // Each start draws a fresh setpoint epoch (its CRC with it): the setpoints are compared
    // decoded, the heartbeat and the diagnostics frame raw.
    let others = |rig: &Rig| -> Vec<(u64, CanFrame)> {
        rig.seen
            .iter()
            .filter(|(_, f)| matches!(f.raw_id(), 0x300 | 0x301))
            .cloned()
            .collect()
    };
    let (a, b) = (early.setpoints(), late.setpoints());
    println!(
        "early reads: {} setpoints, at most {early_most} frames waiting at a deadline; ticks \
         only: {} setpoints, at most {late_most} waiting",
        a.len(),
        b.len()
    );
    assert!(a.len() >= 5 * 55, "only {} setpoints in 3 s", a.len());
    assert!(
        a.iter().any(|s| s.2 == FingerMode::Active)
            && a.iter().any(|s| s.2 == FingerMode::SafeStop),
        "the run shows both ACTIVE setpoints and the bad CRCs' safe stops"
    );
    assert_eq!(a, b, "the setpoints differ when handd reads between ticks");
    assert_eq!(
        others(&early),
        others(&late),
        "the heartbeat or the diagnostics differ when handd reads between ticks"
    );
    let per_ms = 3; // three EMG frames each ms, besides the statuses
    let read_ms = (driver::daemon::READ_EVERY_US / 1000) as usize;
    assert!(
        early_most <= (read_ms + 2) * (per_ms + 1),
        "{early_most} frames waited for a tick's read with early reads every {read_ms} ms"
    );
    assert!(
        late_most >= 40 * per_ms,
        "{late_most} frames waited for a tick reading at its deadline only: the rig does not \
         show what early reads remove"
    );
}
