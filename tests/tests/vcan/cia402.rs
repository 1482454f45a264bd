//! Issue 26 over SocketCAN: the index finger through a simulated CiA 402 drive (`handsim
//! --cia402 1`, node 6) while the other fingers stay native. handd starts the drive over the
//! bus (reset, boot-up, identity, configuration read back, the power state machine), then every
//! tick sends its RPDO1 followed by SYNC; the drive's TPDO1 comes back. Killed, handd stops
//! its heartbeat and the drive stops by itself on its watchdog (EMCY 0x8130).

use std::time::{Duration, Instant};

use hand_dbc::messages::FingerSetpoint;
use handstack_tests::vcan::monitor::now_us;
use handstack_tests::vcan::procs::handsim;
use handstack_tests::vcan::{Monitor, TestConfig, VcanEnv};

use super::calibrated_model;

/// The index finger's drive, as `handsim --cia402 1` simulates it.
const DRIVE_TABLE: &str = "\n[fingers.index.drive]\nprofile = \"cia402\"\nnode_id = 6\n\
     mode = \"cst\"\nrated_torque_mnm = 25.0\ngear_ratio = 64.0\nmoment_arm_m = 0.04\n\
     max_torque_permille = 1000\nmax_speed_rpm = 8000\n\n[canopen]\nmaster_node_id = 127\n\
     sync_cob_id = 0x07F\n";
const RPDO1: u32 = 0x206;
const TPDO1: u32 = 0x186;
const EMCY: u32 = 0x086;
const SYNC: u32 = 0x07F;
/// The drive watches handd's heartbeat for three ticks (150 ms); its heartbeat came at most one
/// tick before the kill, and the EMCY needs a frame time: 250 ms is the bar.
const WATCHDOG_BAR_US: u64 = 250_000;

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
    let mut sim = handsim(&env, &dir, "handsim", "sine", 6.0, &["--cia402", "1"]);
    let started = Instant::now();
    let following = loop {
        let st = cfg.status(&env);
        let drive = st.drives.first().cloned();
        if st.state == "RUNNING"
            && drive
                .as_ref()
                .is_some_and(|d| d.state.starts_with("Operation enabled, following"))
        {
            break started.elapsed();
        }
        assert!(
            started.elapsed() < Duration::from_secs(4),
            "the index drive never followed its setpoint: state {}, faults {}, drives {:?}\n\
             handd:\n{}",
            st.state,
            st.faults,
            st.drives,
            handd.output()
        );
        std::thread::sleep(Duration::from_millis(100));
    };
    println!(
        "cia402: the index drive follows its setpoint {:.0} ms after handsim started",
        following.as_secs_f64() * 1e3
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
    assert!(
        rpdos.iter().all(|f| f.2[..2] == [0x0F, 0x00]),
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
