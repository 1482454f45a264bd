//! An in-memory bus between the master core and simulated drives, with a virtual clock.

#![allow(dead_code)]

use hand_canopen::heartbeat::HeartbeatProducer;
use hand_canopen::sim::SimDrive;
use hand_canopen::startup::{Startup, StartupSettings, QUICK_STOP_RAMP_THEN_DISABLE};
use hand_canopen::{CanFrame, CobId, Mode, NmtState, NodeId, SyncProducer};

pub const MASTER: u8 = 100;
pub const DRIVE: u8 = 3;
/// The SYNC COB-ID the tests' start-up writes to 0x1005: not CiA 301's 0x080, which hand.dbc
/// gives HAND_ESTOP.
pub const SYNC_COB: u16 = 0x07F;

pub fn sync_cob() -> CobId {
    CobId::try_new(SYNC_COB).expect("11 bits")
}

pub fn node(id: u8) -> NodeId {
    NodeId::try_new(id).expect("test node id in range")
}

pub fn settings(mode: Mode) -> StartupSettings {
    StartupSettings {
        node: node(DRIVE),
        master: node(MASTER),
        mode,
        sync_period_us: 10_000,
        sync_cob_id: sync_cob(),
        master_heartbeat_timeout_ms: 100,
        drive_heartbeat_ms: 20,
        abort_connection: hand_canopen::startup::ABORT_CONNECTION_QUICK_STOP,
        quick_stop_option: QUICK_STOP_RAMP_THEN_DISABLE,
        sdo_timeout_us: 20_000,
        step_timeout_us: 200_000,
    }
}

/// The master side of the bench: the start-up of one drive, handd's heartbeat, SYNC,
/// and everything the drive sent (with the time).
pub struct Bench {
    pub now: u64,
    pub drive: SimDrive,
    pub startup: Startup,
    pub heartbeat: Option<HeartbeatProducer>,
    pub sync: Option<SyncProducer>,
    pub from_drive: Vec<(u64, CanFrame)>,
    pub to_drive: Vec<CanFrame>,
}

impl Bench {
    pub fn new(s: StartupSettings) -> Self {
        let steps = s.plan().expect("valid test settings");
        Self {
            now: 0,
            drive: SimDrive::new(s.node),
            startup: Startup::new(s.node, steps, s.sdo_timeout_us, s.step_timeout_us),
            heartbeat: Some(HeartbeatProducer::new(s.master, 10_000)),
            sync: None,
            from_drive: Vec::new(),
            to_drive: Vec::new(),
        }
    }

    /// Delivers `f` to the drive and the drive's answers to the master, until quiet.
    pub fn send(&mut self, f: CanFrame) {
        let mut queue = vec![f];
        while let Some(f) = queue.pop() {
            // An answer arrives after its request was sent (about 100 us at 1 Mbit/s).
            self.now += 100;
            self.to_drive.push(f);
            let mut out = Vec::new();
            self.drive.on_frame(&f, self.now, &mut out);
            for r in out {
                self.from_drive.push((self.now, r));
                if let Some(next) = self.startup.on_frame(&r, self.now) {
                    queue.push(next);
                }
            }
        }
    }

    /// One step of `dt_us`: the master's producers and start-up, then the drive's poll.
    pub fn step(&mut self, dt_us: u64) {
        self.now += dt_us;
        let now = self.now;
        if let Some(hb) = self.heartbeat.as_mut() {
            if let Some(f) = hb.poll(now, NmtState::Operational) {
                self.send(f);
            }
        }
        if let Some(sync) = self.sync.as_mut() {
            if let Some(f) = sync.poll(now) {
                self.send(f);
            }
        }
        while let Some(f) = self.startup.poll(now) {
            self.send(f);
        }
        let mut out = Vec::new();
        self.drive.poll(now, &mut out);
        for r in out {
            self.from_drive.push((now, r));
            if let Some(next) = self.startup.on_frame(&r, now) {
                self.send(next);
            }
        }
    }

    /// Steps until the start-up ends or `limit_us` passes.
    pub fn run_startup(&mut self, limit_us: u64) {
        let end = self.now + limit_us;
        while self.now < end
            && matches!(
                self.startup.status(),
                hand_canopen::StartupStatus::Running(_)
            )
        {
            self.step(1_000);
        }
    }
}
