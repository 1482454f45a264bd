//! One finger's mechanics and its motor controller's control law, free of any bus detail.
//!
//! The daemon computes the paper's setpoints (`F = kF·label`, `omega = omega0 + alpha·t`); the
//! motor controller here simply follows the commanded force and joint velocity within its own
//! limits: velocity changes at most `max_accel` per second, force at most `force_slew` per
//! second, both are clamped to their maxima, and the joint angle stays inside its range (at
//! a stop the velocity is zeroed and the joint-limit flag raised). A brake, engaged in
//! safe-stop and when the controller brakes by itself, zeroes velocity and force at once.

use crate::error::{check_range, SimError};

/// Number of fingers: 0 thumb, 1 index, 2 middle, 3 ring, 4 pinky (from hand.dbc).
pub use hand_dbc::hand::N_FINGERS;

/// Commanded mode (hand.dbc FINGER_SETPOINT Mode).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum FingerMode {
    /// Motor off: the finger coasts to rest, no force.
    #[default]
    Disabled,
    /// Follow force and velocity.
    Active,
    /// Keep position, keep the commanded force.
    Hold,
    /// Zero force, zero velocity, brake.
    SafeStop,
}

/// Reported state (hand.dbc FINGER_STATUS State).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum FingerState {
    /// Motor off.
    #[default]
    Disabled,
    /// Following setpoints.
    Active,
    /// Holding position.
    Hold,
    /// Commanded safe stop, brake engaged.
    SafeStop,
    /// Braked by the controller itself (setpoint timeout, E2E errors or an E-stop).
    Braked,
    /// Internal fault.
    Fault,
}

/// A setpoint as the controller uses it.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Command {
    /// Mode.
    pub mode: FingerMode,
    /// Force, N, flexion positive.
    pub force_n: f64,
    /// Joint velocity, rad/s, flexion positive.
    pub velocity_rad_s: f64,
}

/// Limits and timing of one finger and its controller.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FingerConfig {
    /// Joint angle at full extension, rad.
    pub angle_min_rad: f64,
    /// Joint angle at full flexion, rad.
    pub angle_max_rad: f64,
    /// Largest joint speed, rad/s.
    pub max_velocity_rad_s: f64,
    /// Largest joint acceleration, rad/s².
    pub max_accel_rad_s2: f64,
    /// Largest force, N.
    pub max_force_n: f64,
    /// Largest force change, N/s.
    pub force_slew_n_per_s: f64,
    /// The controller brakes by itself when no valid setpoint arrived for this long, µs.
    pub setpoint_timeout_us: u64,
    /// Period of FINGER_STATUS, µs (hand.dbc: 20 ms).
    pub status_period_us: u64,
    /// Period of the control loop, µs.
    pub control_period_us: u64,
}

impl Default for FingerConfig {
    fn default() -> Self {
        Self {
            angle_min_rad: 0.0,
            angle_max_rad: 1.6,
            max_velocity_rad_s: 6.0,
            max_accel_rad_s2: 120.0,
            max_force_n: 20.0,
            force_slew_n_per_s: 400.0,
            setpoint_timeout_us: 150_000,
            status_period_us: 20_000,
            control_period_us: 1_000,
        }
    }
}

impl FingerConfig {
    /// Checks the limits against each other and against hand.dbc's FINGER_STATUS ranges
    /// (position -0.5..2 rad, velocity ±20 rad/s, force ±50 N), so status always encodes.
    pub fn validate(&self) -> Result<(), SimError> {
        check_range(
            "angle_min_rad",
            self.angle_min_rad,
            -0.5,
            1.9,
            "-0.5..=1.9 rad",
        )?;
        check_range(
            "angle_max_rad",
            self.angle_max_rad,
            self.angle_min_rad + 0.1,
            2.0,
            "angle_min_rad+0.1..=2 rad",
        )?;
        check_range(
            "max_velocity_rad_s",
            self.max_velocity_rad_s,
            0.1,
            20.0,
            "0.1..=20 rad/s",
        )?;
        check_range(
            "max_accel_rad_s2",
            self.max_accel_rad_s2,
            1.0,
            1e4,
            "1..=1e4 rad/s²",
        )?;
        check_range("max_force_n", self.max_force_n, 0.1, 50.0, "0.1..=50 N")?;
        check_range(
            "force_slew_n_per_s",
            self.force_slew_n_per_s,
            1.0,
            1e5,
            "1..=1e5 N/s",
        )?;
        let us = |name, v: u64, lo: u64, hi: u64, allowed| {
            check_range(name, v as f64, lo as f64, hi as f64, allowed)
        };
        us(
            "setpoint_timeout_us",
            self.setpoint_timeout_us,
            10_000,
            1_000_000,
            "10 ms..=1 s",
        )?;
        us(
            "status_period_us",
            self.status_period_us,
            1_000,
            1_000_000,
            "1 ms..=1 s",
        )?;
        us(
            "control_period_us",
            self.control_period_us,
            100,
            10_000,
            "0.1..=10 ms",
        )
    }
}

/// The mechanical state of one finger.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct FingerPhysics {
    /// Joint angle, rad.
    pub angle_rad: f64,
    /// Joint velocity, rad/s.
    pub velocity_rad_s: f64,
    /// Motor force, N.
    pub force_n: f64,
    /// True while the joint sits at a stop and the command pushes into it.
    pub at_limit: bool,
}

fn approach(x: f64, target: f64, max_step: f64) -> f64 {
    x + (target - x).clamp(-max_step, max_step)
}

impl FingerPhysics {
    /// A finger at rest at `angle_rad`.
    pub fn at(angle_rad: f64) -> Self {
        Self {
            angle_rad,
            ..Self::default()
        }
    }

    /// Engages the brake: velocity and force to zero now.
    pub fn brake(&mut self) {
        self.velocity_rad_s = 0.0;
        self.force_n = 0.0;
    }

    /// Advances by `dt_s` under `cmd` (braked if `braked`).
    pub fn step(&mut self, cfg: &FingerConfig, cmd: &Command, braked: bool, dt_s: f64) {
        if braked || cmd.mode == FingerMode::SafeStop {
            self.brake();
            self.at_limit = false;
            return;
        }
        let (v_target, f_target) = match cmd.mode {
            FingerMode::Active => (cmd.velocity_rad_s, cmd.force_n),
            FingerMode::Hold => (0.0, cmd.force_n),
            FingerMode::Disabled | FingerMode::SafeStop => (0.0, 0.0),
        };
        let v_target = v_target.clamp(-cfg.max_velocity_rad_s, cfg.max_velocity_rad_s);
        let f_target = f_target.clamp(-cfg.max_force_n, cfg.max_force_n);
        self.velocity_rad_s = approach(self.velocity_rad_s, v_target, cfg.max_accel_rad_s2 * dt_s);
        self.force_n = approach(self.force_n, f_target, cfg.force_slew_n_per_s * dt_s);
        let angle = self.angle_rad + self.velocity_rad_s * dt_s;
        self.at_limit = false;
        if angle <= cfg.angle_min_rad {
            self.angle_rad = cfg.angle_min_rad;
            self.at_limit = self.velocity_rad_s < 0.0;
            self.velocity_rad_s = self.velocity_rad_s.max(0.0);
        } else if angle >= cfg.angle_max_rad {
            self.angle_rad = cfg.angle_max_rad;
            self.at_limit = self.velocity_rad_s > 0.0;
            self.velocity_rad_s = self.velocity_rad_s.min(0.0);
        } else {
            self.angle_rad = angle;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn follows_within_limits_and_stops_at_the_joint_range() {
        let cfg = FingerConfig::default();
        assert!(cfg.validate().is_ok());
        let mut p = FingerPhysics::at(0.2);
        let cmd = Command {
            mode: FingerMode::Active,
            force_n: 100.0,
            velocity_rad_s: 100.0,
        };
        p.step(&cfg, &cmd, false, 0.001);
        assert!(
            (p.velocity_rad_s - 0.12).abs() < 1e-12,
            "acceleration limited"
        );
        assert!((p.force_n - 0.4).abs() < 1e-12, "force slew limited");
        for _ in 0..2000 {
            p.step(&cfg, &cmd, false, 0.001);
            assert!(p.angle_rad <= cfg.angle_max_rad && p.velocity_rad_s <= cfg.max_velocity_rad_s);
        }
        assert_eq!(p.angle_rad, cfg.angle_max_rad);
        assert!(p.at_limit);
        assert_eq!(p.force_n, cfg.max_force_n);
        p.step(&cfg, &cmd, true, 0.001);
        assert_eq!((p.velocity_rad_s, p.force_n), (0.0, 0.0));
    }

    #[test]
    fn rejects_limits_outside_the_dbc() {
        let bad = FingerConfig {
            max_force_n: 80.0,
            ..FingerConfig::default()
        };
        assert!(bad.validate().is_err());
    }
}
