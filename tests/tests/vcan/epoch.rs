//! Issue 16: no stale setpoint can move a finger. After a bus-off and handd's recovery, an
//! ACTIVE setpoint of the epoch before the bus-off, injected with a raw socket with a correct
//! CRC and an alive counter in sequence (the worst case of a frame left in a queue), does not
//! move the simulated finger; the same frame in the epoch the controller follows once handd's
//! stream is trusted again does (the control that shows the injection reaches the controller
//! and would move it).

use std::time::{Duration, Instant};

use hand_dbc::messages::{FingerMode, FingerSetpoint, FingerState, FingerStatus};
use hand_model::dbc::seal;
use handstack_tests::vcan::monitor::{now_us, reader_of, writer, Seen};
use socketcan::{CanSocket, EmbeddedFrame, Frame, Socket};

use super::{wait_scenario_start, Rig, DRILL_SILENCE_MS, ONSET_US};

/// The finger the stale setpoints are aimed at (index).
const FINGER: usize = 1;
/// FINGER_STATUS fault bit 6: a setpoint ignored by the epoch rule.
const FAULT_STALE_EPOCH: u8 = 1 << 6;
/// Injections of the stale frame, one after every other setpoint of handd's. Each is a second
/// sender in handd's stream: the first reaches the epoch rule; Profile 1's sync counter holds
/// back the frames after it, so the controller may brake by itself and retire handd's epoch
/// too (handd then binds a new one with its safe stops).
const STALE_INJECTIONS: usize = 5;
/// After the stale frames, the controller brakes by itself (150 ms), handd binds it to a new
/// epoch and its stream is trusted again. The control waits until, for this long, handd's
/// epoch has not changed and the finger's statuses carry no timeout, E2E or stale-epoch fault,
/// ms (a fixed wait failed on a loaded machine).
const QUIET_MS: u64 = 400;
/// The longest the settling may take, ms (measured in the VM: quiet from about 190 ms after
/// the last stale frame on, so the control goes out about 600 ms after it).
const SETTLE_LIMIT_MS: u64 = 2500;
/// The simulated hand's run, s: the bus-off comes at 2.5 s and the control about 1.4 s after
/// it; the rest is margin for a loaded machine (the suite's 5 s left 0.7 s, and a control that
/// comes after the simulator stopped cannot move a finger).
const RUN_S: f64 = 7.0;
/// FINGER_STATUS fault bits 3 (setpoint timeout) and 4 (setpoint E2E).
const FAULT_TIMEOUT_OR_E2E: u8 = (1 << 3) | (1 << 4);
/// How far the finger may drift while the stale frames come, rad (2 status LSB).
const STILL_RAD: f64 = 0.002;
/// How far the control injection must move it at least, rad.
const MOVED_RAD: f64 = 0.02;

/// handd's next setpoint for `FINGER` (its mode is never ACTIVE here: handd is SAFE).
fn next_handd_setpoint(reader: &CanSocket) -> FingerSetpoint {
    let begun = Instant::now();
    loop {
        assert!(
            begun.elapsed() < Duration::from_secs(2),
            "no setpoint of handd for finger {FINGER} within 2 s"
        );
        let Ok(f) = reader.read_frame() else { continue };
        let socketcan::CanFrame::Data(d) = f else {
            continue;
        };
        let id = FingerSetpoint::IDS[FINGER];
        if d.raw_id() != id {
            continue;
        }
        let sp = FingerSetpoint::decode(id, d.data()).expect("handd's setpoint decodes");
        if sp.mode() != FingerMode::Active {
            return sp;
        }
    }
}

/// Attempts at placing one injected frame right after handd's setpoint: one that comes after
/// handd's next setpoint instead (the test process held up for a period, as a loaded VM can)
/// repeats handd's counter, which E2E drops before the epoch rule sees it, and is tried again.
const ATTEMPTS: usize = 5;

/// Right after handd's setpoint with counter c, an ACTIVE setpoint of `epoch` with counter
/// c + 1 and the right CRC: E2E accepts it. Returns the time just before it was written, once
/// it is seen on the bus before handd's next setpoint (in sequence), after at most
/// [`ATTEMPTS`] tries.
fn inject_after(reader: &CanSocket, w: &CanSocket, epoch: u16, velocity: f64) -> u64 {
    for attempt in 1..=ATTEMPTS {
        let handd = next_handd_setpoint(reader);
        // Force of the velocity's sign: the controller moves only when the two agree (hand.dbc).
        let sp = FingerSetpoint::new(
            FINGER,
            FingerMode::Active,
            20.0_f64.copysign(velocity),
            velocity,
            epoch,
        )
        .expect("in range");
        let mut frame = sp.to_frame();
        seal(
            &mut frame,
            FingerSetpoint::E2E[FINGER],
            (handd.counter() + 1) & 0x0F,
            false,
        );
        let out = socketcan::CanFrame::new(frame.id(), frame.data()).expect("a data frame");
        // Stamped before the write: a status stamped after it may already answer the frame
        // (this process can be held up between the write and a later stamp while the
        // simulator runs: one run saw the control frame's ACTIVE counted as the stale one's).
        let at = now_us();
        w.write_frame(&out).expect("vcan takes the injected frame");
        if came_first(reader, out.data()) {
            return at;
        }
        println!(
            "epoch: injection {attempt}/{ATTEMPTS} reached the bus after handd's next setpoint \
             (its counter repeats handd's, E2E drops it): trying again"
        );
    }
    panic!(
        "{ATTEMPTS} injections in a row reached the bus after handd's next setpoint: the test \
         process is held up for whole 50 ms periods"
    );
}

/// Reads on until the injected frame (`data`) or handd's next setpoint for `FINGER` comes:
/// true when the injected one came first, so its counter is next in sequence.
fn came_first(reader: &CanSocket, data: &[u8]) -> bool {
    let begun = Instant::now();
    loop {
        assert!(
            begun.elapsed() < Duration::from_secs(2),
            "neither the injected frame nor handd's next setpoint within 2 s"
        );
        let Ok(socketcan::CanFrame::Data(d)) = reader.read_frame() else {
            continue;
        };
        let id = FingerSetpoint::IDS[FINGER];
        if d.raw_id() != id {
            continue;
        }
        if d.data() == data {
            return true;
        }
        let sp = FingerSetpoint::decode(id, d.data()).expect("a setpoint decodes");
        if sp.mode() != FingerMode::Active {
            return false;
        }
    }
}

/// FINGER_STATUS of `FINGER` in [from, to): (time, position, state, faults).
pub(super) fn statuses(seen: &[Seen], from: u64, to: u64) -> Vec<(u64, f64, FingerState, u8)> {
    seen.iter()
        .filter(|s| (from..to).contains(&s.time_us))
        .filter_map(|s| {
            let f = s.frame.as_ref()?;
            (f.raw_id() == FingerStatus::IDS[FINGER]).then_some(())?;
            let st = FingerStatus::decode(f.raw_id(), f.data()).ok()?;
            Some((s.time_us, st.position(), st.state(), st.faults()))
        })
        .collect()
}

/// The epoch of handd's last setpoint for `FINGER` before `t`.
fn epoch_before(seen: &[Seen], t: u64) -> u16 {
    seen.iter()
        .filter(|s| s.time_us < t)
        .rev()
        .find_map(|s| {
            let f = s.frame.as_ref()?;
            (f.raw_id() == FingerSetpoint::IDS[FINGER]).then_some(())?;
            FingerSetpoint::decode(f.raw_id(), f.data()).ok()
        })
        .map(|sp| sp.epoch())
        .expect("handd sent setpoints before the bus-off")
}

/// What the test did and when (µs on the kernel's time base).
struct Injected {
    start: u64,
    onset: u64,
    old: u16,
    current: u16,
    here: f64,
    velocity: f64,
    stale_from: u64,
    control_at: u64,
}

/// Bus-off at the scenario's onset; 300 ms later (handd recovered in a new epoch), the stale
/// frames, then the control in the current epoch.
fn bus_off_then_inject(rig: &Rig, reader: &CanSocket, w: &CanSocket) -> Injected {
    let start = wait_scenario_start(&rig.monitor);
    while now_us() < start + ONSET_US {
        std::thread::sleep(Duration::from_millis(1));
    }
    let busoff = socketcan::CanErrorFrame::new_error(0x0040, &[0; 8]).expect("error frame");
    w.write_frame(&busoff)
        .expect("vcan accepts an injected error frame");
    let onset = now_us();
    // handd reopens after 10 ms and sends safe stops of a new epoch; 300 ms is well past them.
    std::thread::sleep(Duration::from_millis(300));
    let seen = rig.monitor.snapshot();
    let old = epoch_before(&seen, onset);
    // Flex if the finger is in the lower half of its range, extend otherwise.
    let here = statuses(&seen, onset, now_us())
        .last()
        .map(|s| s.1)
        .expect("finger status after the bus-off");
    let velocity = if here < 0.8 { 4.0 } else { -4.0 };
    // Drain what the reader queued so far: inject right after handd's next frames.
    reader.set_nonblocking(true).expect("nonblocking");
    while reader.read_frame().is_ok() {}
    reader.set_nonblocking(false).expect("blocking");
    let stale_from = inject_after(reader, w, old, velocity);
    for _ in 1..STALE_INJECTIONS {
        next_handd_setpoint(reader);
        inject_after(reader, w, old, velocity);
    }
    let stale_end = now_us();
    let settled = wait_settled(rig, stale_end);
    println!(
        "epoch: handd's stream was trusted again {} ms after the last stale frame",
        (settled - stale_end) / 1000
    );
    reader.set_nonblocking(true).expect("nonblocking");
    while reader.read_frame().is_ok() {}
    reader.set_nonblocking(false).expect("blocking");
    let current = next_handd_setpoint(reader).epoch();
    let control_at = inject_after(reader, w, current, velocity);
    Injected {
        start,
        onset,
        old,
        current,
        here,
        velocity,
        stale_from,
        control_at,
    }
}

/// Waits until handd's epoch for `FINGER` and the finger's faults have been quiet for
/// [`QUIET_MS`] since `from`; returns when they became quiet.
fn wait_settled(rig: &Rig, from: u64) -> u64 {
    loop {
        std::thread::sleep(Duration::from_millis(50));
        let now = now_us();
        assert!(
            now < from + SETTLE_LIMIT_MS * 1000,
            "handd's stream for finger {FINGER} did not settle within {SETTLE_LIMIT_MS} ms of \
             the stale frames (its epoch kept changing or the finger kept reporting faults)"
        );
        let seen = rig.monitor.snapshot();
        let faulted = statuses(&seen, from, now)
            .iter()
            .filter(|s| s.3 & (FAULT_TIMEOUT_OR_E2E | FAULT_STALE_EPOCH) != 0)
            .map(|s| s.0)
            .max();
        let epochs: Vec<(u64, u16)> = seen
            .iter()
            .filter(|s| (from..now).contains(&s.time_us))
            .filter_map(|s| {
                let f = s.frame.as_ref()?;
                (f.raw_id() == FingerSetpoint::IDS[FINGER]).then_some(())?;
                let sp = FingerSetpoint::decode(f.raw_id(), f.data()).ok()?;
                (sp.mode() != FingerMode::Active).then_some((s.time_us, sp.epoch()))
            })
            .collect();
        let changed = epochs
            .windows(2)
            .filter(|p| p[0].1 != p[1].1)
            .map(|p| p[1].0)
            .max();
        let quiet_since = faulted.max(changed).unwrap_or(from).max(from);
        if !epochs.is_empty() && now >= quiet_since + QUIET_MS * 1000 {
            return quiet_since;
        }
    }
}

#[test]
fn stale_active_setpoint_of_the_old_epoch_after_bus_off_recovery_does_not_move_the_finger() {
    let rig = Rig::start("epoch", DRILL_SILENCE_MS);
    let mut sim = rig.sim("sine", RUN_S, &[]);
    let w = writer(&rig.env.iface);
    // Only FINGER's setpoints (handd's and the injected ones): a reader that queued the
    // amplifier too could drop the very frames the drill waits for (see `reader_of`).
    let reader = reader_of(
        &rig.env.iface,
        &[FingerSetpoint::IDS[FINGER]],
        Duration::from_millis(100),
    );
    let i = bus_off_then_inject(&rig, &reader, &w);
    std::thread::sleep(Duration::from_millis(200));
    sim.wait_success(Duration::from_secs(60));
    let seen = rig.monitor.finish();
    drop(rig.handd);
    check_stale_ignored(&seen, &i);
    check_control_moved(&seen, &i);
}

fn check_stale_ignored(seen: &[Seen], i: &Injected) {
    assert_ne!(
        i.current, i.old,
        "handd recovered in the epoch of before the bus-off"
    );
    let during = statuses(seen, i.stale_from, i.control_at);
    assert!(
        during.len() >= 10,
        "only {} statuses while the stale frames came",
        during.len()
    );
    let (lo, hi) = during.iter().fold((f64::MAX, f64::MIN), |(lo, hi), s| {
        (lo.min(s.1), hi.max(s.1))
    });
    println!(
        "epoch: old {:#06x}, after recovery {:#06x}; {STALE_INJECTIONS} stale ACTIVE setpoints \
         ({} rad/s): finger {FINGER} within [{lo:.3}, {hi:.3}] rad over {} statuses",
        i.old,
        i.current,
        i.velocity,
        during.len()
    );
    assert!(
        hi - lo <= STILL_RAD,
        "a stale setpoint moved the finger: position {lo:.3}..{hi:.3} rad"
    );
    let active: Vec<i64> = during
        .iter()
        .filter(|s| s.2 == FingerState::Active)
        .map(|s| s.0 as i64 - i.control_at as i64)
        .collect();
    assert!(
        active.is_empty(),
        "the controller went ACTIVE on a stale setpoint (its ACTIVE statuses, µs from the \
         control frame's write: {active:?})"
    );
    assert!(
        during.iter().any(|s| s.3 & FAULT_STALE_EPOCH != 0),
        "the controller never reported a setpoint ignored by the epoch rule (did the \
         injected frames reach it past E2E?)"
    );
}

/// The control: the same frame in the current epoch moves the finger.
fn check_control_moved(seen: &[Seen], i: &Injected) {
    let before = statuses(seen, i.stale_from, i.control_at)
        .last()
        .map_or(i.here, |s| s.1);
    let end = i.start + (RUN_S * 1e6) as u64;
    assert!(
        i.control_at + 300_000 <= end,
        "the control came {} ms after the bus-off, too late in the simulator's {RUN_S} s run",
        (i.control_at - i.onset) / 1000
    );
    let after = statuses(seen, i.control_at, i.control_at + 150_000);
    let moved = after
        .iter()
        .map(|s| (s.1 - before).abs())
        .fold(0.0, f64::max);
    println!(
        "epoch: the control (same frame, current epoch) moved the finger {moved:.3} rad ({} \
         statuses after it; injected {} ms after the bus-off)",
        after.len(),
        (i.control_at - i.onset) / 1000
    );
    assert!(
        moved >= MOVED_RAD,
        "the control injection moved the finger only {moved:.3} rad: the test cannot tell a \
         stale frame from one that does not reach the controller"
    );
}
