//! The drive bank (every finger drive after start-up) against simulated CiA 402 drives on
//! an in-memory bus: start-up, per-tick RPDO1 + SYNC + heartbeat, faults latched until `arm`.

use hand_canopen::master::{
    BankError, BankSettings, DriveBank, DriveFault, DriveStatus, Target, TorqueLimit,
};
use hand_canopen::sim::SimDrive;
use hand_canopen::startup::{Step, StepFailure};
use hand_canopen::{CanFrame, CobId, Mode, NmtState, NodeId, ObjectAddr, PowerState};

const TICK_US: u64 = 50_000;
const MASTER: u8 = 127;
const SYNC: u16 = 0x07F;

fn node(id: u8) -> NodeId {
    NodeId::try_new(id).expect("in range")
}

fn settings() -> BankSettings {
    BankSettings {
        master: node(MASTER),
        tick_us: TICK_US as u32,
        sync_cob_id: CobId::try_new(SYNC).expect("11 bits"),
        master_heartbeat_timeout_ms: 150,
        drive_heartbeat_ms: 50,
        drive_heartbeat_timeout_us: 150_000,
        sdo_timeout_us: 20_000,
        step_timeout_us: 200_000,
    }
}

const DRIVES: [(u8, Mode); 3] = [
    (5, Mode::CyclicSyncTorque),
    (6, Mode::CyclicSyncVelocity),
    (7, Mode::ProfileVelocity),
];

/// handd's side (the bank) and the drives on one in-memory bus, with a virtual clock.
struct Hand {
    now: u64,
    bank: DriveBank,
    drives: Vec<SimDrive>,
    /// Every frame the bank sent, with the time.
    sent: Vec<(u64, CanFrame)>,
}

impl Hand {
    fn new() -> Self {
        let list: Vec<(NodeId, Mode)> = DRIVES.iter().map(|&(n, m)| (node(n), m)).collect();
        let bank = DriveBank::try_new(settings(), &list).expect("valid bank");
        let mut drives: Vec<SimDrive> = DRIVES
            .iter()
            .map(|&(n, _)| SimDrive::new(node(n)))
            .collect();
        let mut boot = Vec::new();
        for d in &mut drives {
            d.power_on(0, &mut boot);
        }
        Self {
            now: 0,
            bank,
            drives,
            sent: Vec::new(),
        }
    }

    /// Delivers frames from the bank to every drive and the drives' answers back, until quiet.
    fn deliver(&mut self, from_bank: Vec<CanFrame>) {
        let mut queue: Vec<(bool, CanFrame)> = from_bank.into_iter().map(|f| (true, f)).collect();
        queue.reverse();
        while let Some((by_bank, f)) = queue.pop() {
            // A frame takes time on the bus (about 100 us at 1 Mbit/s): an answer is never
            // received at the instant its request was sent.
            self.now += 100;
            let now = self.now;
            let mut answers = Vec::new();
            if by_bank {
                self.sent.push((now, f));
            } else {
                let mut replies = Vec::new();
                self.bank.on_frame(&f, now, &mut |r| replies.push(r));
                answers.extend(replies.into_iter().map(|r| (true, r)));
            }
            for d in &mut self.drives {
                let mut out = Vec::new();
                d.on_frame(&f, now, &mut out);
                answers.extend(out.into_iter().map(|r| (false, r)));
            }
            answers.reverse();
            queue.extend(answers);
        }
    }

    /// The drives' own clocks advance by `dt` (heartbeats, watchdog, quick stop ramp).
    fn poll_drives(&mut self) {
        let mut out = Vec::new();
        for d in &mut self.drives {
            d.poll(self.now, &mut out);
        }
        let frames: Vec<(bool, CanFrame)> = out.into_iter().map(|f| (false, f)).collect();
        for (_, f) in frames {
            let mut replies = Vec::new();
            self.bank.on_frame(&f, self.now, &mut |r| replies.push(r));
            for d in &mut self.drives {
                let mut ignored = Vec::new();
                d.on_frame(&f, self.now, &mut ignored);
            }
            self.deliver(replies);
        }
    }

    /// One tick of handd's loop with `targets`; the frames the tick sent.
    fn tick(&mut self, targets: &[Target]) -> Vec<CanFrame> {
        self.now += TICK_US;
        let mut out = Vec::new();
        self.bank.tick(self.now, targets, &mut |f| out.push(f));
        self.deliver(out.clone());
        self.poll_drives();
        out
    }

    fn ticks(&mut self, n: usize, targets: &[Target]) {
        for _ in 0..n {
            self.tick(targets);
        }
    }

    fn od(&self, k: usize, index: u16, sub: u8) -> u32 {
        self.drives[k].od().get(ObjectAddr::new(index, sub))
    }
}

const STOP: [Target; 3] = [Target::Stop; 3];
const RUN: [Target; 3] = [
    Target::torque(250),
    Target::velocity(-1200, TorqueLimit(400)),
    Target::velocity(900, TorqueLimit(650)),
];

/// Started and then driven: every drive enabled and following its target.
fn running() -> Hand {
    let mut h = Hand::new();
    h.ticks(2, &STOP);
    for k in 0..3 {
        assert!(
            matches!(h.bank.status(k), DriveStatus::Running { .. }),
            "drive {k} after start-up: {:?}",
            h.bank.status(k)
        );
    }
    h.ticks(5, &RUN);
    for k in 0..3 {
        assert!(h.bank.is_enabled(k), "drive {k}: {:?}", h.bank.status(k));
    }
    h
}

#[test]
fn every_drive_starts_then_follows_its_target_each_tick() {
    let mut h = running();
    assert_eq!(h.od(0, 0x6071, 0) as u16 as i16, 250);
    assert_eq!(h.od(1, 0x60FF, 0) as i32, -1200);
    assert_eq!(h.od(2, 0x60FF, 0) as i32, 900);
    // The velocity drives' torque limit arrived with the target; the torque drive's 0x6072
    // is not mapped and keeps its default.
    assert_eq!(h.od(1, 0x6072, 0), 400);
    assert_eq!(h.od(2, 0x6072, 0), 650);
    assert_eq!(h.od(0, 0x6072, 0), 1000);
    let DriveStatus::Running {
        feedback: Some(fb), ..
    } = h.bank.status(0)
    else {
        panic!("drive 0 has feedback: {:?}", h.bank.status(0));
    };
    assert_eq!(fb.torque_permille, 250);
    // One tick: RPDO1 of each drive in order, then SYNC on 0x07F, then handd's heartbeat.
    let frames = h.tick(&RUN);
    let ids: Vec<u16> = frames.iter().map(CanFrame::cob_id).collect();
    assert_eq!(
        ids,
        vec![0x205, 0x206, 0x207, SYNC, 0x700 + u16::from(MASTER)]
    );
    assert_eq!(frames[0].payload(), &[0x0F, 0x00, 250, 0x00]);
    let v = (-1200_i32).to_le_bytes();
    assert_eq!(
        frames[1].payload(),
        &[0x0F, 0x00, v[0], v[1], v[2], v[3], 0x90, 0x01]
    );
    assert_eq!(frames[4].payload(), &[NmtState::Operational.byte()]);
    for d in &h.drives {
        assert_eq!(d.power_state(), PowerState::OperationEnabled);
        assert_eq!(d.stats().watchdog_trips, 0);
    }
}

#[test]
fn a_stop_is_a_quick_stop_with_the_target_zeroed_and_running_again_walks_the_state_machine() {
    let mut h = running();
    let frames = h.tick(&STOP);
    for f in &frames[..3] {
        assert_eq!(&f.payload()[..2], &[0x02, 0x00], "quick stop controlword");
        assert!(
            f.payload()[2..].iter().all(|&b| b == 0),
            "target (and torque limit) zeroed"
        );
    }
    h.ticks(2, &STOP);
    for (k, d) in h.drives.iter().enumerate() {
        assert_eq!(d.power_state(), PowerState::SwitchOnDisabled, "drive {k}");
        assert!(d.stats().quick_stops >= 1);
        assert!(!h.bank.is_faulted(k), "a commanded stop is not a fault");
    }
    // Back to running: Shutdown, Switch on, Enable operation, one per tick, target 0 meanwhile.
    let mut enabled_after = None;
    for t in 1..=6 {
        let frames = h.tick(&RUN);
        if enabled_after.is_none() && (0..3).all(|k| h.bank.is_enabled(k)) {
            enabled_after = Some(t);
        }
        if enabled_after.is_none() {
            assert_eq!(
                &frames[0].payload()[2..4],
                &[0, 0],
                "no target before enabled"
            );
            assert_eq!(
                &frames[1].payload()[2..],
                &[0; 6],
                "no target and no torque limit before enabled"
            );
        }
    }
    assert!(enabled_after.is_some_and(|t| t <= 5), "{enabled_after:?}");
    assert_eq!(h.drives[0].power_state(), PowerState::OperationEnabled);
}

#[test]
fn a_silent_drive_is_faulted_at_its_step_and_the_others_run() {
    let mut h = Hand::new();
    h.drives[1].set_silent(true);
    h.ticks(12, &RUN);
    match h.bank.status(1) {
        DriveStatus::Faulted(DriveFault::Startup(e)) => {
            assert_eq!(e.step, Step::AwaitBootUp);
            assert!(matches!(e.cause, StepFailure::NoBootUp(_)), "{e}");
        }
        s => panic!("silent drive: {s:?}"),
    }
    assert!(h.bank.is_enabled(0) && h.bank.is_enabled(2));
}

#[test]
fn an_emcy_latches_a_fault_that_only_arm_clears() {
    let mut h = running();
    let mut out = Vec::new();
    h.drives[2].inject_fault(0x2310, &mut out);
    let emcy = out[0];
    h.deliver(vec![]);
    let mut replies = Vec::new();
    h.bank.on_frame(&emcy, h.now, &mut |r| replies.push(r));
    let DriveStatus::Faulted(DriveFault::Emcy(e)) = h.bank.status(2) else {
        panic!("after EMCY: {:?}", h.bank.status(2));
    };
    assert_eq!(e.code, 0x2310);
    // Running targets do not re-enable it: quick stop each tick, the fault stays.
    for _ in 0..4 {
        let frames = h.tick(&RUN);
        assert_eq!(&frames[2].payload()[..2], &[0x02, 0x00]);
    }
    assert_eq!(h.drives[2].power_state(), PowerState::Fault);
    assert!(matches!(
        h.bank.status(2),
        DriveStatus::Faulted(DriveFault::Emcy(_))
    ));
    assert!(
        h.bank.is_enabled(0) && h.bank.is_enabled(1),
        "the others run"
    );
    // arm: start-up from scratch, fault reset on the way to Operation enabled.
    assert_eq!(h.bank.arm(), 1);
    h.ticks(3, &RUN);
    assert!(h.bank.is_enabled(2), "{:?}", h.bank.status(2));
    assert_eq!(h.drives[2].power_state(), PowerState::OperationEnabled);
}

#[test]
fn a_drive_that_reboots_mid_run_is_reconfigured_only_on_arm() {
    let mut h = running();
    let mut boot = Vec::new();
    h.drives[0].power_on(h.now, &mut boot);
    assert_eq!(h.od(0, 0x1016, 1), 0, "its configuration is gone");
    h.deliver(vec![]);
    for f in boot {
        let mut replies = Vec::new();
        h.bank.on_frame(&f, h.now, &mut |r| replies.push(r));
        assert!(replies.is_empty());
    }
    assert_eq!(h.bank.status(0), DriveStatus::Faulted(DriveFault::Rebooted));
    h.ticks(4, &RUN);
    assert_eq!(h.bank.status(0), DriveStatus::Faulted(DriveFault::Rebooted));
    assert_ne!(h.drives[0].power_state(), PowerState::OperationEnabled);
    assert_eq!(h.bank.arm(), 1);
    h.ticks(3, &RUN);
    assert!(h.bank.is_enabled(0), "{:?}", h.bank.status(0));
    assert_eq!(h.od(0, 0x1016, 1), (u32::from(MASTER) << 16) | 150);
}

#[test]
fn feedback_older_than_three_periods_faults_the_drive() {
    let mut h = running();
    h.drives[1].set_silent(true);
    let mut faulted_at = None;
    for t in 1..=6 {
        h.tick(&RUN);
        if faulted_at.is_none() && h.bank.is_faulted(1) {
            faulted_at = Some(t);
        }
    }
    assert!(
        matches!(faulted_at, Some(3..=4)),
        "faulted after {faulted_at:?} ticks"
    );
    assert!(
        matches!(
            h.bank.status(1),
            DriveStatus::Faulted(
                DriveFault::FeedbackStale { .. } | DriveFault::HeartbeatLost { .. }
            )
        ),
        "{:?}",
        h.bank.status(1)
    );
    assert!(h.bank.is_enabled(0) && h.bank.is_enabled(2));
}

#[test]
fn when_the_loop_stops_every_drive_quick_stops_by_itself() {
    let mut h = running();
    // handd hangs: no tick, so no RPDO, no SYNC, no heartbeat; the drives' clocks go on.
    for _ in 0..10 {
        h.now += 20_000;
        h.poll_drives();
    }
    for (k, d) in h.drives.iter().enumerate() {
        assert_eq!(d.stats().watchdog_trips, 1, "drive {k}");
        assert_ne!(d.power_state(), PowerState::OperationEnabled, "drive {k}");
    }
}

#[test]
fn after_bus_off_recovery_nothing_is_enabled_before_arm_reads_every_drive_again() {
    let mut h = running();
    h.bank.bus_recovered();
    for k in 0..3 {
        assert_eq!(
            h.bank.status(k),
            DriveStatus::Faulted(DriveFault::BusRecovered)
        );
    }
    let frames = h.tick(&RUN);
    assert!(frames[..3].iter().all(|f| f.payload()[..2] == [0x02, 0x00]));
    assert_eq!(h.bank.arm(), 3);
    h.ticks(3, &RUN);
    assert!((0..3).all(|k| h.bank.is_enabled(k)));
}

#[test]
fn a_bank_that_cannot_work_is_refused() {
    let two = [
        (node(5), Mode::CyclicSyncTorque),
        (node(5), Mode::CyclicSyncVelocity),
    ];
    assert_eq!(
        DriveBank::try_new(settings(), &two).err(),
        Some(BankError::DuplicateNode(5))
    );
    let own = [(node(MASTER), Mode::CyclicSyncTorque)];
    assert!(matches!(
        DriveBank::try_new(settings(), &own),
        Err(BankError::Settings { node: MASTER, .. })
    ));
    let mut s = settings();
    s.drive_heartbeat_timeout_us = 50_000;
    assert!(matches!(
        DriveBank::try_new(s, &[(node(5), Mode::CyclicSyncTorque)]),
        Err(BankError::HeartbeatTimeout { .. })
    ));
}

#[test]
fn nothing_left_in_a_drive_can_move_it_on_enable() {
    use hand_canopen::startup::{
        StartupSettings, ABORT_CONNECTION_QUICK_STOP, QUICK_STOP_RAMP_THEN_DISABLE,
    };
    for (mode, zeroed) in [
        (Mode::CyclicSyncTorque, vec![0x6071]),
        (Mode::CyclicSyncVelocity, vec![0x60FF, 0x6072]),
        (Mode::ProfileVelocity, vec![0x60FF, 0x6072]),
    ] {
        let plan = StartupSettings {
            node: node(5),
            master: node(MASTER),
            mode,
            sync_period_us: TICK_US as u32,
            sync_cob_id: CobId::try_new(SYNC).expect("11 bits"),
            master_heartbeat_timeout_ms: 150,
            drive_heartbeat_ms: 50,
            abort_connection: ABORT_CONNECTION_QUICK_STOP,
            quick_stop_option: QUICK_STOP_RAMP_THEN_DISABLE,
            sdo_timeout_us: 20_000,
            step_timeout_us: 200_000,
        }
        .plan()
        .expect("a valid plan");
        let start = plan
            .iter()
            .position(|s| matches!(s, Step::StartNode))
            .expect("NMT start in the plan");
        // Each object written 0 before the node starts, and read back as 0.
        for index in &zeroed {
            let zero_at = |s: &Step, write: bool| match s {
                Step::ZeroTarget(w) if write => {
                    w.addr == ObjectAddr::new(*index, 0) && w.data.as_u32() == 0
                }
                Step::ReadBack(w) if !write => {
                    w.addr == ObjectAddr::new(*index, 0) && w.data.as_u32() == 0
                }
                _ => false,
            };
            assert!(
                plan[..start].iter().any(|s| zero_at(s, true))
                    && plan[..start].iter().any(|s| zero_at(s, false)),
                "{mode:?}: 0x{index:04X} zeroed and read back before NMT start"
            );
        }
        let all: Vec<u16> = plan
            .iter()
            .filter_map(|s| match s {
                Step::ZeroTarget(w) => Some(w.addr.index),
                _ => None,
            })
            .collect();
        assert_eq!(all, zeroed, "{mode:?}");
    }
    // And on the simulated drives: a velocity drive reaches Operation enabled with a zero
    // torque limit (its dictionary's default is 1000 per mille), before any RPDO1 brings one.
    let mut h = Hand::new();
    let mut ticks = 0;
    while h.drives[1].power_state() != PowerState::OperationEnabled {
        assert!(ticks < 100, "drive 1 never enabled: {:?}", h.bank.status(1));
        h.tick(&STOP);
        ticks += 1;
    }
    assert!(
        !h.sent.iter().any(|(_, f)| f.cob_id() == 0x206),
        "an RPDO1 reached drive 1 before it was enabled"
    );
    assert_eq!(h.od(1, 0x6072, 0), 0);
    assert_eq!(h.od(1, 0x60FF, 0), 0);
}
