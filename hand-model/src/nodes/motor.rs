//! A finger's motor controller on the bus: obeys FINGER_SETPOINT_f, reports FINGER_STATUS_f,
//! and brakes by itself when valid setpoints stop.
//!
//! Every setpoint goes through an E2E check (CRC with the message's data id, alive counter).
//! Only a frame classified OK refreshes the setpoint watchdog; a bad CRC, a repeated (stuck)
//! counter or a counter jump does not, and raises the E2E fault bit. When no valid setpoint
//! arrived for `setpoint_timeout_us` (150 ms), the brake engages: velocity and force go to
//! zero at once, the state becomes BRAKED and fault bit 3 is set, so a killed daemon leaves a
//! safe hand. A valid HAND_ESTOP STOP also brakes (reported BRAKED, without bit 3) and, on
//! its first frame, retires the epoch and replaces the command with SAFE_STOP, as braking by
//! itself does: a RELEASE only lifts the brake, and the finger stays stopped (SAFE_STOP) until
//! a SAFE_STOP of a new epoch and an ACTIVE after it arrive. The repetitions of a STOP (every
//! 10 ms) retire nothing more, so the new epoch handd opens while the stop lasts stays bound.
//!
//! A setpoint that passed E2E is then judged by its epoch ([`super::epoch`]): the controller
//! follows it only in the epoch it is bound to, which a SAFE_STOP opens; one it ignores sets
//! fault bit 6 and feeds no watchdog. So after braking by itself or an E-stop (which retire its epoch)
//! the controller moves again only after a SAFE_STOP of a new epoch (the first frame after a
//! gap moves the E2E reference; the two in-sequence frames after it are not used, as AUTOSAR E2E
//! Profile 1's sync counter has it, except that a SAFE_STOP among them stops the finger; the
//! next SAFE_STOP then opens the epoch).

use hand_dbc::e2e::E2eStatus;
use hand_dbc::e2e::{E2eCheckConfig, E2eChecker};
use hand_dbc::messages::{self, EstopRequest, FingerSetpoint, FingerStatus, HandEstop};

use super::epoch::{EpochGate, Verdict};
use super::{std_id, Bus, NodeStats};
use crate::dbc::seal;
use crate::error::SimError;
use crate::faults::{CrcTarget, Fault, FaultPlan};
use crate::finger::{
    Command, FingerConfig, FingerMode, FingerPhysics, FingerState, MotionStats, N_FINGERS,
};

/// FINGER_STATUS fault bit 3: setpoint timeout, braked.
pub const FAULT_SETPOINT_TIMEOUT: u8 = 1 << 3;
/// FINGER_STATUS fault bit 4: E2E error on setpoints since the previous status.
pub const FAULT_SETPOINT_E2E: u8 = 1 << 4;
/// FINGER_STATUS fault bit 5: at a joint limit.
pub const FAULT_JOINT_LIMIT: u8 = 1 << 5;
/// FINGER_STATUS fault bit 6: a valid setpoint of a stale or unopened epoch was ignored since
/// the previous status.
pub const FAULT_STALE_EPOCH: u8 = 1 << 6;

/// Counter steps accepted between two setpoints: one lost frame is tolerated.
const SETPOINT_MAX_DELTA: u16 = 2;

/// One finger and its motor controller.
#[derive(Debug, Clone)]
pub struct FingerNode {
    finger: usize,
    cfg: FingerConfig,
    phys: FingerPhysics,
    cmd: Command,
    checker: E2eChecker,
    gate: EpochGate,
    stale_since_status: bool,
    last_valid_us: Option<u64>,
    ever_valid: bool,
    timed_out: bool,
    estop: bool,
    e2e_errors_since_status: bool,
    e2e_errors: u64,
    last_step_us: u64,
    next_status_us: u64,
    status_counter: u8,
    status_frames: u64,
    faults: FaultPlan,
    stats: NodeStats,
}

impl FingerNode {
    /// The controller of finger `finger` (0 thumb ..= 4 pinky), starting at full extension
    /// (`angle_min_rad`), disabled and braked until the first valid setpoint.
    pub fn try_new(finger: usize, cfg: FingerConfig, start_us: u64) -> Result<Self, SimError> {
        if finger >= N_FINGERS {
            return Err(SimError::BadFinger(finger));
        }
        cfg.validate()?;
        let checker = E2eChecker::with_config(
            FingerSetpoint::E2E[finger],
            E2eCheckConfig::profile1(SETPOINT_MAX_DELTA),
        )
        .map_err(|e| SimError::BadScript(format!("setpoint E2E profile: {e}")))?;
        Ok(Self {
            finger,
            phys: FingerPhysics::at(cfg.angle_min_rad),
            cfg,
            cmd: Command::default(),
            checker,
            gate: EpochGate::new(),
            stale_since_status: false,
            last_valid_us: None,
            ever_valid: false,
            timed_out: false,
            estop: false,
            e2e_errors_since_status: false,
            e2e_errors: 0,
            last_step_us: start_us,
            next_status_us: start_us,
            status_counter: 0,
            status_frames: 0,
            faults: FaultPlan::new(),
            stats: NodeStats::default(),
        })
    }

    /// Replaces the fault plan.
    pub fn set_faults(&mut self, faults: FaultPlan) {
        self.faults = faults;
    }

    /// The finger index.
    pub fn finger(&self) -> usize {
        self.finger
    }

    /// The mechanical state.
    pub fn physics(&self) -> &FingerPhysics {
        &self.phys
    }

    /// The state that FINGER_STATUS reports now.
    pub fn state(&self) -> FingerState {
        if self.estop || self.timed_out {
            FingerState::Braked
        } else if !self.ever_valid {
            FingerState::Disabled
        } else {
            match self.cmd.mode {
                FingerMode::Disabled => FingerState::Disabled,
                FingerMode::Active => FingerState::Active,
                FingerMode::Hold => FingerState::Hold,
                FingerMode::SafeStop => FingerState::SafeStop,
            }
        }
    }

    /// True while the brake is engaged by the controller itself (timeout or E-stop).
    pub fn braked(&self) -> bool {
        self.estop || self.timed_out || !self.ever_valid
    }

    /// Impacts on the joint stops and commands beyond the motor's limits so far.
    pub fn motion_stats(&self) -> MotionStats {
        self.phys.stats
    }

    /// Setpoints rejected by the E2E check so far.
    pub fn e2e_errors(&self) -> u64 {
        self.e2e_errors
    }

    /// Transmit and receive counts.
    pub fn stats(&self) -> NodeStats {
        self.stats
    }

    /// The epoch rule's state: the bound and retired epochs, the setpoints it ignored.
    pub fn epoch_gate(&self) -> &EpochGate {
        &self.gate
    }

    /// Reads setpoints and E-stops, runs the control loop up to `now_us`, sends status.
    pub fn poll<B: Bus>(&mut self, now_us: u64, bus: &mut B) {
        let deaf = self
            .faults
            .active(now_us)
            .any(|(_, f)| matches!(f, Fault::SetpointLoss { finger } if finger == self.finger));
        while let Some(frame) = self.stats.receive(bus) {
            if deaf && std_id(&frame) == FingerSetpoint::IDS[self.finger] {
                continue;
            }
            self.on_frame(now_us, &frame);
        }
        let dt_us = self.cfg.control_period_us;
        while self.last_step_us + dt_us <= now_us {
            self.last_step_us += dt_us;
            let t = self.last_step_us;
            let was_timed_out = self.timed_out;
            self.timed_out = self
                .last_valid_us
                .is_some_and(|l| t.saturating_sub(l) >= self.cfg.setpoint_timeout_us);
            if self.timed_out && !was_timed_out {
                self.gate.braked_by_itself();
            }
            let braked = self.braked();
            self.phys
                .step(&self.cfg, &self.cmd, braked, dt_us as f64 * 1e-6);
        }
        while self.next_status_us <= now_us {
            let t = self.next_status_us;
            self.send_status(t, bus);
            self.next_status_us += self.cfg.status_period_us;
        }
    }

    /// A FINGER_SETPOINT of this finger: E2E, then the epoch gate, then the command.
    fn on_setpoint(&mut self, now_us: u64, id: u32, frame: &hand_dbc::CanFrame) {
        let status = self.checker.check_frame(Some(frame));
        let decoded = messages::FingerSetpoint::decode(id, frame.data());
        match (status, decoded) {
            (E2eStatus::Ok, Ok(sp))
                if self.gate.admit(sp.mode(), sp.epoch()) == Verdict::Ignore =>
            {
                self.stale_since_status = true;
            }
            (E2eStatus::Ok, Ok(sp)) => {
                self.cmd = Command {
                    mode: match sp.mode() {
                        messages::FingerMode::Disabled => FingerMode::Disabled,
                        messages::FingerMode::Active => FingerMode::Active,
                        messages::FingerMode::Hold => FingerMode::Hold,
                        messages::FingerMode::SafeStop => FingerMode::SafeStop,
                    },
                    force_n: sp.force(),
                    velocity_rad_s: sp.velocity(),
                };
                self.last_valid_us = Some(now_us);
                self.ever_valid = true;
                self.timed_out = false;
            }
            // A correct frame of a stream that is resynchronising (Profile 1's sync
            // counter: after a counter jump, the next two in-sequence frames are not used).
            // A jump is a restarted sender, lost frames or a second sender interleaving
            // with the first; until two consecutive frames prove one sender again, nothing
            // moves the finger, feeds the watchdog or opens an epoch. A SAFE_STOP still
            // stops it: stopping is always safe, whoever asks.
            (E2eStatus::Sync | E2eStatus::WrongSequence, Ok(sp))
                if sp.mode() == messages::FingerMode::SafeStop =>
            {
                self.stop_command();
                if status == E2eStatus::WrongSequence {
                    self.e2e_errors += 1;
                    self.e2e_errors_since_status = true;
                }
            }
            // In sequence, not yet trusted: not an error.
            (E2eStatus::Sync, Ok(_)) => {}
            _ => {
                self.e2e_errors += 1;
                self.e2e_errors_since_status = true;
            }
        }
    }

    fn on_frame(&mut self, now_us: u64, frame: &hand_dbc::CanFrame) {
        let id = std_id(frame);
        if id == FingerSetpoint::IDS[self.finger] {
            self.on_setpoint(now_us, id, frame);
        } else if id == HandEstop::ID {
            // Several senders interleave counters on HAND_ESTOP (hand.dbc): only the CRC
            // decides whether to believe it.
            let data = frame.data();
            let crc_ok = data.len() == HandEstop::DLC && data[0] == HandEstop::E2E.crc(data);
            if let (true, Ok(e)) = (crc_ok, HandEstop::decode(data)) {
                let stop = e.request() == EstopRequest::Stop;
                if stop && !self.estop {
                    // As when it brakes by itself: the epoch is retired and the command
                    // forgotten, so a RELEASE resumes nothing.
                    self.gate.braked_by_itself();
                    self.stop_command();
                }
                self.estop = stop;
            }
        }
    }

    /// The command becomes a safe stop: zero force and velocity.
    fn stop_command(&mut self) {
        self.cmd = Command {
            mode: FingerMode::SafeStop,
            force_n: 0.0,
            velocity_rad_s: 0.0,
        };
    }

    /// FINGER_STATUS's fault bits now; the ones about setpoints since the previous status
    /// are cleared.
    fn take_status_faults(&mut self) -> u8 {
        let bits = [
            (self.timed_out, FAULT_SETPOINT_TIMEOUT),
            (self.e2e_errors_since_status, FAULT_SETPOINT_E2E),
            (self.phys.at_limit, FAULT_JOINT_LIMIT),
            (self.stale_since_status, FAULT_STALE_EPOCH),
        ];
        self.e2e_errors_since_status = false;
        self.stale_since_status = false;
        bits.iter()
            .filter(|(on, _)| *on)
            .fold(0, |acc, (_, b)| acc | b)
    }

    fn send_status<B: Bus>(&mut self, t: u64, bus: &mut B) {
        self.status_frames += 1;
        let mut silent = false;
        let mut bad_crc = false;
        for (_, f) in self.faults.active(t) {
            match f {
                Fault::MotorSilent { finger } if finger == self.finger => silent = true,
                Fault::BadCrc {
                    target: CrcTarget::FingerStatus(finger),
                    every,
                } if finger == self.finger => {
                    bad_crc |= self.status_frames.is_multiple_of(u64::from(every))
                }
                _ => {}
            }
        }
        let faults = self.take_status_faults();
        let counter = self.status_counter;
        self.status_counter = (counter + 1) & 0x0F;
        if silent {
            return;
        }
        let state = match self.state() {
            FingerState::Disabled => messages::FingerState::Disabled,
            FingerState::Active => messages::FingerState::Active,
            FingerState::Hold => messages::FingerState::Hold,
            FingerState::SafeStop => messages::FingerState::SafeStop,
            FingerState::Braked => messages::FingerState::Braked,
            FingerState::Fault => messages::FingerState::Fault,
        };
        // Status resolution: position 1 mrad, velocity 0.01 rad/s, force 0.025 N; the config
        // limits are inside the DBC ranges (checked in FingerConfig::validate), so this encodes.
        let msg = FingerStatus::new(
            self.finger,
            state,
            self.phys.angle_rad,
            self.phys.velocity_rad_s,
            self.phys.force_n,
            faults,
        );
        let Ok(msg) = msg else {
            self.stats.tx_errors += 1;
            return;
        };
        let mut frame = msg.to_frame();
        seal(&mut frame, FingerStatus::E2E[self.finger], counter, bad_crc);
        self.stats.transmit(bus, &frame);
    }
}
