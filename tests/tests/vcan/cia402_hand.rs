//! Issue 26's drills with the whole hand on CiA 402 drives over SocketCAN: every finger moved by
//! a simulated drive (`handsim --drives cia402`, nodes 5-9, cyclic synchronous torque), none by
//! a native controller. handd starts all five, the patient tracks the sine with the index finger
//! (closed loop, R² from the index drive's own TPDO1 torque), then the ring finger's drive trips
//! (EMCY 0x2310): that finger alone gets the quick stop while the other four keep following.
//! Killed, handd stops its heartbeat and every drive stops by itself on its watchdog.

use std::time::Duration;

use hand_dbc::messages::FingerSetpoint;
use hand_model::nodes::DriveFingerConfig;
use hand_model::patient::{Target, TrackingConfig};
use handstack_tests::vcan::monitor::now_us;
use handstack_tests::vcan::procs::{handsim, DEADLINE_SLACK_MS};
use handstack_tests::vcan::stall::StallMeter;
use handstack_tests::vcan::stream_breaks::{emg_silences, judge_not_running};
use handstack_tests::vcan::{scenario_start_us, Monitor, TestConfig, VcanEnv};

use super::calibrated_model;
use super::cia402::{poll_drives, wait_drives, QUICK_STOP, SYNC, WATCHDOG_BAR_US};

/// The tripped finger (the ring's drive, node 8).
const TRIPPED: usize = 3;
/// The tracked finger (the index's drive, node 6).
const TRACKED: usize = 1;
/// The ring's drive trips this long after handsim started, s.
const TRIP_S: f64 = 18.0;
/// handsim's run, s (handd is killed before its end, so the drives' watchdogs are seen).
const RUN_S: f64 = 27.0;
/// The tracking is scored from this long after every drive follows its setpoint (the native
/// closed loop's settling from the scenario's start, where its fingers follow at once).
const SETTLE_US: u64 = 4_000_000;
/// Not scored after an excused stop (`stream_breaks`): the drives' three ticks back to
/// Operation enabled and the patient's finger back on the sine, µs.
const EXCUSED_SETTLE_US: u64 = 1_000_000;
/// The patient's sine's period, for the per-period printout, µs.
const PERIOD_US: u64 = 4_000_000;
/// The CiA 402 state line of a drive that follows its setpoint.
const FOLLOWING: &str = "Operation enabled, following";

fn node(f: usize) -> u32 {
    u32::from(hand_model::nodes::drive::simulated_node_id(f))
}

/// handd.toml's `[fingers.NAME.drive]` for each of the five simulated drives, as a technician
/// writes them for `handsim --drives cia402` (its scaling and node 5 + finger).
fn drive_tables() -> String {
    let s = DriveFingerConfig::SIM_SCALING;
    let mut t = String::new();
    for (f, name) in hand_dbc::hand::FINGER_NAMES.iter().enumerate() {
        t.push_str(&format!(
            "\n[fingers.{name}.drive]\nprofile = \"cia402\"\nnode_id = {}\nmode = \"cst\"\n\
             rated_torque_mnm = {:?}\ngear_ratio = {:?}\nmoment_arm_m = {:?}\n\
             max_torque_permille = {}\nmax_speed_rpm = {}\n",
            node(f),
            s.rated_torque_mnm,
            s.gear_ratio,
            s.moment_arm_m,
            s.max_torque_permille,
            s.max_speed_rpm
        ));
    }
    t.push_str("\n[canopen]\nmaster_node_id = 127\nsync_cob_id = 0x07F\n");
    t
}

#[test]
fn j_every_finger_on_a_drive_tracks_one_trips_alone_and_all_stop_on_their_watchdogs() {
    let env = VcanEnv::get();
    let model = calibrated_model(&env).to_path_buf();
    let dir = env.scratch("cia402-hand");
    let cfg = TestConfig::write(&env, &dir, &model, 100);
    let mut text = std::fs::read_to_string(&cfg.path).expect("read the config");
    text.push_str(&drive_tables());
    std::fs::write(&cfg.path, text).expect("write the config");
    let monitor = Monitor::start(&env.iface);
    let mut handd = cfg.start(&env, &dir);
    let trip = format!("drive-trip:{TRIPPED}@{TRIP_S}..{}", TRIP_S + 0.1);
    let mut sim = handsim(
        &env,
        &dir,
        "handsim",
        "sine",
        RUN_S,
        &["--drives", "cia402", "--fault", &trip],
    );
    let all_follow = |d: &[driver::protocol::DriveLine]| {
        d.len() == 5 && d.iter().all(|l| l.state.starts_with(FOLLOWING))
    };
    let t = wait_drives(
        &cfg,
        "all five drives follow",
        Duration::from_secs(6),
        true,
        all_follow,
    );
    let following_at = now_us();
    // Whether the machine ran while handd was late (`stall`): the CPU meters from here to the
    // kill, and handd's late ticks over the same span.
    let meter = StallMeter::start();
    let mono_to_wall = now_us() as i64 - driver::rt::monotonic_us() as i64;
    let st0 = cfg.query_status();
    println!(
        "cia402 hand: all five drives follow their setpoints {:.0} ms after handsim started",
        t.as_secs_f64() * 1e3
    );
    // The trip: the ring finger stopped with its EMCY named, the other four still following.
    // A timeout is judged after the bus log is read (below), which says whose it was.
    let trip_seen = poll_drives(
        &cfg,
        "the ring drive's trip is seen, the others follow",
        Duration::from_secs(TRIP_S as u64 + 4),
        true,
        |d| {
            d.len() == 5
                && d.iter().enumerate().all(|(f, l)| {
                    if f == TRIPPED {
                        l.faulted && l.state.contains("EMCY") && l.state.contains("0x2310")
                    } else {
                        !l.faulted && l.state.starts_with(FOLLOWING)
                    }
                })
        },
    );
    let tripped_at = now_us();
    if trip_seen.is_ok() {
        std::thread::sleep(Duration::from_millis(3_000));
    }
    // The three seconds after the trip, in which the other four go on (counted below).
    let after_trip = now_us();
    let st1 = cfg.query_status();
    let judged = meter
        .stop()
        .judge(&st0, &st1, u64::from(DEADLINE_SLACK_MS) * 1_000);
    let kill_at = now_us();
    handd.kill();
    std::thread::sleep(Duration::from_millis(600));
    sim.kill();
    let seen = monitor.finish();
    let start = scenario_start_us(&seen);
    let frames: Vec<(u64, u32, Vec<u8>)> = seen
        .iter()
        .filter_map(|s| s.frame.as_ref().map(|f| (s.time_us, f)))
        .filter(|(_, f)| !f.is_extended())
        .map(|(t, f)| (t, f.raw_id(), f.data().to_vec()))
        .collect();
    let of = |id: u32, from: u64, to: u64| -> Vec<&(u64, u32, Vec<u8>)> {
        frames
            .iter()
            .filter(|f| f.1 == id && f.0 > from && f.0 < to)
            .collect()
    };
    // While handd ran, no drive lost its heartbeat: handd's heartbeat (0x77F) on the bus, its
    // largest gap, and each drive's heartbeat-loss EMCY before the kill, if any.
    let beats: Vec<u64> = of(0x77F, start, kill_at).iter().map(|f| f.0).collect();
    let (gap, gap_at) = beats
        .windows(2)
        .map(|w| (w[1] - w[0], w[0] - start))
        .max()
        .unwrap_or((0, 0));
    let lost: Vec<(usize, u64)> = (0..5)
        .filter_map(|f| {
            frames
                .iter()
                .find(|e| e.1 == 0x080 + node(f) && e.0 < kill_at && e.2[..2] == [0x30, 0x81])
                .map(|e| (f, e.0 - start))
        })
        .collect();
    // Whether the simulated world (handsim, in the same guest) stood still in that gap too:
    // the amplifier's silences over 5 ms inside it (ms into the scenario, length, whether it
    // resumed with the next counter). A whole-guest stall stops both; handd alone, only its.
    let in_gap: Vec<String> = emg_silences(&seen, 5_000)
        .iter()
        .filter(|e| e.to_us > start + gap_at && e.from_us < start + gap_at + gap)
        .map(|e| {
            format!(
                "{:.1} ms at {:.3} s{}",
                e.len_us() as f64 * 1e-3,
                (e.from_us - start) as f64 * 1e-6,
                if e.in_sequence { "" } else { " (counter jump)" }
            )
        })
        .collect();
    println!(
        "cia402 hand: handd's heartbeat on the bus: {} in {:.1} s, largest gap {:.1} ms (from \
         {:.3} s into the scenario; the drives followed from {:.3} s); the amplifier's \
         silences in that gap: {in_gap:?}; drives that lost it while handd ran (finger, us \
         into the scenario): {lost:?}",
        beats.len(),
        (kill_at - start) as f64 * 1e-6,
        gap as f64 * 1e-3,
        gap_at as f64 * 1e-6,
        following_at.saturating_sub(start) as f64 * 1e-6
    );
    if gap > 75_000 {
        // A beat missing: what handd put on the bus around it, tick by tick (its RPDO1s,
        // SYNC, heartbeat, HAND_DIAG every tick, HAND_HEARTBEAT every other): a tick that
        // did not run leaves no frame; one whose sends were refused, only its first frames.
        let from = start + gap_at;
        let handd_ids =
            |id: u32| matches!(id, 0x07F | 0x77F | 0x300 | 0x301) || (0x205..=0x209).contains(&id);
        let around: Vec<String> = frames
            .iter()
            .filter(|f| handd_ids(f.1) && f.0 + 5_000 >= from && f.0 <= from + gap + 5_000)
            .map(|f| format!("{:+.1}:{:03X}", (f.0 as f64 - from as f64) * 1e-3, f.1))
            .collect();
        // The meters' gaps inside it (a CPU that ran nothing of the guest's), per CPU.
        let stalled: Vec<String> = judged
            .stalls
            .gaps
            .iter()
            .map(|g| {
                let wall = |t: u64| (t as i64 + mono_to_wall) as u64;
                (g.cpu, wall(g.from_us), wall(g.to_us))
            })
            .filter(|&(_, a, b)| b > from && a < from + gap)
            .map(|(cpu, a, b)| {
                format!(
                    "CPU {cpu} {:+.1}..{:+.1}",
                    (a as f64 - from as f64) * 1e-3,
                    (b as f64 - from as f64) * 1e-3
                )
            })
            .collect();
        println!(
            "cia402 hand: handd's frames around its heartbeat's largest gap (ms from its last beat \
             before it: id): {}\ncia402 hand: the CPU meters' gaps in it (ms, same origin): \
             {stalled:?}",
            around.join(" ")
        );
    }
    println!("cia402 hand: handd's loop from all five following to the trip's end: {judged}");
    if !lost.is_empty() {
        // Whether handd's loop stood still or only its CANopen heartbeat went missing: its
        // HAND_HEARTBEAT (0x300, every tick) in the same span, and what handd logged of late
        // ticks (where their time went), errors and state changes (a transmit queue refusing
        // frames for long is `bus_degraded`).
        let from = start + gap_at;
        let hand_beats: Vec<u64> = of(0x300, from.saturating_sub(100_000), from + gap + 100_000)
            .iter()
            .map(|f| f.0)
            .collect();
        let hand_gap = hand_beats
            .windows(2)
            .map(|w| w[1] - w[0])
            .max()
            .unwrap_or(0);
        let log = handd.output();
        let notable: Vec<&str> = log
            .lines()
            .filter(|l| l.contains("WARN") || l.contains("ERROR") || l.contains("state change"))
            .collect();
        println!(
            "cia402 hand: HAND_HEARTBEAT around that gap: largest gap {:.1} ms; handd's warnings, \
             errors and state changes ({} lines, the last 20):\n{}",
            hand_gap as f64 * 1e-3,
            notable.len(),
            notable[notable.len().saturating_sub(20)..].join("\n")
        );
    }
    assert!(
        lost.is_empty(),
        "drives stopped on their heartbeat watchdog while handd ran (largest gap between \
         handd's heartbeats on the bus {:.1} ms, the watchdog 150 ms): {lost:?}",
        gap as f64 * 1e-3
    );
    if let Err(e) = trip_seen {
        panic!("{e}");
    }
    // No native setpoint: every finger is a drive's.
    assert!(
        frames.iter().all(|f| !FingerSetpoint::IDS.contains(&f.1)),
        "a FINGER_SETPOINT on a bus where every finger is on a drive"
    );
    // The closed loop through the index drive: its reported torque (TPDO1, 0x6077) as
    // fingertip force over full scale, against the patient's sine.
    let scaling = DriveFingerConfig::SIM_SCALING
        .validate()
        .expect("the simulated drives' scaling");
    let full_scale = TrackingConfig::default().full_scale_force_n;
    let (mut target, mut tracked, mut at) = (Vec::new(), Vec::new(), Vec::new());
    let scored_from = following_at + SETTLE_US;
    // A stop the simulated amplifier's stream caused (`stream_breaks`, from HAND_HEARTBEAT:
    // no finger has a FINGER_SETPOINT here) quick-stops every drive; it and the second after it
    // (the drives back to Operation enabled, the patient's finger back on the sine) are not
    // scored, and printed. Any other stop is scored as before.
    let verdict = judge_not_running(&seen, scored_from, kill_at);
    if !verdict.stretches.is_empty() {
        println!(
            "cia402 hand: handd not RUNNING while scored:\n{}",
            verdict.lines()
        );
    }
    let mut unscored = 0;
    for f in of(0x180 + node(TRACKED), scored_from, kill_at) {
        if verdict.excuses_within(f.0, EXCUSED_SETTLE_US) {
            unscored += 1;
            continue;
        }
        let permille = i16::from_le_bytes([f.2[2], f.2[3]]);
        target.push(Target::SINE_4S.at(f.0 - start));
        tracked.push(scaling.force_n(permille) / full_scale);
        at.push(f.0);
    }
    let span_s = (kill_at - scored_from) as f64 * 1e-6;
    println!(
        "cia402 hand: {unscored} index TPDO1 not scored (in or within {} ms after an excused stop)",
        EXCUSED_SETTLE_US / 1000
    );
    assert!(
        target.len() as f64 >= 0.6 * 20.0 * span_s,
        "only {} index TPDO1 scored in {span_s:.1} s of tracking ({unscored} not scored after \
         excused stops): too little to score",
        target.len()
    );
    let m = decoder::eval::tracking_metrics(&target, &tracked).expect("metrics");
    println!(
        "cia402 hand: closed loop through the index drive: {} TPDO1 in {span_s:.1} s, R² {:.3}, \
         RMSE {:.3} (force / full scale)",
        target.len(),
        m.r2,
        m.rmse
    );
    // Each period of the sine on its own: a loop that tracks worse as it runs shows here.
    let periods: Vec<String> = (0..)
        .map(|k| scored_from + k * PERIOD_US)
        .take_while(|from| from + PERIOD_US <= kill_at)
        .filter_map(|from| {
            let within: Vec<usize> = (0..at.len())
                .filter(|&i| (from..from + PERIOD_US).contains(&at[i]))
                .collect();
            let pick = |v: &[f64]| within.iter().map(|&i| v[i]).collect::<Vec<_>>();
            let m = decoder::eval::tracking_metrics(&pick(&target), &pick(&tracked)).ok()?;
            Some(format!("{:.3} ({})", m.r2, within.len()))
        })
        .collect();
    println!(
        "cia402 hand: R² per {} s period (TPDO1 scored): {}",
        PERIOD_US / 1_000_000,
        periods.join(", ")
    );
    assert!(
        m.r2 >= 0.8,
        "tracking R² {:.3} < 0.8 through the drive (RMSE {:.3})",
        m.r2,
        m.rmse
    );
    // The trip: from the ring drive's EMCY on the bus to handd's first quick stop for it,
    // within the 100 ms every drill gives a safe stop (one RPDO1 built before handd read the
    // EMCY may go first); then quick stops only, while the other four drives get Enable
    // operation and SYNC follows every tick.
    let emcy = frames
        .iter()
        .find(|f| f.1 == 0x080 + node(TRIPPED) && f.2[..2] == [0x10, 0x23])
        .expect("the ring drive's trip EMCY (0x2310) on the bus");
    let ring = of(0x200 + node(TRIPPED), emcy.0, kill_at);
    let first_stop = ring
        .iter()
        .position(|f| f.2 == QUICK_STOP)
        .expect("a quick stop for the tripped drive");
    let dt = ring[first_stop].0 - emcy.0;
    println!(
        "cia402 hand: the ring drive's first quick stop {:.1} ms after its EMCY ({first_stop} \
         RPDO1 built before it was read went first), {} quick stops until the kill",
        dt as f64 * 1e-3,
        ring.len() - first_stop
    );
    assert!(first_stop <= 1, "Enable operation after the trip: {ring:?}");
    assert!(
        dt <= 100_000,
        "the quick stop {dt} us after the trip's EMCY"
    );
    assert!(
        ring[first_stop..].iter().all(|f| f.2 == QUICK_STOP),
        "the tripped drive enabled again before `arm`: {ring:?}"
    );
    for f in (0..5).filter(|f| *f != TRIPPED) {
        let rpdos = of(0x200 + node(f), tripped_at, after_trip);
        assert!(
            (50..=64).contains(&rpdos.len()),
            "finger {f}: {} RPDO1 in the 3 s after the trip",
            rpdos.len()
        );
        assert!(
            rpdos.iter().all(|r| r.2[..2] == [0x0F, 0x00]),
            "finger {f} did not go on in Enable operation after another's trip: {rpdos:?}"
        );
    }
    let syncs = of(SYNC, tripped_at, after_trip).len();
    assert!((50..=64).contains(&syncs), "{syncs} SYNC in those 3 s");
    // Killed: every drive's own watchdog stops it, the tripped one's too.
    for f in 0..5 {
        let emcy = frames
            .iter()
            .find(|e| e.1 == 0x080 + node(f) && e.0 > kill_at && e.2[..2] == [0x30, 0x81])
            .unwrap_or_else(|| {
                panic!("finger {f}: no heartbeat-loss EMCY (0x8130) after the kill")
            });
        let dt = emcy.0 - kill_at;
        println!(
            "cia402 hand: finger {f}'s drive stopped on its watchdog {:.1} ms after SIGKILL",
            dt as f64 * 1e-3
        );
        assert!(
            dt <= WATCHDOG_BAR_US,
            "finger {f}: EMCY {dt} us after the kill"
        );
    }
}
