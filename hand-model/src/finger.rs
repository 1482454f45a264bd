//! One finger's mechanics and its motor controller's control law, free of any bus detail.
//!
//! The controller follows hand.dbc's one definition of force and velocity (can-dbc/README.md,
//! section "Force, velocity and modes"), with nothing kinder than a motor:
//!
//! - **ACTIVE**: `velocity` is the commanded joint speed and `|force|` the most the finger may
//!   push with. It moves only when both are non-zero and of the same sign: a velocity servo
//!   whose drive is limited by the motor's force setting (at the full `max_force_n` it
//!   accelerates the joint by at most `max_accel_rad_s2`, proportionally less with less force).
//!   When their signs differ or either is zero it holds the finger still, as HOLD.
//! - **HOLD**: keep the position (the holding drive is the motor's full acceleration limit).
//! - **DISABLED**: motor off, no brake: the finger is free and coasts, slowed only by its
//!   passive joint friction (`passive_friction_per_s`, see [`FingerConfig`]) and by the stops.
//! - **SAFE_STOP**, and the controller's own brake (setpoint timeout, E-stop): velocity and
//!   force to zero at once, the joint held where it is.
//!
//! The motor's force setting (what FINGER_STATUS reports as Force, and what the finger pushes
//! with when blocked) follows the commanded force at most `force_slew_n_per_s`; the model has no
//! objects, so only a joint stop blocks the finger. A joint stop is a stiff one-sided
//! spring-damper (`stop_stiffness_per_s2`, `stop_damping_per_s`): driving into it is visible,
//! as a small overtravel beyond the stop and as an impact counted in [`MotionStats`], and a
//! finger pushed against it settles where the spring balances the force limit. Fault bit 5
//! (joint limit) is raised while the joint is at a stop and the command pushes into it.
//!
//! A command beyond the motor's limits (`max_force_n`, `max_velocity_rad_s`) is saturated, as
//! a real motor saturates, and reported: [`MotionStats`] counts the control ticks with such a
//! command and keeps the largest value requested.
//!
//! The mechanics are integrated semi-implicitly (velocity, then angle) in sub-steps of at most
//! [`MAX_SUBSTEP_S`], so the stop's spring stays stable at every allowed control period.

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
    /// Passive viscous friction of the joint with the motor off, as a decay rate of the joint
    /// speed, 1/s: a free finger coasts as `ω(t) = ω0·e^(−c·t)`. The default, 4/s (time
    /// constant 0.25 s: a finger let go at 2 rad/s travels 0.5 rad), is assumed, not measured,
    /// for a back-drivable geared finger drive; measure it on a real finger by commanding
    /// DISABLED at a known speed and fitting that exponential to FINGER_STATUS velocity.
    pub passive_friction_per_s: f64,
    /// Stiffness of a joint stop, as joint acceleration per radian of overtravel, 1/s².
    /// The default, 25,000/s², is a stop of about 25 Hz: the full force limit presses the
    /// finger `max_accel_rad_s2 / stop_stiffness_per_s2` (4.8 mrad) beyond it.
    pub stop_stiffness_per_s2: f64,
    /// Damping of a joint stop while the joint is beyond it, 1/s (default 150/s: a damping
    /// ratio of about 0.47 with the default stiffness, a small rebound).
    pub stop_damping_per_s: f64,
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
            passive_friction_per_s: 4.0,
            stop_stiffness_per_s2: 25_000.0,
            stop_damping_per_s: 150.0,
        }
    }
}

impl FingerConfig {
    /// How far a joint can travel beyond a stop, rad: the kinetic energy of the fastest finger
    /// (`max_velocity / √stiffness`) plus twice the static press of the full force limit (the
    /// overshoot of a force step), a bound whatever the damping.
    pub fn max_overtravel_rad(&self) -> f64 {
        self.max_velocity_rad_s / self.stop_stiffness_per_s2.sqrt()
            + 2.0 * self.max_accel_rad_s2 / self.stop_stiffness_per_s2
    }

    /// Checks the limits against each other and against hand.dbc's FINGER_STATUS ranges
    /// (position -0.5..2 rad, velocity ±20 rad/s, force ±50 N), so status always encodes: the
    /// joint range widened by the stops' overtravel ([`Self::max_overtravel_rad`]) must fit in
    /// -0.5..=2 rad.
    pub fn validate(&self) -> Result<(), SimError> {
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
        check_range(
            "passive_friction_per_s",
            self.passive_friction_per_s,
            0.0,
            1e3,
            "0..=1000 /s",
        )?;
        // Bounds that keep the semi-implicit sub-steps stable: ω_n·h <= 0.25, d·h <= 0.5.
        check_range(
            "stop_stiffness_per_s2",
            self.stop_stiffness_per_s2,
            1e3,
            1e6,
            "1e3..=1e6 /s²",
        )?;
        check_range(
            "stop_damping_per_s",
            self.stop_damping_per_s,
            0.0,
            2e3,
            "0..=2000 /s",
        )?;
        let over = self.max_overtravel_rad();
        check_range(
            "angle_min_rad",
            self.angle_min_rad,
            -0.5 + over,
            1.9,
            "-0.5 + max_overtravel_rad..=1.9 rad",
        )?;
        check_range(
            "angle_max_rad",
            self.angle_max_rad,
            self.angle_min_rad + 0.1,
            2.0 - over,
            "angle_min_rad+0.1..=2 rad - max_overtravel_rad",
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

/// Longest sub-step of the mechanics, s.
pub const MAX_SUBSTEP_S: f64 = 2.5e-4;

/// An entry into a joint stop faster than this counts as an impact, rad/s.
pub const IMPACT_MIN_SPEED_RAD_S: f64 = 0.05;

/// What the finger went through so far, for tests and for handsim's summary: impacts on the
/// joint stops and commands beyond the motor's limits.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct MotionStats {
    /// Entries into a joint stop at more than [`IMPACT_MIN_SPEED_RAD_S`].
    pub impacts: u64,
    /// The fastest entry into a joint stop, rad/s (0 if none).
    pub max_impact_speed_rad_s: f64,
    /// The farthest the joint went beyond a stop, rad.
    pub max_overtravel_rad: f64,
    /// Control ticks whose followed command (ACTIVE or HOLD) asked more than `max_force_n`.
    pub over_force_ticks: u64,
    /// The largest |force| a followed command asked, N.
    pub max_force_requested_n: f64,
    /// Control ticks whose ACTIVE command asked more than `max_velocity_rad_s`.
    pub over_speed_ticks: u64,
    /// The largest |velocity| an ACTIVE command asked, rad/s.
    pub max_speed_requested_rad_s: f64,
}

/// The mechanical state of one finger.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct FingerPhysics {
    /// Joint angle, rad (beyond a stop by the stop's small overtravel while pressed into it).
    pub angle_rad: f64,
    /// Joint velocity, rad/s.
    pub velocity_rad_s: f64,
    /// The motor's force setting, N: what the finger pushes with when blocked.
    pub force_n: f64,
    /// True while the joint sits at a stop and the command pushes into it (fault bit 5).
    pub at_limit: bool,
    /// Impacts and over-limit commands so far.
    pub stats: MotionStats,
}

fn approach(x: f64, target: f64, max_step: f64) -> f64 {
    x + (target - x).clamp(-max_step, max_step)
}

/// What the motor does during one control tick.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Drive {
    /// Motor off: the joint is free.
    Free,
    /// Hold the joint still with the full holding drive.
    Hold,
    /// Drive the joint at this velocity (already saturated), force-limited.
    Move(f64),
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

    /// The joint acceleration the stops give at `angle` and `velocity`, rad/s² (0 between
    /// them; a stop pushes, never pulls).
    fn stop_accel(cfg: &FingerConfig, angle: f64, velocity: f64) -> f64 {
        let (k, d) = (cfg.stop_stiffness_per_s2, cfg.stop_damping_per_s);
        if angle > cfg.angle_max_rad {
            (-k * (angle - cfg.angle_max_rad) - d * velocity).min(0.0)
        } else if angle < cfg.angle_min_rad {
            (k * (cfg.angle_min_rad - angle) - d * velocity).max(0.0)
        } else {
            0.0
        }
    }

    /// How far `angle` is beyond a stop, rad (0 between them).
    fn overtravel(cfg: &FingerConfig, angle: f64) -> f64 {
        (angle - cfg.angle_max_rad)
            .max(cfg.angle_min_rad - angle)
            .max(0.0)
    }

    /// Advances by `dt_s` under `cmd` (braked if `braked`).
    pub fn step(&mut self, cfg: &FingerConfig, cmd: &Command, braked: bool, dt_s: f64) {
        if braked || cmd.mode == FingerMode::SafeStop {
            self.brake();
            self.at_limit = false;
            return;
        }
        let (drive, f_target) = match cmd.mode {
            FingerMode::Active => {
                let moves = cmd.force_n * cmd.velocity_rad_s > 0.0;
                let v = cmd.velocity_rad_s;
                self.note_request(cfg, cmd.force_n, Some(v));
                let drive = if moves {
                    Drive::Move(v.clamp(-cfg.max_velocity_rad_s, cfg.max_velocity_rad_s))
                } else {
                    Drive::Hold
                };
                (drive, cmd.force_n)
            }
            FingerMode::Hold => {
                self.note_request(cfg, cmd.force_n, None);
                (Drive::Hold, cmd.force_n)
            }
            FingerMode::Disabled | FingerMode::SafeStop => (Drive::Free, 0.0),
        };
        let f_target = f_target.clamp(-cfg.max_force_n, cfg.max_force_n);
        self.force_n = if drive == Drive::Free {
            0.0
        } else {
            approach(self.force_n, f_target, cfg.force_slew_n_per_s * dt_s)
        };
        let (v_target, authority) = match drive {
            Drive::Free => (0.0, 0.0),
            Drive::Hold => (0.0, cfg.max_accel_rad_s2),
            Drive::Move(v) => (
                v,
                cfg.max_accel_rad_s2 * self.force_n.abs() / cfg.max_force_n,
            ),
        };
        // The fewest sub-steps of at most MAX_SUBSTEP_S (the margin keeps 1 ms at 4, not 5).
        let n = (dt_s / MAX_SUBSTEP_S - 1e-9).ceil().max(1.0);
        let h = dt_s / n;
        for _ in 0..n as u32 {
            let (angle, velocity) = (self.angle_rad, self.velocity_rad_s);
            let passive =
                -cfg.passive_friction_per_s * velocity + Self::stop_accel(cfg, angle, velocity);
            let motor = ((v_target - velocity) / h - passive).clamp(-authority, authority);
            self.velocity_rad_s = velocity + (motor + passive) * h;
            self.angle_rad = angle + self.velocity_rad_s * h;
            let before = Self::overtravel(cfg, angle);
            let after = Self::overtravel(cfg, self.angle_rad);
            let speed = self.velocity_rad_s.abs();
            if before == 0.0 && after > 0.0 && speed > IMPACT_MIN_SPEED_RAD_S {
                self.stats.impacts += 1;
                self.stats.max_impact_speed_rad_s = self.stats.max_impact_speed_rad_s.max(speed);
            }
            self.stats.max_overtravel_rad = self.stats.max_overtravel_rad.max(after);
        }
        self.at_limit = match drive {
            Drive::Move(v) => {
                (v > 0.0 && self.angle_rad >= cfg.angle_max_rad)
                    || (v < 0.0 && self.angle_rad <= cfg.angle_min_rad)
            }
            Drive::Free | Drive::Hold => false,
        };
    }

    /// Counts a followed command beyond the motor's limits (`velocity` for ACTIVE only).
    fn note_request(&mut self, cfg: &FingerConfig, force_n: f64, velocity: Option<f64>) {
        let s = &mut self.stats;
        let f = force_n.abs();
        s.max_force_requested_n = s.max_force_requested_n.max(f);
        if f > cfg.max_force_n {
            s.over_force_ticks += 1;
        }
        if let Some(v) = velocity.map(f64::abs) {
            s.max_speed_requested_rad_s = s.max_speed_requested_rad_s.max(v);
            if v > cfg.max_velocity_rad_s {
                s.over_speed_ticks += 1;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const DT: f64 = 0.001;

    fn active(force_n: f64, velocity_rad_s: f64) -> Command {
        Command {
            mode: FingerMode::Active,
            force_n,
            velocity_rad_s,
        }
    }

    /// Runs `cmd` for `ms` control ticks of 1 ms.
    fn run(p: &mut FingerPhysics, cfg: &FingerConfig, cmd: Command, ms: u32) {
        for _ in 0..ms {
            p.step(cfg, &cmd, false, DT);
        }
    }

    #[test]
    fn moves_only_when_force_and_velocity_agree_in_sign() {
        let cfg = FingerConfig::default();
        assert!(cfg.validate().is_ok());
        for (force, velocity) in [(5.0, -1.0), (-5.0, 1.0), (0.0, 1.0), (5.0, 0.0)] {
            let mut p = FingerPhysics::at(0.8);
            run(&mut p, &cfg, active(force, velocity), 200);
            assert_eq!(
                (p.angle_rad, p.velocity_rad_s),
                (0.8, 0.0),
                "force {force} velocity {velocity}: held still"
            );
            assert!(!p.at_limit);
        }
        for (force, velocity) in [(5.0, 1.0), (-5.0, -1.0)] {
            let mut p = FingerPhysics::at(0.8);
            run(&mut p, &cfg, active(force, velocity), 200);
            assert!(
                (p.velocity_rad_s - velocity).abs() < 1e-9,
                "moves at the commanded velocity: {}",
                p.velocity_rad_s
            );
            assert!((p.force_n - force).abs() < 1e-9);
            // Force builds at 400 N/s, and the drive with it (at most 6 rad/s² per N): the
            // finger reaches 1 rad/s within about 30 ms, then travels at it.
            let travelled = (p.angle_rad - 0.8) * velocity.signum();
            assert!((0.17..0.2).contains(&travelled), "travelled {travelled}");
        }
        // A moving finger whose force reverses stops at once (within the holding drive), it
        // does not keep going until its velocity unwinds.
        let mut p = FingerPhysics::at(0.8);
        run(&mut p, &cfg, active(5.0, 1.0), 100);
        run(&mut p, &cfg, active(-5.0, 1.0), 10);
        assert_eq!(p.velocity_rad_s, 0.0, "held after 10 ms at 120 rad/s²");
    }

    #[test]
    fn less_force_drives_more_gently() {
        let cfg = FingerConfig::default();
        let speed_after_30ms = |force: f64| {
            let mut p = FingerPhysics::at(0.4);
            p.force_n = force;
            run(&mut p, &cfg, active(force, 2.0), 30);
            p.velocity_rad_s
        };
        // 0.5 N of 20 N: a drive of at most 3 rad/s², less the friction;
        // 20 N: 2 rad/s reached.
        // dω/dt = 3 − c·ω: ω(t) = (3/c)·(1 − e^(−c·t)).
        let c = cfg.passive_friction_per_s;
        let expected = 3.0 / c * (1.0 - (-c * 0.03).exp());
        let gentle = speed_after_30ms(0.5);
        assert!((gentle - expected).abs() < 1e-3 * expected, "{gentle}");
        assert!((speed_after_30ms(20.0) - 2.0).abs() < 1e-9);
    }

    #[test]
    fn disabled_coasts_on_passive_friction_only() {
        let cfg = FingerConfig::default();
        let mut p = FingerPhysics::at(0.3);
        p.velocity_rad_s = 2.0;
        p.force_n = 5.0;
        let disabled = Command::default();
        run(&mut p, &cfg, disabled, 100);
        let expected = 2.0 * (-cfg.passive_friction_per_s * 0.1).exp();
        assert!(
            (p.velocity_rad_s - expected).abs() < 0.01 * expected,
            "coasting at {} after 100 ms, friction alone gives {expected}",
            p.velocity_rad_s
        );
        assert_eq!(p.force_n, 0.0, "motor off");
        assert!(p.angle_rad > 0.45, "still travelling: {}", p.angle_rad);
        // SAFE_STOP, by contrast, brakes at once.
        p.step(
            &cfg,
            &Command {
                mode: FingerMode::SafeStop,
                ..disabled
            },
            false,
            DT,
        );
        assert_eq!(p.velocity_rad_s, 0.0);
    }

    #[test]
    fn driving_into_a_stop_is_an_impact_and_raises_the_limit_only_while_pushing() {
        let cfg = FingerConfig::default();
        let mut p = FingerPhysics::at(1.2);
        let mut limit_before_the_stop = false;
        for _ in 0..400 {
            p.step(&cfg, &active(10.0, 2.0), false, DT);
            limit_before_the_stop |= p.at_limit && p.angle_rad < cfg.angle_max_rad;
        }
        assert!(!limit_before_the_stop);
        assert_eq!(p.stats.impacts, 1, "one entry into the flexion stop");
        assert!(
            (p.stats.max_impact_speed_rad_s - 2.0).abs() < 0.01,
            "impact at the commanded speed: {}",
            p.stats.max_impact_speed_rad_s
        );
        // The stop pushes back: no free zeroing, an overtravel that settles where the spring
        // balances the force limit (10 N of 20 N: 60 rad/s² / 25,000 /s² = 2.4 mrad).
        assert!(
            p.stats.max_overtravel_rad > 0.005,
            "{}",
            p.stats.max_overtravel_rad
        );
        assert!(p.stats.max_overtravel_rad <= cfg.max_overtravel_rad());
        let press = 0.5 * cfg.max_accel_rad_s2 / cfg.stop_stiffness_per_s2;
        assert!(
            (p.angle_rad - cfg.angle_max_rad - press).abs() < 1e-4,
            "pressed {} beyond the stop",
            p.angle_rad - cfg.angle_max_rad
        );
        assert!(p.velocity_rad_s.abs() < 1e-3);
        assert!(p.at_limit, "at the stop and pushing into it");
        // Holding (zero velocity) or leaving is not pushing.
        p.step(&cfg, &active(10.0, 0.0), false, DT);
        assert!(!p.at_limit, "held: not pushing");
        p.step(&cfg, &active(-10.0, -1.0), false, DT);
        assert!(!p.at_limit, "leaving the stop");
        run(&mut p, &cfg, active(-10.0, -1.0), 200);
        assert!(p.angle_rad < cfg.angle_max_rad && !p.at_limit);
        assert_eq!(p.stats.impacts, 1, "leaving is no impact");
        // A gentle approach below the threshold is no impact but still the limit.
        let mut slow = FingerPhysics::at(cfg.angle_min_rad + 0.001);
        run(&mut slow, &cfg, active(-10.0, -0.04), 200);
        assert_eq!(slow.stats.impacts, 0);
        assert!(slow.at_limit);
    }

    #[test]
    fn commands_beyond_the_limits_saturate_and_are_counted() {
        let cfg = FingerConfig::default();
        let mut p = FingerPhysics::at(0.2);
        run(&mut p, &cfg, active(30.0, 10.0), 100);
        assert_eq!(p.force_n, cfg.max_force_n, "saturated at the force limit");
        assert_eq!(
            p.velocity_rad_s, cfg.max_velocity_rad_s,
            "and at the speed limit"
        );
        assert_eq!(
            (p.stats.over_force_ticks, p.stats.over_speed_ticks),
            (100, 100)
        );
        assert_eq!(p.stats.max_force_requested_n, 30.0);
        assert_eq!(p.stats.max_speed_requested_rad_s, 10.0);
        run(&mut p, &cfg, active(-5.0, -3.0), 10);
        let hold = Command {
            mode: FingerMode::Hold,
            force_n: -25.0,
            velocity_rad_s: 0.0,
        };
        p.step(&cfg, &hold, false, DT);
        assert_eq!(
            (p.stats.over_force_ticks, p.stats.over_speed_ticks),
            (101, 100)
        );
        assert_eq!(p.stats.max_force_requested_n, 30.0, "the largest is kept");
    }

    #[test]
    fn the_brake_zeroes_velocity_and_force_at_once() {
        let cfg = FingerConfig::default();
        let mut p = FingerPhysics::at(0.5);
        run(&mut p, &cfg, active(10.0, 2.0), 100);
        p.step(&cfg, &active(10.0, 2.0), true, DT);
        assert_eq!((p.velocity_rad_s, p.force_n), (0.0, 0.0));
        let angle = p.angle_rad;
        p.step(&cfg, &Command::default(), true, DT);
        assert_eq!(p.angle_rad, angle, "held where it is");
    }

    #[test]
    fn rejects_limits_outside_the_dbc() {
        let bad = FingerConfig {
            max_force_n: 80.0,
            ..FingerConfig::default()
        };
        assert!(bad.validate().is_err());
        // Full flexion at 2 rad leaves no room for the stop's overtravel in the status range.
        let no_room = FingerConfig {
            angle_max_rad: 2.0,
            ..FingerConfig::default()
        };
        assert!(matches!(
            no_room.validate(),
            Err(SimError::OutOfRange {
                name: "angle_max_rad",
                ..
            })
        ));
        let soft = FingerConfig {
            stop_stiffness_per_s2: 10.0,
            ..FingerConfig::default()
        };
        assert!(soft.validate().is_err());
    }
}
