//! A finger moved by a simulated CiA 402 drive (`hand_canopen::sim::SimDrive`): the drive's
//! object dictionary, SDO server, PDOs, NMT, heartbeats, 0x1016 watchdog, EMCY and power state
//! machine, driving the same finger physics as the native controller ([`super::FingerNode`]).
//!
//! In Operation enabled the drive's target becomes the finger's command, through the finger's
//! scaling (the same `Scaling` handd uses, inverted):
//! - cyclic synchronous torque (10): the force is the target torque in N at the fingertip; the
//!   finger moves toward it at up to its maximum speed, force-limited, and pushes with it when
//!   blocked (the native controller's ACTIVE with that force and a saturated speed);
//! - cyclic synchronous or profile velocity (9, 3): the speed is the target in rad/s at the
//!   joint, with up to the finger's maximum force or the drive's max torque (0x6072) in N at the
//!   fingertip, whichever is less (handd sends its force setpoint there each tick: the native
//!   controller's force-limited velocity).
//!
//! In any other power state the finger is braked. The position actual value (0x6064) is the
//! joint angle in milliradians.

use hand_canopen::cia402::{objects, PowerState};
use hand_canopen::scaling::Scaling;
use hand_canopen::sim::SimDrive;
use hand_canopen::{NodeId, ObjectAddr};

use super::{std_id, Bus, NodeStats};
use crate::dbc::CanFrame;
use crate::error::SimError;
use crate::faults::{Fault, FaultPlan};
use crate::finger::{Command, FingerConfig, FingerMode, FingerPhysics, N_FINGERS};

/// The position actual value's unit: increments per radian of joint angle.
pub const INCREMENTS_PER_RAD: f64 = 1000.0;

/// One finger's simulated CiA 402 drive.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DriveFingerConfig {
    /// The drive's node id.
    pub node: NodeId,
    /// handd's units to the drive's, as handd's `[fingers.NAME.drive]` gives them.
    pub scaling: Scaling,
}

/// The node id of finger `f`'s simulated drive: 5 + f (the native controllers' node ids,
/// hand.dbc's 0-4, are left free; handd is 127).
pub const fn simulated_node_id(finger: usize) -> u8 {
    5 + finger as u8
}

impl DriveFingerConfig {
    /// The scaling of every simulated finger drive (`handsim --cia402`, `handctl demo
    /// --drives cia402`): a 25 mNm motor through a 64:1 gear on a 40 mm moment arm, so full
    /// torque is 40 N at the fingertip, and 8000 rpm at most.
    pub const SIM_SCALING: hand_canopen::scaling::ScalingSettings =
        hand_canopen::scaling::ScalingSettings {
            rated_torque_mnm: 25.0,
            gear_ratio: 64.0,
            moment_arm_m: 0.04,
            max_torque_permille: 1000,
            max_speed_rpm: 8000,
        };

    /// Finger `finger`'s simulated drive: node [`simulated_node_id`], [`Self::SIM_SCALING`].
    pub fn simulated(finger: usize) -> Result<Self, SimError> {
        if finger >= N_FINGERS {
            return Err(SimError::BadFinger(finger));
        }
        let node = NodeId::try_new(simulated_node_id(finger))
            .map_err(|e| SimError::BadScript(format!("drive of finger {finger}: {e}")))?;
        let scaling = Self::SIM_SCALING
            .validate()
            .map_err(|e| SimError::BadScript(format!("drive scaling: {e}")))?;
        Ok(Self { node, scaling })
    }
}

/// `magnitude` in the direction of `x` (0 for 0: `f64::signum` would give 1).
fn toward(x: f64, magnitude: f64) -> f64 {
    if x > 0.0 {
        magnitude
    } else if x < 0.0 {
        -magnitude
    } else {
        0.0
    }
}

/// A finger and its CiA 402 drive on the bus.
#[derive(Debug, Clone)]
pub struct DriveFingerNode {
    finger: usize,
    cfg: FingerConfig,
    scaling: Scaling,
    drive: SimDrive,
    phys: FingerPhysics,
    last_step_us: u64,
    out: Vec<hand_canopen::CanFrame>,
    stats: NodeStats,
    faults: FaultPlan,
    /// One-shot faults already applied (bit i = the plan's fault i).
    one_shots: u64,
}

impl DriveFingerNode {
    /// Finger `finger`'s drive, powered on at `start_us` (its boot-up message goes out at the
    /// first poll), the finger at full extension.
    pub fn try_new(
        finger: usize,
        cfg: FingerConfig,
        drive: DriveFingerConfig,
        start_us: u64,
    ) -> Result<Self, SimError> {
        if finger >= N_FINGERS {
            return Err(SimError::BadFinger(finger));
        }
        cfg.validate()?;
        let mut sim = SimDrive::new(drive.node);
        let mut out = Vec::new();
        sim.power_on(start_us, &mut out);
        Ok(Self {
            finger,
            cfg,
            scaling: drive.scaling,
            drive: sim,
            phys: FingerPhysics::at(cfg.angle_min_rad),
            last_step_us: start_us,
            out,
            stats: NodeStats::default(),
            faults: FaultPlan::new(),
            one_shots: 0,
        })
    }

    /// Which finger.
    pub fn finger(&self) -> usize {
        self.finger
    }

    /// The finger's mechanics.
    pub fn physics(&self) -> &FingerPhysics {
        &self.phys
    }

    /// The drive node (its power state, object dictionary, counters).
    pub fn drive(&self) -> &SimDrive {
        &self.drive
    }

    /// A drive fault now (EMCY `code`, then Fault), as a tripped drive does.
    pub fn inject_fault(&mut self, code: u16) {
        self.drive.inject_fault(code, &mut self.out);
    }

    /// Power-cycles the drive at `now_us`: its configuration is gone, it boots again.
    pub fn power_cycle(&mut self, now_us: u64) {
        self.drive.power_on(now_us, &mut self.out);
    }

    /// The faults of the run: `drive-trip:F` and `drive-power-cycle:F` of this finger act on
    /// the drive when they start.
    pub fn set_faults(&mut self, faults: FaultPlan) {
        self.faults = faults;
    }

    fn apply_faults(&mut self, now_us: u64) {
        let mine: Vec<(usize, Fault)> = self
            .faults
            .active(now_us)
            .filter(|&(i, f)| {
                self.one_shots & (1 << i) == 0
                    && matches!(f, Fault::DriveTrip { finger } | Fault::DrivePowerCycle { finger }
                        if finger == self.finger)
            })
            .collect();
        for (i, f) in mine {
            self.one_shots |= 1 << i;
            match f {
                Fault::DriveTrip { .. } => self.inject_fault(0x2310),
                _ => self.power_cycle(now_us),
            }
        }
    }

    /// Transmit and receive counts.
    pub fn stats(&self) -> NodeStats {
        self.stats
    }

    /// The command the drive's state and target give the finger.
    fn command(&self) -> Command {
        if self.drive.power_state() != PowerState::OperationEnabled {
            return Command {
                mode: FingerMode::SafeStop,
                ..Command::default()
            };
        }
        let od = self.drive.od();
        let (force_n, velocity_rad_s) = match od.get_i32(ObjectAddr::new(objects::MODES_DISPLAY, 0))
        {
            10 => {
                let permille = od.get(ObjectAddr::new(objects::TARGET_TORQUE, 0)) as u16 as i16;
                let f = self.scaling.force_n(permille);
                (f, toward(f, self.cfg.max_velocity_rad_s))
            }
            3 | 9 => {
                let rpm = od.get_i32(ObjectAddr::new(objects::TARGET_VELOCITY, 0));
                let v = self.scaling.rad_s(rpm);
                let limit = od.get(ObjectAddr::new(objects::MAX_TORQUE, 0)) as u16;
                let f = self.cfg.max_force_n.min(self.scaling.limit_force_n(limit));
                (toward(v, f), v)
            }
            _ => (0.0, 0.0),
        };
        Command {
            mode: FingerMode::Active,
            force_n,
            velocity_rad_s,
        }
    }

    /// Reads what arrived, runs the drive and the finger to `now_us`, sends what is due.
    pub fn poll<B: Bus>(&mut self, now_us: u64, bus: &mut B) {
        self.apply_faults(now_us);
        while let Some(frame) = self.stats.receive(bus) {
            let id = std_id(&frame);
            if let Some(f) = u16::try_from(id)
                .ok()
                .and_then(|id| hand_canopen::CanFrame::new(id, frame.data()))
            {
                self.drive.on_frame(&f, now_us, &mut self.out);
            }
        }
        let dt_us = self.cfg.control_period_us;
        while self.last_step_us + dt_us <= now_us {
            self.last_step_us += dt_us;
            let cmd = self.command();
            self.phys.step(&self.cfg, &cmd, false, dt_us as f64 * 1e-6);
            self.drive
                .set_position((self.phys.angle_rad * INCREMENTS_PER_RAD).round() as i32);
        }
        self.drive.poll(now_us, &mut self.out);
        for f in std::mem::take(&mut self.out) {
            if let Some(frame) = CanFrame::new_standard(f.cob_id(), f.payload()) {
                self.stats.transmit(bus, &frame);
            }
        }
    }
}
