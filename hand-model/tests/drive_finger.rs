//! A finger moved by its simulated CiA 402 drive (issue 26 item 6), driven by handd's CANopen
//! master core (`hand_canopen::master::DriveBank`) over the in-memory bus: the drive starts,
//! a torque target flexes the finger and an opposite one extends it, a stop brakes it, a
//! velocity target moves it at that speed with no more force than its torque limit, and a
//! drive fault (EMCY) or a power cycle reaches the master as a latched fault.

use hand_canopen::master::{BankSettings, DriveBank, DriveFault, DriveStatus, Target, TorqueLimit};
use hand_canopen::scaling::ScalingSettings;
use hand_canopen::{CobId, Mode, NodeId, PowerState};
use hand_model::dbc::CanFrame;
use hand_model::faults::FaultPlan;
use hand_model::nodes::DriveFingerConfig;
use hand_model::patient::Script;
use hand_model::world::{PatientMode, World, WorldConfig};
use hand_model::{MemBus, MemEndpoint};

const INDEX: usize = 1;
const TICK_US: u64 = 50_000;

fn node() -> NodeId {
    NodeId::try_new(5).expect("in range")
}

struct Rig {
    now: u64,
    world: World<MemEndpoint>,
    bank: DriveBank,
    master: MemEndpoint,
}

impl Rig {
    fn new(mode: Mode) -> Self {
        Self::with_faults(mode, FaultPlan::new())
    }

    fn with_faults(mode: Mode, faults: FaultPlan) -> Self {
        let scaling = ScalingSettings {
            rated_torque_mnm: 25.0,
            gear_ratio: 64.0,
            moment_arm_m: 0.04,
            max_torque_permille: 1000,
            max_speed_rpm: 8000,
        }
        .validate()
        .expect("valid scaling");
        let bus = MemBus::new();
        let b = bus.clone();
        let mut drives = [None; 5];
        drives[INDEX] = Some(DriveFingerConfig {
            node: node(),
            scaling,
        });
        let world = World::try_new(
            WorldConfig {
                faults,
                drives,
                ..WorldConfig::default()
            },
            PatientMode::Script(Script::resting(60_000_000)),
            || Ok::<_, String>(b.endpoint()),
        )
        .expect("world");
        let bank = DriveBank::try_new(
            BankSettings {
                master: NodeId::try_new(127).expect("in range"),
                tick_us: TICK_US as u32,
                sync_cob_id: CobId::try_new(0x07F).expect("11 bits"),
                master_heartbeat_timeout_ms: 150,
                drive_heartbeat_ms: 50,
                drive_heartbeat_timeout_us: 150_000,
                sdo_timeout_us: 20_000,
                step_timeout_us: 500_000,
            },
            &[(node(), mode)],
        )
        .expect("bank");
        Self {
            now: 0,
            world,
            bank,
            master: bus.endpoint(),
        }
    }

    fn send(&mut self, f: hand_canopen::CanFrame) {
        let frame = CanFrame::new_standard(f.cob_id(), f.payload()).expect("11-bit frame");
        self.master.send(&frame).expect("the bus takes it");
    }

    /// Runs `us` in 1 ms steps with `target`, the master ticking every 50 ms.
    fn run(&mut self, us: u64, target: Target) {
        let end = self.now + us;
        while self.now < end {
            self.now += 1000;
            self.world.step(self.now);
            let mut out = Vec::new();
            while let Some(r) = self.master.receive_timestamped() {
                if let Some(f) =
                    hand_canopen::CanFrame::new(r.frame.raw_id() as u16, r.frame.data())
                {
                    self.bank.on_frame(&f, self.now, &mut |x| out.push(x));
                }
            }
            if self.now.is_multiple_of(TICK_US) {
                self.bank.tick(self.now, &[target], &mut |x| out.push(x));
            }
            for f in out {
                self.send(f);
            }
        }
    }

    fn angle(&self) -> f64 {
        self.world
            .drive_fingers()
            .find(|n| n.finger() == INDEX)
            .expect("the index finger's drive")
            .physics()
            .angle_rad
    }

    fn power(&self) -> PowerState {
        self.world
            .drive_fingers()
            .next()
            .expect("one drive")
            .drive()
            .power_state()
    }

    fn force(&self) -> f64 {
        self.world
            .drive_fingers()
            .find(|n| n.finger() == INDEX)
            .expect("the index finger's drive")
            .physics()
            .force_n
    }
}

#[test]
fn the_drive_starts_and_its_torque_moves_the_finger_both_ways() {
    let mut r = Rig::new(Mode::CyclicSyncTorque);
    assert_eq!(
        r.world.fingers().count(),
        4,
        "no native controller for the index"
    );
    r.run(300_000, Target::Stop);
    assert!(
        matches!(r.bank.status(0), DriveStatus::Running { .. }),
        "{:?}",
        r.bank.status(0)
    );
    let start = r.angle();
    r.run(600_000, Target::torque(400));
    assert_eq!(r.power(), PowerState::OperationEnabled);
    let flexed = r.angle();
    assert!(flexed > start + 0.2, "flexion: {start} -> {flexed} rad");
    r.run(600_000, Target::torque(-400));
    let extended = r.angle();
    assert!(
        extended < flexed - 0.2,
        "extension: {flexed} -> {extended} rad"
    );
    // A stop: quick stop, the finger braked where it is.
    r.run(200_000, Target::Stop);
    let held = r.angle();
    r.run(500_000, Target::Stop);
    assert!(
        (r.angle() - held).abs() < 1e-3,
        "braked: {held} -> {}",
        r.angle()
    );
    assert_eq!(r.power(), PowerState::SwitchOnDisabled);
}

#[test]
fn velocity_mode_moves_the_finger_at_the_target_speed() {
    let mut r = Rig::new(Mode::CyclicSyncVelocity);
    r.run(300_000, Target::Stop);
    let start = r.angle();
    // 0.5 rad/s at the joint = 0.5 * 64 * 60 / (2 pi) rpm at the motor.
    let rpm = (0.5 * 64.0 * 60.0 / std::f64::consts::TAU).round() as i32;
    r.run(200_000, Target::velocity(rpm, TorqueLimit(1000)));
    let a = r.angle();
    r.run(400_000, Target::velocity(rpm, TorqueLimit(1000)));
    let speed = (r.angle() - a) / 0.4;
    assert!(r.angle() > start);
    assert!((speed - 0.5).abs() < 0.05, "{speed} rad/s");
}

/// CSV with the torque limit (0x6072) in RPDO1: the finger pushes into its stop with the
/// limit's force in N at the fingertip (250 per mille of 40 N = 10 N), never its full 20 N; no
/// limit, no motion; a limit above the finger's own maximum leaves that maximum.
#[test]
fn in_velocity_mode_the_torque_limit_bounds_the_fingers_force() {
    let mut r = Rig::new(Mode::CyclicSyncVelocity);
    r.run(300_000, Target::Stop);
    let rpm = (1.0 * 64.0 * 60.0 / std::f64::consts::TAU).round() as i32;
    let start = r.angle();
    r.run(500_000, Target::velocity(rpm, TorqueLimit::ZERO));
    assert!(r.bank.is_enabled(0), "{:?}", r.bank.status(0));
    assert!(
        (r.angle() - start).abs() < 1e-3,
        "no torque, no motion: {start} -> {}",
        r.angle()
    );
    assert_eq!(r.force(), 0.0);
    // 1 rad/s flexes the finger into its stop at 1.6 rad within 2.5 s.
    r.run(2_500_000, Target::velocity(rpm, TorqueLimit(250)));
    assert!(r.angle() > 1.55, "at the stop: {}", r.angle());
    for _ in 0..10 {
        r.run(50_000, Target::velocity(rpm, TorqueLimit(250)));
        assert!(
            (r.force() - 10.0).abs() < 1e-9,
            "pushing with the limit's 10 N: {} N",
            r.force()
        );
    }
    r.run(500_000, Target::velocity(rpm, TorqueLimit(1000)));
    assert!(
        (r.force() - 20.0).abs() < 1e-9,
        "40 N asked, the finger's 20 N: {} N",
        r.force()
    );
    let od = r
        .world
        .drive_fingers()
        .next()
        .expect("one drive")
        .drive()
        .od()
        .get(hand_canopen::ObjectAddr::new(0x6072, 0));
    assert_eq!(od, 1000, "0x6072 as RPDO1 carried it");
}

#[test]
fn a_tripped_or_power_cycled_drive_reaches_the_master_as_a_fault() {
    let mut r = Rig::new(Mode::CyclicSyncTorque);
    r.run(500_000, Target::torque(300));
    assert!(r.bank.is_enabled(0));
    r.world
        .drive_finger_mut(INDEX)
        .expect("drive")
        .inject_fault(0x2310);
    r.run(100_000, Target::torque(300));
    assert!(
        matches!(r.bank.status(0), DriveStatus::Faulted(DriveFault::Emcy(e)) if e.code == 0x2310),
        "{:?}",
        r.bank.status(0)
    );
    let held = r.angle();
    r.run(300_000, Target::torque(300));
    assert!(
        (r.angle() - held).abs() < 1e-3,
        "a faulted drive does not move"
    );
    r.bank.arm();
    r.run(500_000, Target::torque(300));
    assert!(r.bank.is_enabled(0), "{:?}", r.bank.status(0));
    let now = r.now;
    r.world
        .drive_finger_mut(INDEX)
        .expect("drive")
        .power_cycle(now);
    r.run(100_000, Target::torque(300));
    assert_eq!(r.bank.status(0), DriveStatus::Faulted(DriveFault::Rebooted));
}

#[test]
fn scheduled_drive_faults_trip_and_power_cycle_the_drive_when_they_start() {
    let f: hand_model::faults::Fault = "drive-trip:1".parse().expect("parses");
    assert_eq!(f, hand_model::faults::Fault::DriveTrip { finger: 1 });
    assert!("drive-power-cycle:5"
        .parse::<hand_model::faults::Fault>()
        .is_err());
    let mut plan = FaultPlan::new();
    plan.add(
        hand_model::faults::Fault::DriveTrip { finger: INDEX },
        700_000,
        800_000,
    )
    .expect("valid");
    plan.add(
        hand_model::faults::Fault::DrivePowerCycle { finger: INDEX },
        1_500_000,
        1_600_000,
    )
    .expect("valid");
    let mut r = Rig::with_faults(Mode::CyclicSyncTorque, plan);
    r.run(650_000, Target::torque(300));
    assert!(r.bank.is_enabled(0), "{:?}", r.bank.status(0));
    r.run(200_000, Target::torque(300));
    assert!(
        matches!(r.bank.status(0), DriveStatus::Faulted(DriveFault::Emcy(e)) if e.code == 0x2310),
        "{:?}",
        r.bank.status(0)
    );
    assert_eq!(
        r.power(),
        PowerState::Fault,
        "once, not again while the fault lasts"
    );
    r.bank.arm();
    r.run(500_000, Target::torque(300));
    assert!(r.bank.is_enabled(0), "{:?}", r.bank.status(0));
    r.run(300_000, Target::torque(300));
    assert_eq!(r.bank.status(0), DriveStatus::Faulted(DriveFault::Rebooted));
}
