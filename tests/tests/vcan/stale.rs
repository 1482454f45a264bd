//! Issue 29: a stale setpoint in the window before the next epoch's first SAFE_STOP. handd is
//! stopped (SIGTERM) mid-motion; right after its last round reaches the bus, inside the
//! controllers' 150 ms timeout and before any next handd could open an epoch, an ACTIVE
//! setpoint of the epoch the fingers ran in (right CRC, alive counter in sequence: a frame
//! left in a queue, or a replay) is injected. The last round opens a new epoch, so the
//! controller has retired that one: the finger does not move and the controller reports the
//! ignored frame (FINGER_STATUS fault bit 6). The control: a SAFE_STOP that opens the epoch
//! after the last round's, then the same ACTIVE frame in that epoch, moves the finger, so the
//! stale frame reached a controller that listened. (The control used to be the ACTIVE frame
//! in the last round's own epoch; it then had to arrive within the controller's 150 ms
//! setpoint timeout of the last round, after which the controller retires that epoch too, and
//! a guest stall between the test reading the last round and writing the control made it
//! miss: "moved the finger only 0.000 rad". A new epoch's SAFE_STOP binds the controller
//! whether or not it timed out in between.)

use std::process::Command;
use std::time::{Duration, Instant};

use hand_dbc::messages::{FingerMode, FingerSetpoint, FingerState};
use hand_model::dbc::seal;
use handstack_tests::vcan::monitor::{now_us, reader_of, writer};
use handstack_tests::vcan::Seen;
use socketcan::{CanSocket, EmbeddedFrame, Frame, Socket};

use super::epoch::statuses;
use super::{wait_scenario_start, Rig, DRILL_SILENCE_MS, ONSET_US, RUN_S};

/// The finger the stale setpoint is aimed at (index).
const FINGER: usize = 1;
/// FINGER_STATUS fault bit 6: a setpoint ignored by the epoch rule.
const FAULT_STALE_EPOCH: u8 = 1 << 6;
/// From the stale frame to the control, µs: three statuses (20 ms apart) to see the finger
/// still.
const CONTROL_AFTER_US: u64 = 60_000;
/// How far the finger may drift while the stale frame is judged, rad (2 status LSB).
const STILL_RAD: f64 = 0.002;
/// How far the control must move it at least, rad.
const MOVED_RAD: f64 = 0.02;

/// `FINGER`'s setpoint in `frame`, if it is one.
fn finger_setpoint(frame: &socketcan::CanFrame) -> Option<FingerSetpoint> {
    let socketcan::CanFrame::Data(d) = frame else {
        return None;
    };
    let id = FingerSetpoint::IDS[FINGER];
    (d.raw_id() == id)
        .then(|| FingerSetpoint::decode(id, d.data()).expect("handd's setpoint decodes"))
}

/// Empties `reader`'s queue (it holds the oldest frames since it was opened: the kernel drops
/// new ones when it is full), then waits for the next ACTIVE setpoint of `FINGER`: a tick
/// handd has just sent, so a signal sent now lands while handd runs.
fn next_active_tick(reader: &CanSocket) -> FingerSetpoint {
    reader.set_nonblocking(true).expect("nonblocking");
    while reader.read_frame().is_ok() {}
    reader.set_nonblocking(false).expect("blocking");
    let begun = Instant::now();
    loop {
        assert!(
            begun.elapsed() < Duration::from_secs(3),
            "handd sent no ACTIVE setpoint for finger {FINGER} within 3 s: is it RUNNING?"
        );
        if let Some(sp) = reader.read_frame().ok().as_ref().and_then(finger_setpoint) {
            if sp.mode() == FingerMode::Active {
                return sp;
            }
        }
    }
}

/// handd's setpoints for `FINGER` as the reader gets them, until (and with) the first one that
/// is not ACTIVE: (the last ACTIVE one, the first other one). `active` is the ACTIVE one read
/// just before SIGTERM: the signal may land before handd's next tick, so its first setpoint
/// after it may already be the last round.
fn until_last_round(
    reader: &CanSocket,
    mut active: FingerSetpoint,
) -> (FingerSetpoint, FingerSetpoint) {
    let begun = Instant::now();
    let mut read = 0;
    loop {
        assert!(
            begun.elapsed() < Duration::from_secs(3),
            "handd sent no last round for finger {FINGER} within 3 s of SIGTERM \
             ({read} ACTIVE setpoints read after it, the last with counter {})",
            active.counter()
        );
        let Some(sp) = reader.read_frame().ok().as_ref().and_then(finger_setpoint) else {
            continue;
        };
        if sp.mode() == FingerMode::Active {
            active = sp;
            read += 1;
            continue;
        }
        return (active, sp);
    }
}

/// An ACTIVE setpoint of `epoch` for `FINGER` with alive counter `counter`, right CRC (E2E
/// accepts it) and force of the velocity's sign (the controller moves only then). Returns
/// the time just before it was written.
fn inject(w: &CanSocket, epoch: u16, counter: u8, velocity: f64) -> u64 {
    inject_mode(w, FingerMode::Active, epoch, counter, velocity)
}

/// A setpoint of `mode` (ACTIVE: force and velocity as [`inject`]; otherwise zero) of `epoch`.
fn inject_mode(w: &CanSocket, mode: FingerMode, epoch: u16, counter: u8, velocity: f64) -> u64 {
    let (force, velocity) = if mode == FingerMode::Active {
        (20.0_f64.copysign(velocity), velocity)
    } else {
        (0.0, 0.0)
    };
    let sp = FingerSetpoint::new(FINGER, mode, force, velocity, epoch).expect("in range");
    let mut frame = sp.to_frame();
    seal(
        &mut frame,
        FingerSetpoint::E2E[FINGER],
        counter & 0x0F,
        false,
    );
    let out = socketcan::CanFrame::new(frame.id(), frame.data()).expect("a data frame");
    // Stamped before the write, so no status that answers the frame is counted before it.
    let at = now_us();
    w.write_frame(&out).expect("vcan takes the injected frame");
    at
}

#[test]
fn stale_active_setpoint_before_the_next_epochs_safe_stop_after_sigterm_moves_no_finger() {
    let mut rig = Rig::start("stale", DRILL_SILENCE_MS);
    let mut sim = rig.sim("sine", RUN_S, &[]);
    let w = writer(&rig.env.iface);
    // Only FINGER's setpoints: the last round is one frame, and a reader that queued the
    // amplifier too could have dropped it while the test waited or spawned `kill`.
    let reader = reader_of(
        &rig.env.iface,
        &[FingerSetpoint::IDS[FINGER]],
        Duration::from_millis(100),
    );
    let start = wait_scenario_start(&rig.monitor);
    while now_us() < start + ONSET_US {
        std::thread::sleep(Duration::from_millis(1));
    }
    let before = next_active_tick(&reader);
    let term = Command::new("kill")
        .args(["-TERM", &rig.handd.pid().to_string()])
        .status()
        .expect("kill runs");
    assert!(term.success(), "kill -TERM handd failed");
    let (running, last) = until_last_round(&reader, before);
    let last_at = now_us();
    let here = statuses(&rig.monitor.snapshot(), start, now_us())
        .last()
        .map(|s| s.1)
        .expect("finger status before the stale frame");
    let velocity = if here < 0.8 { 4.0 } else { -4.0 };
    let stale_at = inject(&w, running.epoch(), last.counter() + 1, velocity);
    while now_us() < stale_at + CONTROL_AFTER_US {
        std::thread::sleep(Duration::from_millis(1));
    }
    // The control: the epoch after the last round's, opened by its SAFE_STOP, then ACTIVE.
    let control_epoch = last.epoch().wrapping_add(1);
    let opened_at = inject_mode(
        &w,
        FingerMode::SafeStop,
        control_epoch,
        last.counter() + 2,
        0.0,
    );
    std::thread::sleep(Duration::from_millis(5));
    let control_at = inject(&w, control_epoch, last.counter() + 3, velocity);
    println!(
        "stale: the last round read at 0 ms, the stale frame at {:.1} ms, the control's SAFE_STOP \
         at {:.1} ms and its ACTIVE at {:.1} ms",
        stale_at.saturating_sub(last_at) as f64 / 1000.0,
        opened_at.saturating_sub(last_at) as f64 / 1000.0,
        control_at.saturating_sub(last_at) as f64 / 1000.0
    );
    std::thread::sleep(Duration::from_millis(250));
    rig.handd.wait_success(Duration::from_secs(10));
    sim.wait_success(Duration::from_secs(60));
    let seen = rig.monitor.finish();
    let w = Window {
        running,
        last,
        here,
        velocity,
        stale_at,
        opened_at,
        control_at,
        control_epoch,
    };
    check_stale_ignored(&seen, &w);
    check_control_moved(&seen, &w);
}

/// What the drill did and when (µs on the kernel's time base).
struct Window {
    running: FingerSetpoint,
    last: FingerSetpoint,
    here: f64,
    velocity: f64,
    stale_at: u64,
    opened_at: u64,
    control_at: u64,
    control_epoch: u16,
}

fn check_stale_ignored(seen: &[Seen], w: &Window) {
    let during = statuses(seen, w.stale_at, w.opened_at);
    assert!(
        during.len() >= 2,
        "only {} statuses between the stale frame and the control",
        during.len()
    );
    let (lo, hi) = during.iter().fold((f64::MAX, f64::MIN), |(lo, hi), s| {
        (lo.min(s.1), hi.max(s.1))
    });
    println!(
        "stale: running epoch {:#06x}, handd's last round {:?} in {:#06x}; the stale ACTIVE \
         ({} rad/s) of {:#06x}: finger {FINGER} within [{lo:.3}, {hi:.3}] rad over {} statuses, \
         states {:?}",
        w.running.epoch(),
        w.last.mode(),
        w.last.epoch(),
        w.velocity,
        w.running.epoch(),
        during.len(),
        during.iter().map(|s| s.2).collect::<Vec<_>>()
    );
    assert!(
        during.iter().all(|s| s.2 != FingerState::Active),
        "the controller went ACTIVE on a stale setpoint of the epoch the fingers ran in, after \
         handd's last round (which did not open a new epoch: {:#06x} -> {:#06x})",
        w.running.epoch(),
        w.last.epoch()
    );
    assert!(
        hi - lo <= STILL_RAD,
        "a stale setpoint moved the finger after handd's last round: position {lo:.3}..{hi:.3} rad"
    );
    assert!(
        during.iter().any(|s| s.3 & FAULT_STALE_EPOCH != 0),
        "the controller never reported the stale setpoint it ignored (fault bit 6)"
    );
    assert_ne!(
        w.last.epoch(),
        w.running.epoch(),
        "handd's last round did not open a new epoch"
    );
}

/// The control: the same frame in the epoch after the last round's (opened by its SAFE_STOP)
/// moves the finger.
fn check_control_moved(seen: &[Seen], w: &Window) {
    let before = statuses(seen, w.stale_at, w.control_at)
        .last()
        .map_or(w.here, |s| s.1);
    let after = statuses(seen, w.control_at, w.control_at + 150_000);
    let moved = after
        .iter()
        .map(|s| (s.1 - before).abs())
        .fold(0.0, f64::max);
    println!(
        "stale: the control (same frame, epoch {:#06x}) moved the finger {moved:.3} rad ({} \
         statuses after it)",
        w.control_epoch,
        after.len()
    );
    assert!(
        moved >= MOVED_RAD,
        "the control moved the finger only {moved:.3} rad: the drill cannot tell an ignored \
         frame from one that does not reach the controller"
    );
}
