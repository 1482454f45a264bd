//! A finger through a CiA 402 drive (issue 26): the daemon's real loop, the simulated world,
//! and a simulated drive node on the same in-memory bus. The index finger's setpoint leaves as
//! the drive's RPDO1, then SYNC and handd's heartbeat; a drive fault stops that finger alone
//! and only `arm` brings it back.

mod common;

use common::{random_predictor, Rig};
use driver::drive_config::{Drive, Drives};
use driver::engine::{Command, EngineSettings};
use driver::safety::DaemonState;
use hand_canopen::master::{DriveFault, DriveStatus};
use hand_canopen::scaling::ScalingSettings;
use hand_canopen::sim::SimDrive;
use hand_canopen::{CobId, Mode, NodeId, ObjectAddr, PowerState};
use hand_dbc::messages::{FingerMode, FingerSetpoint};
use hand_dbc::CanFrame;
use hand_model::faults::FaultPlan;
use hand_model::patient::Script;
use hand_model::world::PatientMode;
use hand_model::MemEndpoint;

const INDEX: usize = 1;
const NODE: u8 = 5;
const SYNC: u16 = 0x07F;

fn node() -> NodeId {
    NodeId::try_new(NODE).expect("in range")
}

fn settings() -> EngineSettings {
    settings_in(Mode::CyclicSyncTorque)
}

/// The index finger on the drive in `mode`.
fn settings_in(mode: Mode) -> EngineSettings {
    let scaling = ScalingSettings {
        rated_torque_mnm: 25.0,
        gear_ratio: 64.0,
        moment_arm_m: 0.04,
        max_torque_permille: 1000,
        max_speed_rpm: 8000,
    }
    .validate()
    .expect("valid scaling");
    let mut fingers = [Drive::Native; 5];
    fingers[INDEX] = Drive::Cia402 {
        node: node(),
        mode,
        scaling,
    };
    EngineSettings {
        drives: Drives {
            fingers,
            master: Some((
                NodeId::try_new(127).expect("in range"),
                CobId::try_new(SYNC).expect("11 bits"),
            )),
        },
        ..EngineSettings::default()
    }
}

/// The rig plus the drive node on its own endpoint.
struct Hand {
    rig: Rig,
    drive: SimDrive,
    port: MemEndpoint,
}

impl Hand {
    fn in_mode(mode: Mode) -> Self {
        let rig = Rig::with_settings(
            FaultPlan::new(),
            PatientMode::Script(Script::resting(30_000_000)),
            random_predictor(7),
            |t| t,
            |b| b,
            settings_in(mode),
        );
        let mut port = rig.bus.endpoint();
        let mut drive = SimDrive::new(node());
        let mut out = Vec::new();
        drive.power_on(0, &mut out);
        for f in out {
            send(&mut port, f);
        }
        Self { rig, drive, port }
    }

    /// As `Rig::run_until`, with the drive node served every 1 ms step (before handd: what
    /// handd sends, the drive answers at the next step, never at the instant it was sent).
    fn run_until(&mut self, t_end_us: u64) {
        let mut now = self.rig.clock_now();
        while now < t_end_us {
            now += 1000;
            self.rig.clock.set_us(now);
            self.rig.world.step(now);
            self.serve_drive(now);
            if now >= self.rig.runner.next_deadline_us() {
                self.rig.runner.step();
            } else if now >= self.rig.runner.next_wake_us() {
                self.rig.runner.service_bus();
            }
            while let Some(r) = self.rig.probe.receive_timestamped() {
                self.rig.seen.push((r.time_us.unwrap_or(now), r.frame));
            }
        }
    }

    fn serve_drive(&mut self, now: u64) {
        let mut out = Vec::new();
        while let Some(r) = self.port.receive_timestamped() {
            if let Some(f) = hand_canopen::CanFrame::new(r.frame.raw_id() as u16, r.frame.data()) {
                self.drive.on_frame(&f, now, &mut out);
            }
        }
        self.drive.poll(now, &mut out);
        for f in out {
            send(&mut self.port, f);
        }
    }

    fn status(&self) -> Option<DriveStatus> {
        self.rig.runner.engine().drive_status(INDEX)
    }

    /// The frames handd sent in [from, to), as (time, id, payload).
    fn sent(&self, from: u64, to: u64) -> Vec<(u64, u32, Vec<u8>)> {
        self.rig
            .seen
            .iter()
            .filter(|(t, _)| *t >= from && *t < to)
            .map(|(t, f)| (*t, f.raw_id(), f.data().to_vec()))
            .collect()
    }
}

fn send(port: &mut MemEndpoint, f: hand_canopen::CanFrame) {
    let frame = CanFrame::new_standard(f.cob_id(), f.payload()).expect("11-bit frame");
    port.send(&frame).expect("the bus takes it");
}

fn running() -> Hand {
    running_in(Mode::CyclicSyncTorque)
}

fn running_in(mode: Mode) -> Hand {
    let mut h = Hand::in_mode(mode);
    h.run_until(3_000_000);
    let e = h.rig.runner.engine();
    assert_eq!(e.state(), DaemonState::Running, "{}", e.faults());
    assert!(
        matches!(h.status(), Some(DriveStatus::Running { enabled: true, .. })),
        "{:?}",
        h.status()
    );
    assert_eq!(h.drive.power_state(), PowerState::OperationEnabled);
    h
}

#[test]
fn the_index_finger_runs_through_its_drive_rpdo_then_sync_each_tick() {
    let mut h = running();
    assert!(!h.rig.runner.engine().finger_disabled(INDEX));
    let from = h.rig.clock_now();
    h.run_until(from + 500_000);
    let sent = h.sent(from, from + 500_000);
    let rpdo = 0x200 + u32::from(NODE);
    let rpdos: Vec<_> = sent.iter().filter(|s| s.1 == rpdo).collect();
    assert!(
        (9..=11).contains(&rpdos.len()),
        "{} RPDO1 in 0.5 s",
        rpdos.len()
    );
    assert!(
        rpdos.iter().all(|s| s.2[..2] == [0x0F, 0x00]),
        "enable operation"
    );
    // Each RPDO1 is followed by SYNC, then handd's heartbeat, in the same tick.
    for (i, s) in sent.iter().enumerate().filter(|(_, s)| s.1 == rpdo) {
        assert_eq!(
            sent[i + 1].1,
            u32::from(SYNC),
            "SYNC after the RPDO1 at {}",
            s.0
        );
        assert_eq!(
            sent[i + 2].1,
            0x77F,
            "handd's heartbeat after SYNC at {}",
            s.0
        );
    }
    // No FINGER_SETPOINT for the index finger; the others still get theirs.
    let index_sp = FingerSetpoint::IDS[INDEX];
    assert!(sent.iter().all(|s| s.1 != index_sp));
    let thumb: Vec<_> = h
        .rig
        .setpoints()
        .into_iter()
        .filter(|s| s.0 >= from && s.1 == 0)
        .collect();
    assert!(thumb.len() >= 9 && thumb.iter().all(|s| s.2 == FingerMode::Active));
    // The drive's target is the engine's force setpoint, scaled.
    let force = h.rig.runner.engine().setpoints()[INDEX].force.0;
    let target = h.drive.od().get(ObjectAddr::new(0x6071, 0)) as u16 as i16;
    let Drive::Cia402 { scaling, .. } = settings().drives.fingers[INDEX] else {
        unreachable!()
    };
    assert_eq!(target, scaling.torque_permille(force), "force {force} N");
    assert_eq!(h.drive.stats().watchdog_trips, 0);
}

/// CSV: each RPDO1 is 8 bytes, the velocity setpoint in rpm and the force setpoint's magnitude
/// as the torque limit (0x6072), through the finger's scaling; the drive takes every one.
#[test]
fn in_csv_the_index_finger_sends_its_velocity_with_the_force_as_torque_limit() {
    let mut h = running_in(Mode::CyclicSyncVelocity);
    let from = h.rig.clock_now();
    h.run_until(from + 500_000);
    let sent = h.sent(from, from + 500_000);
    let rpdo = 0x200 + u32::from(NODE);
    let rpdos: Vec<_> = sent.iter().filter(|s| s.1 == rpdo).collect();
    assert!(
        (9..=11).contains(&rpdos.len()),
        "{} RPDO1 in 0.5 s",
        rpdos.len()
    );
    assert!(
        rpdos
            .iter()
            .all(|s| s.2.len() == 8 && s.2[..2] == [0x0F, 0x00]),
        "8 bytes, enable operation: {rpdos:?}"
    );
    let Drive::Cia402 { scaling, .. } = settings_in(Mode::CyclicSyncVelocity).drives.fingers[INDEX]
    else {
        unreachable!()
    };
    // The next tick's setpoint, taken right after it, against its RPDO1 (read a few ms later:
    // the bus delivers a frame after its transmission time).
    let deadline = h.rig.runner.next_deadline_us();
    while h.rig.runner.next_deadline_us() == deadline {
        let now = h.rig.clock_now();
        h.run_until(now + 1_000);
    }
    let sp = h.rig.runner.engine().setpoints()[INDEX];
    let ticked = h.rig.clock_now();
    h.run_until(ticked + 5_000);
    let after = h.sent(ticked - 1_000, ticked + 5_000);
    let last = &after
        .iter()
        .find(|s| s.1 == rpdo)
        .expect("the tick's RPDO1")
        .2;
    let rpm = i32::from_le_bytes([last[2], last[3], last[4], last[5]]);
    let limit = u16::from_le_bytes([last[6], last[7]]);
    assert_eq!(rpm, scaling.velocity_rpm(sp.velocity.0), "{sp:?}");
    assert_eq!(limit, scaling.max_torque_permille(sp.force.0), "{sp:?}");
    let limits: Vec<u16> = rpdos
        .iter()
        .map(|s| u16::from_le_bytes([s.2[6], s.2[7]]))
        .collect();
    assert!(
        limits.iter().any(|&l| l > 0),
        "the random predictor's forces give limits: {limits:?}"
    );
    // The drive applied them (the newest, or the one before if the last SYNC is unserved).
    let applied = h.drive.od().get(ObjectAddr::new(0x6072, 0)) as u16;
    assert!(
        limits[limits.len() - 2..].contains(&applied),
        "{applied} of {limits:?}"
    );
    assert_eq!(h.drive.stats().rpdo_length_errors, 0);
    assert_eq!(h.drive.stats().emcys, 0);
}

#[test]
fn a_drive_fault_stops_that_finger_alone_until_arm() {
    let mut h = running();
    let mut out = Vec::new();
    h.drive.inject_fault(0x2310, &mut out);
    for f in out {
        send(&mut h.port, f);
    }
    let at = h.rig.clock_now();
    h.run_until(at + 1_000_000);
    match h.status() {
        Some(DriveStatus::Faulted(DriveFault::Emcy(e))) => assert_eq!(e.code, 0x2310),
        s => panic!("after the drive's fault: {s:?}"),
    }
    let e = h.rig.runner.engine();
    assert_eq!(
        e.state(),
        DaemonState::Running,
        "the others run: {}",
        e.faults()
    );
    assert_eq!(e.setpoints()[INDEX].force.0, 0.0);
    let rpdo = 0x200 + u32::from(NODE);
    let late: Vec<_> = h
        .sent(at + 100_000, at + 1_000_000)
        .into_iter()
        .filter(|s| s.1 == rpdo)
        .collect();
    assert!(!late.is_empty());
    assert!(
        late.iter().all(|s| s.2 == [0x02, 0x00, 0x00, 0x00]),
        "quick stop, target zero: {late:?}"
    );
    assert_eq!(
        h.drive.power_state(),
        PowerState::Fault,
        "no fault reset without arm"
    );
    // arm: the drive starts again from scratch (fault reset on the way) and runs.
    let now = h.rig.clock_now();
    h.rig
        .runner
        .engine_mut()
        .command(now, Command::Arm)
        .expect("arm");
    h.run_until(now + 1_500_000);
    assert!(
        matches!(h.status(), Some(DriveStatus::Running { enabled: true, .. })),
        "{:?}",
        h.status()
    );
    assert_eq!(h.drive.power_state(), PowerState::OperationEnabled);
}

#[test]
fn when_the_loop_stops_the_drive_quick_stops_by_its_own_watchdog() {
    let mut h = running();
    let from = h.rig.clock_now();
    // handd stalls: the world and the drive run on, handd sends nothing.
    for t in (from..from + 500_000).step_by(1000) {
        h.rig.clock.set_us(t);
        h.rig.world.step(t);
        h.serve_drive(t);
    }
    assert_eq!(h.drive.stats().watchdog_trips, 1);
    assert_ne!(h.drive.power_state(), PowerState::OperationEnabled);
}
