//! Issue 30, item 6: frames the kernel drops from handd's full receive queue are counted, not
//! blamed on the amplifier. handd is stopped (SIGSTOP) for 1.2 s while handsim runs the bus at
//! its full load (about 3,500 frames/s): its socket's queue (at most 2 x net.core.rmem_max of
//! skbs; with the install's rmem_max of 671,744, as the VM sets it, about 1,900 frames or
//! 0.55 s of this bus, measured) overflows.
//! After SIGCONT, `handctl status` counts the drops (`kernel_drops`, SO_RXQ_OVFL); the first
//! setpoints handd sends are safe stops (the backlog is stale and has a gap: no window is
//! valid), and the hand runs again by itself once the signal is good for the recovery time.

use std::time::Duration;

use hand_dbc::messages::FingerMode;
use handstack_tests::vcan::monitor::now_us;
use handstack_tests::vcan::procs::{handsim, Proc};
use handstack_tests::vcan::{setpoints_of, VcanEnv};
use rustix::process::Signal;

use super::restart::wait_active_after;
use super::{Rig, ALL, DRILL_SILENCE_MS};

/// How long handd stays stopped.
const STALL: Duration = Duration::from_millis(1_200);

#[test]
fn field_a_stalled_handd_counts_the_kernels_drops_then_recovers() {
    let rig = Rig::start("kernel-drops", DRILL_SILENCE_MS);
    let mut sim = rig.sim("sine", 8.0, &[]);
    wait_active_after(&rig.monitor, 0, Duration::from_secs(10))
        .expect("handd never RUNNING before the stall");
    std::thread::sleep(Duration::from_millis(1_000));
    let st0 = rig.cfg.status(&rig.env);
    rig.handd.signal(Signal::STOP);
    std::thread::sleep(STALL);
    rig.handd.signal(Signal::CONT);
    let resumed_at = now_us();
    std::thread::sleep(Duration::from_millis(2_500));
    let st = rig.cfg.status(&rig.env);
    let seen = rig.monitor.snapshot();
    let sps = setpoints_of(&seen);
    let drops = st.bus.counters.kernel_drops - st0.bus.counters.kernel_drops;
    // The first setpoint of each finger after the stall, and when the hand ran again.
    let first: Vec<_> = ALL
        .iter()
        .filter_map(|&f| {
            sps.iter()
                .find(|s| s.finger == f && s.time_us >= resumed_at)
        })
        .collect();
    let active_again = wait_active_after(&rig.monitor, resumed_at, Duration::ZERO);
    println!(
        "stall {STALL:?}: kernel drops {drops} (before the stall {}), EMG samples lost {}, \
         state after {} ({}); first setpoints after SIGCONT: {:?}; ACTIVE again {} ms after it",
        st0.bus.counters.kernel_drops,
        st.samples_lost - st0.samples_lost,
        st.state,
        st.faults,
        first.iter().map(|s| s.mode).collect::<Vec<_>>(),
        active_again.map_or(-1, |t| ((t - resumed_at) / 1000) as i64)
    );
    assert!(
        drops > 0,
        "handd was stopped {STALL:?} on a full bus and counted no kernel drops"
    );
    assert_eq!(first.len(), 5, "handd sent nothing after SIGCONT");
    assert!(
        first.iter().all(|s| s.mode != FingerMode::Active),
        "handd drove the fingers from the stale backlog after the stall: {first:?}"
    );
    assert!(
        active_again.is_some(),
        "handd did not run again within 2.5 s after the stall (faults {})",
        st.faults
    );
    assert_eq!(st.state, "RUNNING", "faults after recovery: {}", st.faults);
    sim.wait_success(Duration::from_secs(60));
}

/// `handctl record` stalled as a slow disk or a loaded board would stall it (SIGSTOP for
/// longer than its receive buffer holds): the kernel drops frames of its socket. It says how
/// many and refuses the recording (exit 1, the log kept) rather than leave a log with gaps no
/// one sees. Issue 29: in one run the closed-loop test's two recorders disagreed by 7.5 ms on
/// the same frames, the signature of frames lost by one of them; neither counted its drops.
#[test]
fn field_handctl_record_refuses_a_recording_the_kernel_dropped_frames_of() {
    let env = VcanEnv::get();
    let dir = env.scratch("record-drops");
    let mut sim = handsim(&env, &dir, "handsim", "sine", 4.0, &[]);
    std::thread::sleep(Duration::from_millis(500));
    let out = dir.join("recording");
    let mut rec = Proc::spawn(
        &env,
        "handctl",
        "record",
        &[
            "record".into(),
            "--iface".into(),
            env.iface.clone(),
            "--out".into(),
            out.display().to_string(),
            "--duration".into(),
            "2.5".into(),
        ],
        &dir,
    );
    let stall = Duration::from_millis(1_200);
    std::thread::sleep(Duration::from_millis(800));
    rec.signal(Signal::STOP);
    std::thread::sleep(stall);
    rec.signal(Signal::CONT);
    let st = rec.wait_exit(Duration::from_secs(15));
    let said = rec.output();
    let drops: Option<u64> = said
        .split_once("frames because handctl record fell behind")
        .and_then(|(before, _)| before.rsplit("dropped ").next())
        .and_then(|n| n.trim().parse().ok());
    println!("handctl record stalled {stall:?}: {st}, kernel drops {drops:?}");
    assert!(
        !st.success(),
        "handctl record lost frames and succeeded; its output:\n{said}"
    );
    assert!(
        drops.is_some_and(|n| n > 0) && said.contains("has gaps"),
        "handctl record did not say how many frames the kernel dropped; its output:\n{said}"
    );
    assert!(
        out.join("frames.log").is_file(),
        "the refused recording's log was not kept"
    );
    sim.wait_success(Duration::from_secs(30));
}
