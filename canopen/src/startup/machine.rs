//! The start-up of one drive as a sans-IO state machine: feed it frames and `now`, send
//! what [`Startup::poll`] returns, read its [`Startup::status`].

use super::step::Step;
use crate::cia402::{objects, Cia402Error, Controlword, DriverStep, PowerDriver, Statusword};
use crate::frame::CanFrame;
use crate::ids::{NodeId, ObjectAddr};
use crate::nmt::{ErrorControl, NmtCommand};
use crate::sdo::{SdoClient, SdoData, SdoDone, SdoError};
use thiserror::Error;

/// Why a step failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Error)]
pub enum StepFailure {
    /// The SDO transfer failed (abort code named inside).
    #[error(transparent)]
    Sdo(#[from] SdoError),
    /// No boot-up message within the step timeout.
    #[error("no boot-up message within {0} us")]
    NoBootUp(u64),
    /// 0x6502 does not list the mode.
    #[error("mode {mode} not in supported modes 0x{supported:08X}")]
    ModeUnsupported {
        /// The mode configured.
        mode: i8,
        /// 0x6502 as read.
        supported: u32,
    },
    /// Read back a different value than written.
    #[error("read back {got:?}, wrote {expected:?}")]
    ReadBack {
        /// What was written.
        expected: SdoData,
        /// What was read.
        got: SdoData,
    },
    /// The power state machine did not reach Operation enabled.
    #[error(transparent)]
    Cia402(#[from] Cia402Error),
    /// The drive booted again during its start-up, more often than
    /// [`MAX_BOOT_UPS_DURING_STARTUP`].
    #[error(
        "the drive kept booting during start-up ({} boot-ups after the one answering the reset)",
        MAX_BOOT_UPS_DURING_STARTUP + 1
    )]
    UnexpectedBootUp,
}

/// Boot-ups after the answer to the reset that start the start-up again (after the boot-up)
/// before a further one fails it. A drive powered on while handd starts sends its power-on
/// boot-up and then answers handd's reset with a second one, which may come while handd
/// already reads its identity; one that keeps rebooting (a brown-out) is a fault.
pub const MAX_BOOT_UPS_DURING_STARTUP: u8 = 3;

/// A failed start-up: the drive, the step, the reason.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Error)]
#[error("{node}: start-up step `{step}` failed: {cause}")]
pub struct StartupError {
    /// The drive.
    pub node: NodeId,
    /// The step that failed.
    pub step: Step,
    /// Why.
    pub cause: StepFailure,
}

/// The drive's identity (0x1018); optional subindices the drive lacks are `None`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Identity {
    /// Vendor id.
    pub vendor: u32,
    /// Product code.
    pub product: Option<u32>,
    /// Revision number.
    pub revision: Option<u32>,
    /// Serial number.
    pub serial: Option<u32>,
}

/// Where the start-up is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StartupStatus {
    /// In progress, at this step.
    Running(Step),
    /// Operation enabled; what was learned.
    Done {
        /// 0x1018.
        identity: Identity,
        /// 0x6502.
        supported_modes: u32,
    },
    /// Failed.
    Failed(StartupError),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Phase {
    /// The current step has not sent anything yet.
    Issue,
    /// Waiting for a reply (SDO in flight, or boot-up) until the deadline.
    Await,
    /// Enable: a statusword read in flight.
    ReadStatus,
    /// Enable: a controlword write in flight.
    WriteControl,
}

/// One drive's start-up.
#[derive(Clone, Debug)]
pub struct Startup {
    node: NodeId,
    steps: Vec<Step>,
    at: usize,
    phase: Phase,
    deadline_us: u64,
    step_timeout_us: u64,
    sdo: SdoClient,
    power: PowerDriver,
    identity: Identity,
    supported_modes: u32,
    failed: Option<StartupError>,
    /// When the reset communication went out: only a boot-up received after it answers it
    /// (one sent before, at the drive's power-on, may still be queued).
    reset_sent_us: u64,
    /// Boot-ups that started it again after the one that answered the reset.
    reboots: u8,
}

fn masked_equal(expected: SdoData, got: SdoData) -> bool {
    let n = expected.len();
    let mask = if n >= 4 {
        u32::MAX
    } else {
        (1u32 << (8 * n)) - 1
    };
    got.as_u32() & mask == expected.as_u32() && got.len() >= n
}

impl Startup {
    /// A start-up of `node` following `steps` (from [`super::StartupSettings::plan`]).
    pub fn new(node: NodeId, steps: Vec<Step>, sdo_timeout_us: u64, step_timeout_us: u64) -> Self {
        Self {
            node,
            steps,
            at: 0,
            phase: Phase::Issue,
            deadline_us: 0,
            step_timeout_us,
            sdo: SdoClient::new(node, sdo_timeout_us),
            power: PowerDriver::new(step_timeout_us),
            identity: Identity::default(),
            supported_modes: 0,
            failed: None,
            reset_sent_us: 0,
            reboots: 0,
        }
    }

    /// Where it is.
    pub fn status(&self) -> StartupStatus {
        if let Some(e) = self.failed {
            return StartupStatus::Failed(e);
        }
        match self.steps.get(self.at) {
            Some(s) => StartupStatus::Running(*s),
            None => StartupStatus::Done {
                identity: self.identity,
                supported_modes: self.supported_modes,
            },
        }
    }

    fn running(&self) -> Option<Step> {
        match self.status() {
            StartupStatus::Running(s) => Some(s),
            _ => None,
        }
    }

    fn fail(&mut self, step: Step, cause: StepFailure) {
        self.failed = Some(StartupError {
            node: self.node,
            step,
            cause,
        });
    }

    /// The drive booted during the start-up, after the boot-up that answered the reset: what
    /// was written is gone and any transfer in flight with it. Start again at the step after
    /// the boot-up (the drive is freshly booted, pre-operational), a few times at most.
    fn booted_again(&mut self, step: Step) {
        if self.reboots >= MAX_BOOT_UPS_DURING_STARTUP {
            self.fail(step, StepFailure::UnexpectedBootUp);
            return;
        }
        self.reboots += 1;
        let after_boot_up = self
            .steps
            .iter()
            .position(|s| *s == Step::AwaitBootUp)
            .map_or(0, |i| i + 1);
        self.at = after_boot_up;
        self.phase = Phase::Issue;
        self.sdo.cancel();
        self.power = PowerDriver::new(self.step_timeout_us);
        self.identity = Identity::default();
        self.supported_modes = 0;
    }

    fn next_step(&mut self) {
        self.at += 1;
        self.phase = Phase::Issue;
    }

    /// The next frame to send at `now`, if any (call until `None`); checks timeouts.
    pub fn poll(&mut self, now_us: u64) -> Option<CanFrame> {
        let step = self.running()?;
        if let Some((e, abort)) = self.sdo.poll(now_us) {
            self.fail(step, e.into());
            return Some(abort);
        }
        if self.phase == Phase::Await && step == Step::AwaitBootUp && now_us >= self.deadline_us {
            self.fail(step, StepFailure::NoBootUp(self.step_timeout_us));
            return None;
        }
        if self.phase != Phase::Issue {
            return None;
        }
        let node = self.node;
        let sent = match step {
            Step::ResetCommunication => {
                self.reset_sent_us = now_us;
                self.next_step();
                return Some(NmtCommand::ResetCommunication.frame(Some(node)));
            }
            Step::AwaitBootUp => {
                self.phase = Phase::Await;
                self.deadline_us = now_us.saturating_add(self.step_timeout_us);
                return None;
            }
            Step::StartNode => {
                self.next_step();
                return Some(NmtCommand::Start.frame(Some(node)));
            }
            Step::ReadIdentity(sub) => self.sdo.upload(ObjectAddr::new(0x1018, sub), now_us),
            Step::CheckMode(_) => self
                .sdo
                .upload(ObjectAddr::new(objects::SUPPORTED_MODES, 0), now_us),
            Step::Write(w) | Step::ZeroTarget(w) => self.sdo.download(w.addr, w.data, now_us),
            Step::ReadBack(w) => self.sdo.upload(w.addr, now_us),
            Step::Enable => {
                self.phase = Phase::ReadStatus;
                return self.read_status(now_us);
            }
        };
        self.phase = Phase::Await;
        match sent {
            Ok(f) => Some(f),
            Err(e) => {
                self.fail(step, e.into());
                None
            }
        }
    }

    fn read_status(&mut self, now_us: u64) -> Option<CanFrame> {
        match self
            .sdo
            .upload(ObjectAddr::new(objects::STATUSWORD, 0), now_us)
        {
            Ok(f) => Some(f),
            Err(e) => {
                self.fail(Step::Enable, e.into());
                None
            }
        }
    }

    /// Offers a received frame at `now`; may return a frame to send at once.
    pub fn on_frame(&mut self, f: &CanFrame, now_us: u64) -> Option<CanFrame> {
        let step = self.running()?;
        if let Ok(ec) = ErrorControl::decode(f) {
            if ec.node == self.node && ec.is_boot_up() {
                if step == Step::AwaitBootUp {
                    // A boot-up received no later than the reset was sent is an older one.
                    if now_us > self.reset_sent_us {
                        self.next_step();
                    }
                } else if self.at > 1 {
                    self.booted_again(step);
                }
            }
            return None;
        }
        let done = match self.sdo.on_frame(f)? {
            Ok(d) => d,
            Err(e) => {
                if let (Step::ReadIdentity(2..), SdoError::Aborted { .. }) = (step, e) {
                    // Optional identity entries the drive lacks.
                    self.next_step();
                } else {
                    self.fail(step, e.into());
                }
                return None;
            }
        };
        let data = match done {
            SdoDone::Uploaded(d) => Some(d),
            SdoDone::Downloaded => None,
        };
        self.on_transfer_done(step, data, now_us)
    }

    /// The step's SDO transfer finished (`data` for an upload): check it and move on; may
    /// return a frame to send at once (the enable walk's next request).
    fn on_transfer_done(
        &mut self,
        step: Step,
        data: Option<SdoData>,
        now_us: u64,
    ) -> Option<CanFrame> {
        match (step, data) {
            (Step::ReadIdentity(sub), Some(d)) => {
                let v = d.as_u32();
                match sub {
                    1 => self.identity.vendor = v,
                    2 => self.identity.product = Some(v),
                    3 => self.identity.revision = Some(v),
                    _ => self.identity.serial = Some(v),
                }
                self.next_step();
            }
            (Step::CheckMode(mode), Some(d)) => {
                self.supported_modes = d.as_u32();
                if self.supported_modes & mode.supported_bit() == 0 {
                    self.fail(
                        step,
                        StepFailure::ModeUnsupported {
                            mode: mode.value(),
                            supported: self.supported_modes,
                        },
                    );
                } else {
                    self.next_step();
                }
            }
            (Step::ReadBack(w), Some(got)) => {
                if masked_equal(w.data, got) {
                    self.next_step();
                } else {
                    self.fail(
                        step,
                        StepFailure::ReadBack {
                            expected: w.data,
                            got,
                        },
                    );
                }
            }
            (Step::Write(_) | Step::ZeroTarget(_), None) => self.next_step(),
            (Step::Enable, d) => return self.enable_reply(d, now_us),
            _ => self.fail(
                step,
                SdoError::Mismatch {
                    node: self.node,
                    addr: ObjectAddr::new(0, 0),
                }
                .into(),
            ),
        }
        None
    }

    fn enable_reply(&mut self, data: Option<SdoData>, now_us: u64) -> Option<CanFrame> {
        match (self.phase, data) {
            (Phase::ReadStatus, Some(d)) => {
                let sw = Statusword(d.as_u32() as u16);
                match self.power.step(sw, now_us) {
                    Ok(DriverStep::Reached) => {
                        self.next_step();
                        None
                    }
                    Ok(DriverStep::Wait) => self.read_status(now_us),
                    Ok(DriverStep::Send(Controlword(cw))) => {
                        self.phase = Phase::WriteControl;
                        let addr = ObjectAddr::new(objects::CONTROLWORD, 0);
                        match self.sdo.download(addr, SdoData::u16(cw), now_us) {
                            Ok(f) => Some(f),
                            Err(e) => {
                                self.fail(Step::Enable, e.into());
                                None
                            }
                        }
                    }
                    Err(e) => {
                        self.fail(Step::Enable, e.into());
                        None
                    }
                }
            }
            (Phase::WriteControl, None) => {
                self.phase = Phase::ReadStatus;
                self.read_status(now_us)
            }
            _ => {
                self.fail(
                    Step::Enable,
                    SdoError::Mismatch {
                        node: self.node,
                        addr: ObjectAddr::new(objects::STATUSWORD, 0),
                    }
                    .into(),
                );
                None
            }
        }
    }
}
