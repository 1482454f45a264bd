//! Issue 16: no stale setpoint can move a finger. After a bus-off and handd's recovery, an
//! ACTIVE setpoint of the epoch before the bus-off, injected with a raw socket with a correct
//! CRC and an alive counter in sequence (the worst case of a frame left in a queue), does not
//! move the simulated finger; the same frame in the epoch the controller follows once handd's
//! stream is trusted again does (the control that shows the injection reaches the controller
//! and would move it).

use std::time::{Duration, Instant};

use hand_dbc::messages::{FingerMode, FingerSetpoint, FingerState, FingerStatus};
use hand_model::dbc::seal;
use handstack_tests::vcan::monitor::{now_us, writer, Seen};
use socketcan::{CanSocket, EmbeddedFrame, Frame, Socket};

use super::{wait_scenario_start, Rig, DRILL_SILENCE_MS, ONSET_US, RUN_S};

/// The finger the stale setpoints are aimed at (index).
const FINGER: usize = 1;
/// FINGER_STATUS fault bit 6: a setpoint ignored by the epoch rule.
const FAULT_STALE_EPOCH: u8 = 1 << 6;
/// Injections of the stale frame, one after every other setpoint of handd's. Each is a second
/// sender in handd's stream: the first reaches the epoch rule; Profile 1's sync counter holds
/// back the frames after it, so the controller may brake by itself and retire handd's epoch
/// too (handd then binds a new one with its safe stops).
const STALE_INJECTIONS: usize = 5;
/// After the stale frames, time for the controller to brake by itself (150 ms), handd to bind
/// it to a new epoch and its stream to be trusted again, ms.
const SETTLE_MS: u64 = 800;
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

/// Right after handd's setpoint with counter c, an ACTIVE setpoint of `epoch` with counter
/// c + 1 and the right CRC: E2E accepts it. Returns when it was written.
fn inject_after(reader: &CanSocket, w: &CanSocket, epoch: u16, velocity: f64) -> u64 {
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
    w.write_frame(&out).expect("vcan takes the injected frame");
    now_us()
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
    std::thread::sleep(Duration::from_millis(SETTLE_MS));
    reader.set_nonblocking(true).expect("nonblocking");
    while reader.read_frame().is_ok() {}
    reader.set_nonblocking(false).expect("blocking");
    let current = next_handd_setpoint(reader).epoch();
    let control_at = inject_after(reader, w, current, velocity);
    Injected {
        onset,
        old,
        current,
        here,
        velocity,
        stale_from,
        control_at,
    }
}

#[test]
fn stale_active_setpoint_of_the_old_epoch_after_bus_off_recovery_does_not_move_the_finger() {
    let rig = Rig::start("epoch", DRILL_SILENCE_MS);
    let mut sim = rig.sim("sine", RUN_S, &[]);
    let w = writer(&rig.env.iface);
    let reader = CanSocket::open(&rig.env.iface).expect("a reader socket");
    reader
        .set_read_timeout(Duration::from_millis(100))
        .expect("read timeout");
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
    assert!(
        during.iter().all(|s| s.2 != FingerState::Active),
        "the controller went ACTIVE on a stale setpoint"
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
