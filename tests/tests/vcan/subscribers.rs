//! Issue 13 over vcan: a flood of live subscribers against the real handd while handsim runs
//! the closed loop. Half of them never read: they are dropped (their sockets end, handd logs
//! it), the readers keep receiving one line per tick, and no tick misses its deadline.

use std::io::{Read, Write};
use std::os::unix::net::UnixStream;
use std::path::Path;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use driver::live::Live;

use handstack_tests::vcan::monitor::now_us;
use handstack_tests::vcan::procs::DEADLINE_SLACK_MS;
use handstack_tests::vcan::stall::{softnet_drops, StallMeter};
use handstack_tests::vcan::stream_breaks::judge_not_active;

use super::{Rig, ALL};

/// Ten subscribers that read every line until `until`.
fn spawn_readers(socket: &Path, until: Instant) -> Vec<JoinHandle<Vec<Live>>> {
    (0..10)
        .map(|_| {
            let socket = socket.to_path_buf();
            std::thread::spawn(move || {
                let sub = driver::control::subscribe(&socket, Some(50)).expect("subscribed");
                let mut lines = Vec::new();
                for live in sub {
                    lines.push(live.expect("a Live line"));
                    if Instant::now() >= until {
                        break;
                    }
                }
                lines
            })
        })
        .collect()
}

/// A reading subscriber's lines over 4 s of the closed loop.
/// `excused_stop`: the bus shows handd in a stop the simulated amplifier's stream caused
/// (`stream_breaks`) when the readers ended, so a last line SAFE on the stream's faults only
/// is what handd must say.
fn check_reader(i: usize, lines: &[Live], excused_stop: bool) {
    assert!(
        lines.len() >= 40,
        "reader {i}: {} lines in 4 s",
        lines.len()
    );
    assert!(
        lines.windows(2).all(|w| w[1].tick > w[0].tick),
        "reader {i}: ticks go forward"
    );
    let last = lines.last().expect("a line");
    let stream_stop = excused_stop
        && !last.faults.is_empty()
        && last
            .faults
            .iter()
            .all(|f| f == "invalid_window" || f == "emg_silence");
    assert!(
        last.state == "RUNNING" || stream_stop,
        "reader {i}: {last:?}"
    );
    assert!(last.counters.frames_rx > 0, "reader {i}: {last:?}");
    // hand.dbc's worst case for the whole bus is 46.4 % (mostly the EMG frames).
    assert!(
        last.bus_load > 0.3 && last.bus_load < 0.55,
        "reader {i}: bus load {}",
        last.bus_load
    );
    assert!(last.channels.iter().any(|c| c.rms_uv > 0.0), "{last:?}");
}

#[test]
fn h_twenty_subscribers_ten_stuck_no_deadline_miss() {
    let mut rig = Rig::start("subscribers", 100);
    let mut sim = rig.sim("sine", 9.0, &[]);
    std::thread::sleep(Duration::from_millis(2_000));
    let meter = StallMeter::start();
    let st0 = rig.cfg.status(&rig.env);
    let softnet0 = softnet_drops();
    let socket = rig.cfg.socket.clone();

    let readers_from = now_us();
    let until = Instant::now() + Duration::from_secs(4);
    let readers = spawn_readers(&socket, until);
    let stuck: Vec<UnixStream> = (0..10)
        .map(|_| {
            let mut s = UnixStream::connect(&socket).expect("connect");
            s.write_all(b"{\"cmd\":\"subscribe\",\"every_ms\":50}\n")
                .expect("sent");
            s
        })
        .collect();

    // Judged after what the run's other parties say (below), so a failure says where lost
    // frames went.
    let lines: Vec<Vec<Live>> = readers
        .into_iter()
        .map(|r| r.join().expect("reader"))
        .collect();
    let readers_to = now_us();
    for (i, mut s) in stuck.into_iter().enumerate() {
        s.set_read_timeout(Some(Duration::from_secs(3)))
            .expect("timeout");
        let mut rest = Vec::new();
        let r = s.read_to_end(&mut rest);
        assert!(r.is_ok(), "stuck subscriber {i} was not dropped: {r:?}");
    }
    let st = rig.cfg.status(&rig.env);
    let judged = meter
        .stop()
        .judge(&st0, &st, u64::from(DEADLINE_SLACK_MS) * 1_000);
    sim.wait_success(Duration::from_secs(60));
    // Where EMG frames can be lost between handsim's amplifier and handd: refused by vcan's
    // transmit queue or skipped by a stalled handsim (handsim's own count), dropped from the
    // kernel's receive backlog (softnet), or from handd's socket (its kernel_drops).
    let amp = sim
        .output()
        .lines()
        .find(|l| l.contains("amplifier transmits refused"))
        .unwrap_or("handsim printed no amplifier line")
        .to_owned();
    let softnet = softnet0
        .zip(softnet_drops())
        .map(|(a, b)| (b - a).to_string());
    println!(
        "subscribers: EMG on the way to handd: {amp}; the kernel's receive backlog dropped {} \
         frames; handd's socket {}; handd lost {} samples, {} E2E errors",
        softnet.as_deref().unwrap_or("(unreadable)"),
        st.bus.counters.kernel_drops,
        st.samples_lost,
        lines
            .iter()
            .filter_map(|l| l.last())
            .map(|l| l.counters.e2e_errors)
            .max()
            .unwrap_or(0)
    );
    let seen = rig.monitor.snapshot();
    let verdict = judge_not_active(&seen, readers_from, u64::MAX, &ALL);
    if !verdict.stretches.is_empty() {
        println!(
            "subscribers: stretches not ACTIVE while the readers ran:\n{}",
            verdict.lines()
        );
    }
    let excused_stop = verdict.ends_excused_at(readers_to);
    for (i, l) in lines.iter().enumerate() {
        check_reader(i, l, excused_stop);
    }
    let dropped = rig
        .handd
        .output()
        .matches("live subscriber dropped")
        .count();
    println!(
        "subscribers: {judged}\n20 subscribers (10 stuck, {dropped} drop log lines); lateness \
         p99 {} us, max {} us",
        st.lateness.p99_us, st.lateness.max_us
    );
    assert!(dropped >= 10, "handd logged {dropped} dropped subscribers");
    assert_eq!(
        judged.handd, 0,
        "handd missed deadlines with 20 subscribers: {judged}"
    );
    assert!(rig.handd.running(), "handd died:\n{}", rig.handd.output());
}
