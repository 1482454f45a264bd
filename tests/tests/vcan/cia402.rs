//! Issue 26 over SocketCAN: the index finger through a simulated CiA 402 drive (`handsim
//! --cia402 1`, node 6) while the other fingers stay native. handd starts the drive over the
//! bus (reset, boot-up, identity, configuration read back, the power state machine), then every
//! tick sends its RPDO1 followed by SYNC; the drive's TPDO1 comes back. The drive trips (EMCY):
//! that finger alone gets the quick stop until `handctl arm`, which starts the drive again.
//! The drive is power-cycled: handd sees its boot-up, holds it in quick stop, never enables it
//! before `handctl arm`, and after the arm configures it from scratch. The bus goes off (an
//! injected bus-off error frame): after the reopen handd holds the drive in quick stop, its
//! state unknown, and starts it from scratch (reset communication, configuration) only after
//! `handctl arm`. Killed, handd stops its heartbeat and the drive stops by itself on its
//! watchdog (EMCY 0x8130).

use std::time::{Duration, Instant};

use driver::protocol::DriveLine;
use hand_dbc::messages::FingerSetpoint;
use handstack_tests::vcan::monitor::{now_us, writer};
use handstack_tests::vcan::procs::handsim;
use handstack_tests::vcan::stream_breaks::judge_not_active;
use handstack_tests::vcan::{Monitor, TestConfig, VcanEnv};
use socketcan::Socket;

use super::arming::Armed;
use super::calibrated_model;

/// The index finger's drive, as `handsim --cia402 1` simulates it.
const DRIVE_TABLE: &str = "\n[fingers.index.drive]\nprofile = \"cia402\"\nnode_id = 6\n\
     mode = \"cst\"\nrated_torque_mnm = 25.0\ngear_ratio = 64.0\nmoment_arm_m = 0.04\n\
     max_torque_permille = 1000\nmax_speed_rpm = 8000\n\n[canopen]\nmaster_node_id = 127\n\
     sync_cob_id = 0x07F\n";
const RPDO1: u32 = 0x206;
const TPDO1: u32 = 0x186;
const EMCY: u32 = 0x086;
pub(super) const SYNC: u32 = 0x07F;
/// SDO requests to the drive.
const SDO_RX: u32 = 0x606;
/// RPDO1 of the quick stop: controlword 0x0002, target 0.
pub(super) const QUICK_STOP: [u8; 4] = [0x02, 0x00, 0x00, 0x00];
/// The drive's heartbeat and boot-up (`00`).
const BOOT_UP: u32 = 0x706;
/// The drive watches handd's heartbeat for three ticks (150 ms); its heartbeat came at most one
/// tick before the kill, and the EMCY needs a frame time: 250 ms is the bar.
pub(super) const WATCHDOG_BAR_US: u64 = 250_000;
/// The drive trips this long after handsim started, s.
const TRIP_S: f64 = 3.0;
/// The drive is power-cycled this long after handsim started, s.
const POWER_CYCLE_S: f64 = 6.5;
/// NMT from handd: the command byte and the node.
const NMT: u32 = 0x000;
const RESET_COMMUNICATION: [u8; 2] = [0x82, 6];

/// Polls `handctl status` until handd runs and the index drive's line satisfies `ok`, for at
/// most `limit`; the time it took.
fn wait_drive(
    cfg: &TestConfig,
    what: &str,
    limit: Duration,
    ok: impl Fn(&DriveLine) -> bool,
) -> Duration {
    wait_status(cfg, what, limit, true, ok)
}

/// [`wait_drive`], in any state of handd's unless `running` (a latched fault holds it in SAFE).
fn wait_status(
    cfg: &TestConfig,
    what: &str,
    limit: Duration,
    running: bool,
    ok: impl Fn(&DriveLine) -> bool,
) -> Duration {
    wait_drives(cfg, what, limit, running, |d| d.first().is_some_and(&ok))
}

/// Polls handd's status (as `handctl status` asks for it) until every drive's line together satisfies `ok` (and handd runs, if
/// `running`), for at most `limit`; the time it took.
pub(super) fn wait_drives(
    cfg: &TestConfig,
    what: &str,
    limit: Duration,
    running: bool,
    ok: impl Fn(&[DriveLine]) -> bool,
) -> Duration {
    poll_drives(cfg, what, limit, running, ok).unwrap_or_else(|e| panic!("{e}"))
}

/// [`wait_drives`], with the timeout as an error: what was asked and the last status seen.
pub(super) fn poll_drives(
    cfg: &TestConfig,
    what: &str,
    limit: Duration,
    running: bool,
    ok: impl Fn(&[DriveLine]) -> bool,
) -> Result<Duration, String> {
    let started = Instant::now();
    loop {
        let st = cfg.query_status();
        if (!running || st.state == "RUNNING") && ok(&st.drives) {
            return Ok(started.elapsed());
        }
        if started.elapsed() >= limit {
            return Err(format!(
                "{what}: not within {limit:?}: state {}, faults {}, drives {:?}",
                st.state, st.faults, st.drives
            ));
        }
        std::thread::sleep(Duration::from_millis(50));
    }
}

#[test]
fn i_cia402_index_finger_started_driven_and_stopped_by_its_watchdog() {
    let env = VcanEnv::get();
    let model = calibrated_model(&env).to_path_buf();
    let dir = env.scratch("cia402");
    let cfg = TestConfig::write(&env, &dir, &model, 100);
    let mut text = std::fs::read_to_string(&cfg.path).expect("read the config");
    text.push_str(DRIVE_TABLE);
    std::fs::write(&cfg.path, text).expect("write the config");
    let monitor = Monitor::start(&env.iface);
    let mut handd = cfg.start(&env, &dir);
    let trip = format!("drive-trip:1@{TRIP_S}..{}", TRIP_S + 0.1);
    let cycle = format!(
        "drive-power-cycle:1@{POWER_CYCLE_S}..{}",
        POWER_CYCLE_S + 0.1
    );
    let mut sim = handsim(
        &env,
        &dir,
        "handsim",
        "sine",
        18.0,
        &["--cia402", "1", "--fault", &trip, "--fault", &cycle],
    );
    let sim_at = now_us();
    let following = |d: &DriveLine| d.state.starts_with("Operation enabled, following");
    let t = wait_drive(
        &cfg,
        "the index drive follows",
        Duration::from_secs(4),
        following,
    );
    println!(
        "cia402: the index drive follows its setpoint {:.0} ms after handsim started",
        t.as_secs_f64() * 1e3
    );
    // The trip: that finger stopped with the drive's EMCY named, the hand still RUNNING.
    wait_drive(&cfg, "the trip is seen", Duration::from_secs(5), |d| {
        d.faulted && d.state.contains("EMCY") && d.state.contains("0x2310")
    });
    let tripped_at = now_us();
    println!(
        "cia402: status shows the drive's trip {:.0} ms after handsim's {TRIP_S} s",
        (tripped_at - sim_at) as f64 * 1e-3 - TRIP_S * 1e3
    );
    std::thread::sleep(Duration::from_millis(500));
    let armed = Armed::now(&env, &cfg.socket);
    let t = wait_drive(
        &cfg,
        "the drive runs again after arm",
        Duration::from_secs(4),
        following,
    );
    println!(
        "cia402: after `handctl arm` ({:.0} ms to answer) the drive follows again {:.0} ms later",
        (armed.answered_us - armed.sent_us) as f64 * 1e-3,
        t.as_secs_f64() * 1e3
    );
    // The power cycle: its boot-up seen, the finger held until `arm`, then started again.
    wait_drive(
        &cfg,
        "the power cycle is seen",
        Duration::from_secs(6),
        |d| d.faulted && d.state.contains("booted"),
    );
    let booted_at = now_us();
    println!(
        "cia402: status shows the drive's power cycle {:.0} ms after handsim's {POWER_CYCLE_S} s",
        (booted_at - sim_at) as f64 * 1e-3 - POWER_CYCLE_S * 1e3
    );
    std::thread::sleep(Duration::from_millis(500));
    let rearmed = Armed::now(&env, &cfg.socket);
    let t = wait_drive(
        &cfg,
        "the drive runs again after the power cycle and arm",
        Duration::from_secs(4),
        following,
    );
    println!(
        "cia402: after the power cycle and `handctl arm` the drive follows again {:.0} ms later",
        t.as_secs_f64() * 1e3
    );
    // Bus-off and its recovery: the drive's state is unknown after it, so handd holds it in
    // quick stop and starts it from scratch only after `arm`.
    std::thread::sleep(Duration::from_millis(1_000));
    let busoff_at = now_us();
    let busoff = socketcan::CanErrorFrame::new_error(0x0040, &[0; 8]).expect("error frame");
    writer(&env.iface)
        .write_frame(&busoff)
        .expect("vcan accepts an injected error frame");
    wait_status(
        &cfg,
        "the bus-off recovery is seen",
        Duration::from_secs(4),
        false,
        |d| d.faulted && d.state.contains("bus-off recovery"),
    );
    std::thread::sleep(Duration::from_millis(500));
    let armed3 = Armed::now(&env, &cfg.socket);
    let t = wait_drive(
        &cfg,
        "the drive runs again after the bus-off and arm",
        Duration::from_secs(4),
        following,
    );
    println!(
        "cia402: after the bus-off and `handctl arm` the drive follows again {:.0} ms later",
        t.as_secs_f64() * 1e3
    );
    std::thread::sleep(Duration::from_millis(1_000));
    let kill_at = now_us();
    handd.kill();
    std::thread::sleep(Duration::from_millis(600));
    sim.kill();
    let seen = monitor.finish();
    let frames: Vec<(u64, u32, Vec<u8>)> = seen
        .iter()
        .filter_map(|s| s.frame.as_ref().map(|f| (s.time_us, f)))
        .filter(|(_, f)| !f.is_extended())
        .map(|(t, f)| (t, f.raw_id(), f.data().to_vec()))
        .collect();
    // The second before the kill: one RPDO1 per tick with Enable operation, each followed by
    // SYNC within the same tick; the drive's TPDO1 after each SYNC.
    let last_second = |id: u32| -> Vec<&(u64, u32, Vec<u8>)> {
        frames
            .iter()
            .filter(|f| f.1 == id && f.0 + 1_000_000 > kill_at && f.0 < kill_at)
            .collect()
    };
    let rpdos = last_second(RPDO1);
    assert!(
        (17..=21).contains(&rpdos.len()),
        "{} RPDO1 in the second before the kill",
        rpdos.len()
    );
    // A stop the simulated amplifier's stream caused (`stream_breaks`, told from the native
    // fingers' setpoints) quick-stops the drive too; it and the drive's three ticks back to
    // Enable operation are excused, and printed. Any other control word still fails.
    let verdict = judge_not_active(&seen, kill_at - 1_000_000, kill_at, &[0, 2, 3, 4]);
    if !verdict.stretches.is_empty() {
        println!(
            "cia402: stretches not ACTIVE in the second before the kill:\n{}",
            verdict.lines()
        );
    }
    assert!(
        rpdos
            .iter()
            .all(|f| f.2[..2] == [0x0F, 0x00] || verdict.excuses_within(f.0, 3 * 50_000)),
        "Enable operation in every RPDO1: {rpdos:?}"
    );
    for r in &rpdos {
        assert!(
            frames
                .iter()
                .any(|f| f.1 == SYNC && f.0 >= r.0 && f.0 < r.0 + 10_000),
            "no SYNC within 10 ms after the RPDO1 at {}",
            r.0
        );
    }
    // Between the trip (seen by status) and the arm: the quick stop, target zero, each tick.
    let stopped: Vec<_> = frames
        .iter()
        .filter(|f| f.1 == RPDO1 && f.0 > tripped_at && f.0 < armed.sent_us)
        .collect();
    assert!(stopped.len() >= 8, "{} RPDO1 while tripped", stopped.len());
    assert!(
        stopped.iter().all(|f| f.2 == [0x02, 0x00, 0x00, 0x00]),
        "quick stop with the target zeroed while tripped: {stopped:?}"
    );
    // Between the power cycle (seen by status) and the second arm: the quick stop each tick,
    // never Enable operation, and the drive configured again only after the arm (its SDO
    // requests, 0x606, come after it).
    let held: Vec<_> = frames
        .iter()
        .filter(|f| f.1 == RPDO1 && f.0 > booted_at && f.0 < rearmed.sent_us)
        .collect();
    assert!(
        held.len() >= 8,
        "{} RPDO1 after the power cycle",
        held.len()
    );
    assert!(
        held.iter().all(|f| f.2 == QUICK_STOP),
        "quick stop with the target zeroed after the power cycle: {held:?}"
    );
    // From the drive's boot-up on the bus to handd's first quick stop after it, within the
    // 100 ms every other drill gives a safe stop. One RPDO1 built before handd read the
    // boot-up may follow it (the tick that wrote it had read the bus up to its deadline, and
    // the boot-up came after): a drive just booted is pre-operational and takes no PDO, and
    // it does not leave pre-operational before `arm` (no TPDO1 from it until then).
    let boot_up = frames
        .iter()
        .rev()
        .find(|f| f.1 == BOOT_UP && f.2 == [0x00] && f.0 < booted_at)
        .expect("the power-cycled drive's boot-up on the bus");
    let after_boot: Vec<_> = frames
        .iter()
        .filter(|f| f.1 == RPDO1 && f.0 > boot_up.0 && f.0 < rearmed.sent_us)
        .collect();
    let first_stop = after_boot
        .iter()
        .position(|f| f.2 == QUICK_STOP)
        .expect("a quick stop after the boot-up");
    let dt = after_boot[first_stop].0 - boot_up.0;
    println!(
        "cia402: handd's first quick stop after the power-cycled drive's boot-up: {:.1} ms \
         later ({first_stop} RPDO1 built before it was read went first)",
        dt as f64 * 1e-3
    );
    assert!(
        first_stop <= 1,
        "{first_stop} RPDO1 of Enable operation after the boot-up: {after_boot:?}"
    );
    assert!(
        after_boot[first_stop..].iter().all(|f| f.2 == QUICK_STOP),
        "Enable operation again after the quick stop: {after_boot:?}"
    );
    assert!(dt <= 100_000, "the quick stop {dt} us after the boot-up");
    assert!(
        !frames
            .iter()
            .any(|f| f.1 == TPDO1 && f.0 > boot_up.0 && f.0 < rearmed.sent_us),
        "the power-cycled drive was operational again before `arm`"
    );
    let sdo_after = |from: u64, to: u64| {
        frames
            .iter()
            .filter(|f| f.1 == SDO_RX && f.0 > from && f.0 < to)
            .count()
    };
    assert_eq!(
        sdo_after(booted_at, rearmed.sent_us),
        0,
        "handd configured the power-cycled drive before `arm`"
    );
    assert!(
        sdo_after(rearmed.sent_us, busoff_at) >= 20,
        "the power-cycled drive was not configured again after `arm`"
    );
    // After the bus-off: at most one RPDO1 of Enable operation built before handd read the
    // error frame, then only quick stops until `arm`; no SDO and no NMT to the drive before
    // it; after it a reset of the drive's communication and its whole configuration again.
    let onset = seen
        .iter()
        .find(|s| s.frame.is_none() && s.time_us >= busoff_at)
        .map(|s| s.time_us)
        .expect("the monitor saw the injected bus-off error frame");
    let after_off: Vec<_> = frames
        .iter()
        .filter(|f| f.1 == RPDO1 && f.0 > onset && f.0 < armed3.sent_us)
        .collect();
    let first_stop = after_off
        .iter()
        .position(|f| f.2 == QUICK_STOP)
        .expect("a quick stop after the bus-off");
    println!(
        "cia402: after the bus-off, {} RPDO1 in quick stop before `arm` (the first {:.1} ms \
         after the error frame; {first_stop} built before it was read went first)",
        after_off.len() - first_stop,
        (after_off[first_stop].0 - onset) as f64 * 1e-3
    );
    assert!(
        first_stop <= 1 && after_off[first_stop..].iter().all(|f| f.2 == QUICK_STOP),
        "Enable operation after the bus-off before `arm`: {after_off:?}"
    );
    assert!(
        after_off.len() - first_stop >= 8,
        "{} quick stops after the bus-off",
        after_off.len() - first_stop
    );
    assert!(
        after_off[first_stop].0 - onset <= 100_000,
        "the first quick stop {} us after the bus-off",
        after_off[first_stop].0 - onset
    );
    assert_eq!(
        sdo_after(onset, armed3.sent_us),
        0,
        "handd configured the drive after the bus-off before `arm`"
    );
    let resets = |from: u64, to: u64| {
        frames
            .iter()
            .filter(|f| f.1 == NMT && f.2 == RESET_COMMUNICATION && f.0 > from && f.0 < to)
            .count()
    };
    assert_eq!(
        resets(onset, armed3.sent_us),
        0,
        "handd reset the drive after the bus-off before `arm`"
    );
    assert!(
        resets(armed3.sent_us, kill_at) >= 1,
        "handd did not reset the drive's communication after the bus-off and `arm`"
    );
    assert!(
        sdo_after(armed3.sent_us, kill_at) >= 20,
        "the drive was not configured again after the bus-off and `arm`"
    );
    let tpdos = last_second(TPDO1);
    assert!(tpdos.len() >= 17, "{} TPDO1 in that second", tpdos.len());
    // No FINGER_SETPOINT for the index finger; the thumb's still come.
    assert!(frames.iter().all(|f| f.1 != FingerSetpoint::IDS[1]));
    assert!(last_second(FingerSetpoint::IDS[0]).len() >= 17);
    // Killed: the drive's own watchdog stops it.
    let emcy = frames
        .iter()
        .find(|f| f.1 == EMCY && f.0 > kill_at && f.2[..2] == [0x30, 0x81])
        .unwrap_or_else(|| panic!("no heartbeat-loss EMCY (0x8130) after the kill"));
    let dt = emcy.0 - kill_at;
    println!(
        "cia402: the drive's watchdog EMCY came {:.1} ms after SIGKILL",
        dt as f64 * 1e-3
    );
    assert!(dt <= WATCHDOG_BAR_US, "EMCY {dt} us after the kill");
}
