//! Issue 30, item 5, in the VM: the guest's wall clock is stepped by -1 h and then to +1 h
//! (a +2 h step) during the closed loop, as NTP's first sync or `date -s` would. handd's
//! receive times are kernel stamps on the wall clock mapped onto its monotonic clock
//! (driver/src/rx_times.rs): it must stay RUNNING through both steps (no stale windows, no
//! SAFE), and with the clock an hour ahead an E-stop frame must still stop every finger within
//! 100 ms, and amplifier silence (handsim stopped) must still be a fault within 100 ms.
//!
//! Measurements: between the steps only the order of frames and `handctl status` are used.
//! The two reaction times are taken after the last step, from the monitor's kernel stamps and
//! this process's wall clock, which are then both on the same (stepped) clock. The clock is set
//! back when the drill ends, passed or failed.

use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use hand_dbc::messages::{FingerMode, HandEstop};
use handstack_tests::vcan::monitor::now_us;
use handstack_tests::vcan::stream_breaks::{judge_not_active, unstepped};
use handstack_tests::vcan::{first_safe_stop_after, setpoints_of};

use super::arming::Armed;
use super::restart::{send_estop, wait_active_after};
use super::{Rig, ALL, DRILL_SILENCE_MS, SAFE_STOP_BAR_US};

const HOUR_S: i64 = 3_600;

/// The wall clock, stepped relative to the true time (kept on the monotonic clock); set back
/// to the true time when dropped.
struct SteppedClock {
    wall0: SystemTime,
    mono0: Instant,
}

impl SteppedClock {
    fn new() -> Self {
        Self {
            wall0: SystemTime::now(),
            mono0: Instant::now(),
        }
    }

    /// Sets the wall clock to the true time plus `offset_s`.
    fn set(&self, offset_s: i64) {
        let truth = (self.wall0 + self.mono0.elapsed())
            .duration_since(UNIX_EPOCH)
            .expect("after the epoch");
        let ts = rustix::time::Timespec {
            tv_sec: truth.as_secs() as i64 + offset_s,
            tv_nsec: i64::from(truth.subsec_nanos()),
        };
        rustix::time::clock_settime(rustix::time::ClockId::Realtime, ts).unwrap_or_else(|e| {
            panic!("clock_settime (the drill steps the wall clock and needs root): {e}")
        });
    }
}

impl Drop for SteppedClock {
    fn drop(&mut self) {
        self.set(0);
    }
}

#[test]
fn field_clock_steps_keep_handd_running_and_reacting() {
    let tape = std::env::temp_dir().join("clock-step.tape");
    let tape_arg = tape.display().to_string();
    let mut rig = Rig::start_with("clock-step", DRILL_SILENCE_MS, &["--tape", &tape_arg]);
    let mut sim = rig.sim("sine", 30.0, &[]);
    wait_active_after(&rig.monitor, 0, Duration::from_secs(10))
        .expect("handd never RUNNING before the steps");
    std::thread::sleep(Duration::from_millis(1_000));
    let clock = SteppedClock::new();
    let mut offset_before = 0;
    for (offset_s, what) in [(-HOUR_S, "-1 h"), (HOUR_S, "+1 h (a +2 h step)")] {
        let step_us = (offset_s - offset_before) * 1_000_000;
        offset_before = offset_s;
        let from = rig.monitor.snapshot().len();
        clock.set(offset_s);
        std::thread::sleep(Duration::from_millis(1_500));
        let st = rig.cfg.status(&rig.env);
        let seen = rig.monitor.snapshot();
        let sps = setpoints_of(&seen[from..]);
        // A stop the simulated amplifier's stream caused is excused, and printed
        // (`stream_breaks`); any other setpoint not ACTIVE still fails.
        // Judged on the stamps with the step taken out, or a silence across it would not show.
        let unstepped = unstepped(&seen[from..], step_us);
        let verdict = judge_not_active(&unstepped, 0, u64::MAX, &ALL);
        let stopped = setpoints_of(&unstepped)
            .iter()
            .filter(|s| s.mode != FingerMode::Active && !verdict.excuses(s.time_us))
            .count();
        let last_sp = setpoints_of(&unstepped).last().map_or(0, |s| s.time_us);
        let excused_now = verdict.ends_excused_at(last_sp)
            && st
                .faults
                .split(',')
                .all(|f| f == "invalid_window" || f == "emg_silence");
        if !verdict.stretches.is_empty() {
            println!(
                "clock step {what}: stretches not ACTIVE:\n{}",
                verdict.lines()
            );
        }
        println!(
            "clock step {what}: {} setpoints in the 1.5 s after it, {stopped} not ACTIVE; \
             status {} ({}), wall-clock steps counted {}",
            sps.len(),
            st.state,
            st.faults,
            st.bus.counters.clock_steps
        );
        if (st.state != "RUNNING" && !excused_now) || stopped > 0 {
            rig.handd.terminate(Duration::from_secs(5));
            print_ticks_around_first_stop(&tape);
        }
        assert!(
            (st.state == "RUNNING" && st.faults == "none") || excused_now,
            "clock step {what}: handd is {} with faults {} (a step must not stale the windows)",
            st.state,
            st.faults
        );
        assert!(
            sps.len() >= 5 * 20,
            "clock step {what}: only {} setpoints in 1.5 s after it",
            sps.len()
        );
        assert_eq!(
            stopped, 0,
            "clock step {what}: {stopped} setpoints were not ACTIVE after it"
        );
        if excused_now {
            // In the recovery of an excused stop: running again before the next step.
            wait_active_after(&rig.monitor, now_us(), Duration::from_secs(2))
                .expect("ACTIVE again after an excused stop");
        }
    }
    let st = rig.cfg.status(&rig.env);
    assert!(
        st.bus.counters.clock_steps >= 2,
        "handd counted {} wall-clock steps, 2 were made",
        st.bus.counters.clock_steps
    );

    // The clock is an hour ahead from here on: the monitor's stamps and now_us() agree.
    let from = rig.monitor.snapshot().len();
    send_estop(&rig.env.iface);
    std::thread::sleep(Duration::from_millis(500));
    let seen = rig.monitor.snapshot();
    let onset = seen[from..]
        .iter()
        .find(|s| {
            s.frame
                .as_ref()
                .is_some_and(|f| f.raw_id() == HandEstop::ID)
        })
        .map(|s| s.time_us)
        .expect("the monitor saw the E-stop frame");
    let stop = first_safe_stop_after(&setpoints_of(&seen), onset, &ALL)
        .expect("every finger safe-stopped after the E-stop frame");
    println!(
        "clock +1 h: E-stop frame -> every finger safe-stopped in {:.1} ms (bar {} ms)",
        (stop - onset) as f64 * 1e-3,
        SAFE_STOP_BAR_US / 1000
    );
    assert!(
        stop - onset <= SAFE_STOP_BAR_US,
        "clock +1 h: safe stop {} us after the E-stop frame",
        stop - onset
    );

    let armed = Armed::now(&rig.env, &rig.cfg.socket);
    let resumed = wait_active_after(&rig.monitor, armed.sent_us, Duration::from_secs(3))
        .expect("clock +1 h: never ACTIVE again after `handctl arm`");
    armed.check("clock +1 h", resumed, &rig.monitor.snapshot());
    std::thread::sleep(Duration::from_millis(500));

    // Amplifier silence: handsim (the amplifier and the finger controllers) stops.
    let silent_at = now_us();
    sim.kill();
    std::thread::sleep(Duration::from_millis(500));
    assert!(rig.handd.running(), "handd died:\n{}", rig.handd.output());
    let seen = rig.monitor.snapshot();
    let stop = first_safe_stop_after(&setpoints_of(&seen), silent_at, &ALL)
        .expect("every finger safe-stopped after the amplifier fell silent");
    let st = rig.cfg.status(&rig.env);
    println!(
        "clock +1 h: amplifier silent -> every finger safe-stopped in {:.1} ms (bar {} ms, \
         silence timeout {DRILL_SILENCE_MS} ms); faults {}",
        (stop - silent_at) as f64 * 1e-3,
        SAFE_STOP_BAR_US / 1000,
        st.faults
    );
    assert!(
        stop - silent_at <= SAFE_STOP_BAR_US,
        "clock +1 h: safe stop {} us after the amplifier fell silent",
        stop - silent_at
    );
    assert!(
        st.faults.contains("emg_silence"),
        "clock +1 h: the silence is not the fault in force: {}",
        st.faults
    );
    drop(clock);
    drop(rig);
}

/// What handd's tape says of the ticks around its first safe stop: for each tick its deadline,
/// its start, the frames read for it and their receive times (handd's monotonic clock).
fn print_ticks_around_first_stop(tape: &std::path::Path) {
    use driver::tape::Entry;
    use hand_dbc::messages::FingerSetpoint;
    let entries = match driver::tape::read(tape) {
        Ok(e) => e,
        Err(e) => {
            println!("handd's tape {} does not read: {e}", tape.display());
            return;
        }
    };
    // (deadline, started, frames, first rx, last rx, any stop sent)
    let mut ticks: Vec<(u64, u64, usize, u64, u64, bool)> = Vec::new();
    let (mut n, mut lo, mut hi) = (0usize, u64::MAX, 0u64);
    for e in &entries {
        match e {
            Entry::Frame { rx_us, .. } => {
                n += 1;
                lo = lo.min(*rx_us);
                hi = hi.max(*rx_us);
            }
            Entry::Tick {
                deadline_us,
                started_us,
            } => {
                ticks.push((*deadline_us, *started_us, n, lo, hi, false));
                (n, lo, hi) = (0, u64::MAX, 0);
            }
            Entry::Out { frame } => {
                let id = frame.raw_id();
                if FingerSetpoint::instance_of(id).is_some() {
                    let stop = FingerSetpoint::decode(id, frame.data())
                        .map(|m| m.mode() != FingerMode::Active)
                        .unwrap_or(true);
                    if let Some(t) = ticks.last_mut() {
                        t.5 |= stop;
                    }
                }
            }
            _ => {}
        }
    }
    let first_active = ticks.iter().position(|t| !t.5).unwrap_or(0);
    let Some(first_stop) = ticks[first_active..].iter().position(|t| t.5) else {
        println!("handd's tape: no stop after the first ACTIVE tick");
        return;
    };
    let at = first_active + first_stop;
    println!(
        "handd's tape, ticks around its first stop (tick {at} of {}):",
        ticks.len()
    );
    for (i, t) in ticks
        .iter()
        .enumerate()
        .take(at + 8)
        .skip(at.saturating_sub(6))
    {
        println!(
            "  tick {i}: deadline {} started +{} us; {} frames rx {}..{}; {}",
            t.0,
            t.1.saturating_sub(t.0),
            t.2,
            if t.2 > 0 { t.3 } else { 0 },
            t.4,
            if t.5 { "stop" } else { "active" }
        );
    }
}
