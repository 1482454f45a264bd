//! The drives of the hand after validation: each in one phase (starting, running, faulted),
//! the frames a tick sends (RPDO1 per drive, then one SYNC and handd's heartbeat, all from
//! the caller's loop), and every frame from the bus routed to its drive.

use super::cyclic::{decode_tpdo1, is_tpdo1_of, rpdo1, Feedback, Setpoint, Target};
use super::fault::DriveFault;
use crate::cia402::{Command, Controlword, DriverStep, Mode, PowerDriver, PowerState};
use crate::emcy::Emcy;
use crate::frame::CanFrame;
use crate::heartbeat::{HeartbeatConsumer, HeartbeatEvent, HeartbeatProducer};
use crate::ids::{CobId, NodeId};
use crate::nmt::NmtState;
use crate::startup::{
    Identity, SettingsError, Startup, StartupSettings, StartupStatus, Step,
    ABORT_CONNECTION_QUICK_STOP, QUICK_STOP_RAMP_THEN_DISABLE,
};
use crate::sync::sync_frame_on;
use thiserror::Error;

/// TPDO1 older than this many SYNC periods is a fault of its drive.
pub const STALE_PERIODS: u64 = 3;

/// What every drive of the bank shares.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BankSettings {
    /// handd's node id: its heartbeat, which each drive watches.
    pub master: NodeId,
    /// The tick: one RPDO1 per drive, one SYNC and one heartbeat per tick (0x60C2 too).
    pub tick_us: u32,
    /// The SYNC COB-ID written to each drive's 0x1005.
    pub sync_cob_id: CobId,
    /// How long a drive tolerates silence from handd's heartbeat before its quick stop, ms.
    pub master_heartbeat_timeout_ms: u16,
    /// Each drive's heartbeat period (0x1017), ms.
    pub drive_heartbeat_ms: u16,
    /// How long handd tolerates silence from a drive's heartbeat, us.
    pub drive_heartbeat_timeout_us: u64,
    /// Each SDO transfer's timeout at start-up, us.
    pub sdo_timeout_us: u64,
    /// The boot-up wait's and each power state step's timeout, us.
    pub step_timeout_us: u64,
}

/// A bank that cannot work.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Error)]
pub enum BankError {
    /// Two drives on one node id.
    #[error("two drives on node id {0}")]
    DuplicateNode(u8),
    /// One drive's start-up settings.
    #[error("drive {node}: {cause}")]
    Settings {
        /// The drive.
        node: u8,
        /// Why.
        cause: SettingsError,
    },
    /// The drives' heartbeat timeout does not outlast their heartbeat period.
    #[error(
        "drive heartbeat timeout {timeout_us} us is not longer than its period {period_ms} ms"
    )]
    HeartbeatTimeout {
        /// The consumer's timeout.
        timeout_us: u64,
        /// The drives' period.
        period_ms: u16,
    },
}

/// Where one drive is, as the daemon's status shows it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DriveStatus {
    /// Starting up, at this step.
    Starting(Step),
    /// Configured and operational.
    Running {
        /// In Operation enabled and following its target (otherwise held in quick stop or
        /// being walked back by controlword).
        enabled: bool,
        /// 0x1018 as read at start-up.
        identity: Identity,
        /// The newest TPDO1.
        feedback: Option<Feedback>,
    },
    /// Latched until `arm`.
    Faulted(DriveFault),
}

#[derive(Clone, Debug)]
struct Run {
    identity: Identity,
    since_us: u64,
    feedback: Option<Feedback>,
    enabled: bool,
    walk: Option<PowerDriver>,
    cw: Controlword,
}

#[derive(Clone, Debug)]
enum Phase {
    Starting(Box<Startup>),
    Running(Run),
    Faulted(DriveFault),
}

#[derive(Clone, Debug)]
struct Slot {
    settings: StartupSettings,
    steps: Vec<Step>,
    phase: Phase,
}

impl Slot {
    fn start(&mut self) {
        let s = &self.settings;
        self.phase = Phase::Starting(Box::new(Startup::new(
            s.node,
            self.steps.clone(),
            s.sdo_timeout_us,
            s.step_timeout_us,
        )));
    }

    /// Latches `fault` unless one is latched already (the first cause is the one shown).
    fn fault(&mut self, fault: DriveFault) {
        if !matches!(self.phase, Phase::Faulted(_)) {
            self.phase = Phase::Faulted(fault);
        }
    }
}

/// The finger drives: start-up, the per-tick exchange, faults, recovery on `arm`.
#[derive(Clone, Debug)]
pub struct DriveBank {
    settings: BankSettings,
    slots: Vec<Slot>,
    heartbeat: HeartbeatProducer,
    consumer: HeartbeatConsumer,
}

impl DriveBank {
    /// Validates every drive's start-up once; each drive starts at the first tick.
    pub fn try_new(settings: BankSettings, drives: &[(NodeId, Mode)]) -> Result<Self, BankError> {
        if settings.drive_heartbeat_timeout_us <= u64::from(settings.drive_heartbeat_ms) * 1000 {
            return Err(BankError::HeartbeatTimeout {
                timeout_us: settings.drive_heartbeat_timeout_us,
                period_ms: settings.drive_heartbeat_ms,
            });
        }
        let mut slots: Vec<Slot> = Vec::with_capacity(drives.len());
        let mut consumer = HeartbeatConsumer::new();
        for &(node, mode) in drives {
            if slots.iter().any(|s| s.settings.node == node) {
                return Err(BankError::DuplicateNode(node.get()));
            }
            let s = StartupSettings {
                node,
                master: settings.master,
                mode,
                sync_period_us: settings.tick_us,
                sync_cob_id: settings.sync_cob_id,
                master_heartbeat_timeout_ms: settings.master_heartbeat_timeout_ms,
                drive_heartbeat_ms: settings.drive_heartbeat_ms,
                abort_connection: ABORT_CONNECTION_QUICK_STOP,
                quick_stop_option: QUICK_STOP_RAMP_THEN_DISABLE,
                sdo_timeout_us: settings.sdo_timeout_us,
                step_timeout_us: settings.step_timeout_us,
            };
            let steps = s.plan().map_err(|cause| BankError::Settings {
                node: node.get(),
                cause,
            })?;
            consumer.watch(node, settings.drive_heartbeat_timeout_us);
            let mut slot = Slot {
                settings: s,
                steps,
                phase: Phase::Faulted(DriveFault::NotStarted),
            };
            slot.start();
            slots.push(slot);
        }
        Ok(Self {
            settings,
            slots,
            heartbeat: HeartbeatProducer::new(settings.master, u64::from(settings.tick_us)),
            consumer,
        })
    }

    /// How many drives.
    pub fn len(&self) -> usize {
        self.slots.len()
    }

    /// Whether the bank has no drive.
    pub fn is_empty(&self) -> bool {
        self.slots.is_empty()
    }

    /// Drive `k`'s node id.
    pub fn node(&self, k: usize) -> NodeId {
        self.slots[k].settings.node
    }

    /// Drive `k`'s operating mode.
    pub fn mode(&self, k: usize) -> Mode {
        self.slots[k].settings.mode
    }

    /// Drive `k`'s status.
    pub fn status(&self, k: usize) -> DriveStatus {
        match &self.slots[k].phase {
            Phase::Starting(s) => match s.status() {
                StartupStatus::Running(step) => DriveStatus::Starting(step),
                // Finished but not yet taken over by a tick.
                StartupStatus::Done { .. } => DriveStatus::Starting(Step::Enable),
                StartupStatus::Failed(e) => DriveStatus::Faulted(e.into()),
            },
            Phase::Running(r) => DriveStatus::Running {
                enabled: r.enabled,
                identity: r.identity,
                feedback: r.feedback,
            },
            Phase::Faulted(f) => DriveStatus::Faulted(*f),
        }
    }

    /// Whether drive `k` follows its target now (Operation enabled, no fault).
    pub fn is_enabled(&self, k: usize) -> bool {
        matches!(&self.slots[k].phase, Phase::Running(r) if r.enabled)
    }

    /// Whether drive `k` has a latched fault (including a failed or pending start).
    pub fn is_faulted(&self, k: usize) -> bool {
        matches!(self.status(k), DriveStatus::Faulted(_))
    }

    /// `handctl arm`: every faulted drive starts from scratch (reset communication, boot-up,
    /// identity, configuration read back, fault reset and the power state machine). Running
    /// drives are left alone. Returns how many were restarted.
    pub fn arm(&mut self) -> usize {
        let mut n = 0;
        for s in &mut self.slots {
            if matches!(s.phase, Phase::Faulted(_)) {
                s.start();
                n += 1;
            }
        }
        n
    }

    /// The bus came back from bus-off: no drive's NMT or power state is known any more.
    /// Every drive is faulted until `arm` reads and configures it again.
    pub fn bus_recovered(&mut self) {
        for s in &mut self.slots {
            s.fault(DriveFault::BusRecovered);
        }
    }

    /// Offers a frame from the bus at `now`; frames to send at once (SDO steps of a
    /// start-up) go to `out`.
    pub fn on_frame(&mut self, f: &CanFrame, now_us: u64, out: &mut impl FnMut(CanFrame)) {
        if let Some(HeartbeatEvent::BootUp(node)) = self.consumer.on_frame(f, now_us) {
            if let Some(s) = self.slots.iter_mut().find(|s| s.settings.node == node) {
                if !matches!(s.phase, Phase::Starting(_)) {
                    s.fault(DriveFault::Rebooted);
                }
            }
        }
        if let Ok(e) = Emcy::decode(f) {
            if let Some(s) = self.slots.iter_mut().find(|s| s.settings.node == e.node) {
                if !e.is_reset() {
                    s.fault(DriveFault::Emcy(e));
                }
                return;
            }
        }
        for s in &mut self.slots {
            let node = s.settings.node;
            let mut fault = None;
            match &mut s.phase {
                Phase::Running(r) if is_tpdo1_of(f, node) => {
                    if let Some(fb) = decode_tpdo1(f, now_us) {
                        r.feedback = Some(fb);
                        fault = check_state(r, fb);
                    }
                }
                Phase::Starting(st) => {
                    if let Some(reply) = st.on_frame(f, now_us) {
                        out(reply);
                    }
                    // The next step goes out at bus speed, not at the next tick; but the reset
                    // that begins a start-up only at a tick, after every frame received up to
                    // it was read, so a boot-up read later is the answer to it.
                    if !matches!(
                        st.status(),
                        StartupStatus::Running(Step::ResetCommunication)
                    ) {
                        while let Some(next) = st.poll(now_us) {
                            out(next);
                        }
                    }
                    continue;
                }
                _ => continue,
            }
            if let Some(fault) = fault {
                s.fault(fault);
            }
            return;
        }
    }

    /// One tick at `now`: each drive's start-up advanced, its freshness checked, its RPDO1
    /// (`targets[k]`; a missing one is a stop), then SYNC and handd's heartbeat. No
    /// allocation once every drive runs.
    pub fn tick(&mut self, now_us: u64, targets: &[Target], out: &mut impl FnMut(CanFrame)) {
        let limit_us = STALE_PERIODS * u64::from(self.settings.tick_us);
        let timeout_us = self.settings.drive_heartbeat_timeout_us;
        let step_timeout_us = self.settings.step_timeout_us;
        let slots = &mut self.slots;
        self.consumer.poll(now_us, |node| {
            if let Some(s) = slots.iter_mut().find(|s| s.settings.node == node) {
                if matches!(s.phase, Phase::Running(_)) {
                    s.fault(DriveFault::HeartbeatLost { timeout_us });
                }
            }
        });
        for (k, s) in self.slots.iter_mut().enumerate() {
            let target = targets.get(k).copied().unwrap_or(Target::Stop);
            let (node, mode) = (s.settings.node, s.settings.mode);
            if let Phase::Starting(st) = &mut s.phase {
                while let Some(f) = st.poll(now_us) {
                    out(f);
                }
                match st.status() {
                    StartupStatus::Running(_) => continue,
                    StartupStatus::Done { identity, .. } => {
                        s.phase = Phase::Running(Run {
                            identity,
                            since_us: now_us,
                            feedback: None,
                            enabled: true,
                            walk: None,
                            cw: Command::EnableOperation.controlword(),
                        });
                    }
                    StartupStatus::Failed(e) => s.phase = Phase::Faulted(e.into()),
                }
            }
            if let Phase::Running(r) = &s.phase {
                let last = r.feedback.map_or(r.since_us, |f| f.at_us.max(r.since_us));
                let age_us = now_us.saturating_sub(last);
                if age_us > limit_us {
                    s.fault(DriveFault::FeedbackStale { age_us, limit_us });
                }
            }
            let step = match &mut s.phase {
                Phase::Running(r) => run_step(r, target, now_us, step_timeout_us),
                _ => Ok(stop()),
            };
            let (cw, sp) = step.unwrap_or_else(|fault| {
                s.fault(fault);
                stop()
            });
            out(rpdo1(node, mode, cw, sp));
        }
        out(sync_frame_on(self.settings.sync_cob_id));
        out(self.heartbeat.frame(NmtState::Operational));
    }
}

impl DriveBank {
    /// At once, outside the tick (the bus came back, handd exits): every configured drive's
    /// RPDO1 with the quick stop and its target (and torque limit) zeroed, then the SYNC that
    /// applies them. No
    /// state changes: the next tick decides again.
    pub fn stop_frames(&mut self, out: &mut impl FnMut(CanFrame)) {
        for s in &mut self.slots {
            if let Phase::Running(r) = &mut s.phase {
                r.enabled = false;
                r.walk = None;
                r.cw = Command::QuickStop.controlword();
            }
            if !matches!(s.phase, Phase::Starting(_)) {
                let (cw, sp) = stop();
                out(rpdo1(s.settings.node, s.settings.mode, cw, sp));
            }
        }
        out(sync_frame_on(self.settings.sync_cob_id));
    }
}

/// The quick stop with the target and the torque limit zeroed. A zero limit (CSV, PV) means
/// the drive's ramp to standstill cannot push either: the finger is let go rather than held
/// or braked by the motor, and no force reaches the fingertip that the last setpoint did not
/// ask for (a stop may follow a stale or invalid setpoint, so no earlier limit is trusted).
fn stop() -> (Controlword, Setpoint) {
    (Command::QuickStop.controlword(), Setpoint::ZERO)
}

/// The RPDO1 content of a running drive for `target`; walks it back to Operation enabled
/// by controlword (one command per observed statusword) when it was stopped, target and
/// torque limit zero meanwhile.
fn run_step(
    r: &mut Run,
    target: Target,
    now_us: u64,
    step_timeout_us: u64,
) -> Result<(Controlword, Setpoint), DriveFault> {
    let sp = match target {
        Target::Stop => {
            r.enabled = false;
            r.walk = None;
            r.cw = Command::QuickStop.controlword();
            return Ok(stop());
        }
        Target::Run { value, max_torque } => Setpoint { value, max_torque },
    };
    if r.enabled {
        r.cw = Command::EnableOperation.controlword();
        return Ok((r.cw, sp));
    }
    let walk = r
        .walk
        .get_or_insert_with(|| PowerDriver::new(step_timeout_us));
    let Some(fb) = r.feedback else {
        return Ok((r.cw, Setpoint::ZERO));
    };
    match walk.step(fb.statusword, now_us)? {
        DriverStep::Send(cw) => r.cw = cw,
        DriverStep::Wait => {}
        DriverStep::Reached => {
            r.enabled = true;
            r.walk = None;
            r.cw = Command::EnableOperation.controlword();
            return Ok((r.cw, sp));
        }
    }
    Ok((r.cw, Setpoint::ZERO))
}

/// What a TPDO1 statusword means for a running drive.
fn check_state(r: &Run, fb: Feedback) -> Option<DriveFault> {
    let state = fb.statusword.state();
    match state {
        None => Some(DriveFault::Enable(
            crate::cia402::Cia402Error::UnknownStatusword(fb.statusword.0),
        )),
        Some(PowerState::Fault | PowerState::FaultReactionActive) => Some(DriveFault::DriveFault),
        Some(PowerState::OperationEnabled) => None,
        Some(s) if r.enabled => Some(DriveFault::LeftOperation(s)),
        Some(_) => None,
    }
}
