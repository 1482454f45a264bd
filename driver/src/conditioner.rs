//! The output conditioner and the paper's control law, per finger.
//!
//! A model label goes through clamp -> deadband -> slew limit, then becomes setpoints:
//! `F = kF·label`, `α = kα·label`, `ω ← clamp(ω + (α − d·ω)·Δt, ±ω_max)`, where the damping `d`
//! pulls ω toward zero when the label is zero (`d = 0` reproduces the paper's `ω = ω0 + α·t`).
//! Settings are validated once by the config layer; this code cannot fail.

use crate::units::{Newton, RadPerSec, RadPerSec2};

/// Per-finger settings of the conditioner and the control law (validated by `config`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FingerGains {
    /// Force per label unit, N.
    pub kf: f64,
    /// Angular acceleration per label unit, rad/s².
    pub kalpha: f64,
    /// Largest commanded joint velocity, rad/s.
    pub omega_max: f64,
    /// Labels with a magnitude below this are zero; above it the label is rescaled so that the
    /// map stays continuous (|x| = deadband -> 0, |x| = 1 -> 1).
    pub deadband: f64,
    /// Largest change of the conditioned label per second (label units/s).
    pub slew_per_s: f64,
    /// Velocity damping toward zero, 1/s (0 = off, as in the paper).
    pub damping_per_s: f64,
}

impl Default for FingerGains {
    fn default() -> Self {
        Self {
            kf: 10.0,
            kalpha: 3.0,
            omega_max: 2.0,
            deadband: 0.05,
            slew_per_s: 10.0,
            damping_per_s: 0.0,
        }
    }
}

/// The setpoints of one finger for one tick.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Setpoint {
    /// The conditioned label the setpoints came from.
    pub label: f64,
    /// Commanded force.
    pub force: Newton,
    /// Commanded angular acceleration (informational; the bus carries force and velocity).
    pub alpha: RadPerSec2,
    /// Commanded joint velocity.
    pub velocity: RadPerSec,
}

/// The state of one finger's conditioner: the last conditioned label and the integrated velocity.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct FingerConditioner {
    label: f64,
    omega: f64,
}

impl FingerConditioner {
    /// Condition one raw label and integrate the control law over `dt_s` seconds.
    ///
    /// A non-finite label is treated as zero: the caller reports it as a fault, and the hand must
    /// not move on it.
    pub fn step(&mut self, raw: f64, gains: &FingerGains, dt_s: f64) -> Setpoint {
        let x = if raw.is_finite() {
            raw.clamp(-1.0, 1.0)
        } else {
            0.0
        };
        let x = deadband(x, gains.deadband);
        let max_step = gains.slew_per_s * dt_s;
        self.label += (x - self.label).clamp(-max_step, max_step);
        let alpha = gains.kalpha * self.label;
        let omega = self.omega + (alpha - gains.damping_per_s * self.omega) * dt_s;
        self.omega = omega.clamp(-gains.omega_max, gains.omega_max);
        Setpoint {
            label: self.label,
            force: Newton(gains.kf * self.label),
            alpha: RadPerSec2(alpha),
            velocity: RadPerSec(self.omega),
        }
    }

    /// Forget the label and velocity: after a safe stop the finger starts again from rest.
    pub fn reset(&mut self) {
        *self = Self::default();
    }

    /// The current integrated velocity, rad/s.
    pub fn omega(&self) -> f64 {
        self.omega
    }
}

fn deadband(x: f64, band: f64) -> f64 {
    let m = x.abs();
    if m <= band {
        0.0
    } else {
        x.signum() * (m - band) / (1.0 - band)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn gains() -> FingerGains {
        FingerGains {
            kf: 8.0,
            kalpha: 3.0,
            omega_max: 1.0,
            deadband: 0.1,
            slew_per_s: 1000.0,
            damping_per_s: 0.0,
        }
    }

    #[test]
    fn force_is_kf_times_label_and_deadband_is_continuous() {
        let mut c = FingerConditioner::default();
        let g = gains();
        assert_eq!(c.step(0.05, &g, 0.05).force, Newton(0.0));
        let sp = c.step(1.0, &g, 0.05);
        assert!((sp.force.0 - 8.0).abs() < 1e-12);
        let sp = c.step(0.55, &g, 0.05);
        assert!((sp.label - 0.5).abs() < 1e-12, "{}", sp.label);
        let sp = c.step(-3.0, &g, 0.05);
        assert!(
            (sp.label + 1.0).abs() < 1e-12,
            "clamped to -1, got {}",
            sp.label
        );
    }

    #[test]
    fn velocity_integrates_alpha_and_saturates() {
        let mut c = FingerConditioner::default();
        let g = gains();
        let sp = c.step(1.0, &g, 0.05);
        assert!((sp.velocity.0 - 0.15).abs() < 1e-12);
        for _ in 0..100 {
            c.step(1.0, &g, 0.05);
        }
        assert_eq!(c.omega(), 1.0);
        // Without damping the paper's law holds the velocity when the label returns to zero.
        let sp = c.step(0.0, &g, 0.05);
        assert_eq!(sp.velocity.0, 1.0);
    }

    #[test]
    fn damping_pulls_velocity_to_zero_at_rest() {
        let mut c = FingerConditioner::default();
        let g = FingerGains {
            damping_per_s: 4.0,
            ..gains()
        };
        for _ in 0..20 {
            c.step(1.0, &g, 0.05);
        }
        let before = c.omega();
        for _ in 0..40 {
            c.step(0.0, &g, 0.05);
        }
        assert!(
            before > 0.5 && c.omega().abs() < 0.01,
            "{before} -> {}",
            c.omega()
        );
    }

    #[test]
    fn slew_limit_bounds_the_change_per_tick() {
        let mut c = FingerConditioner::default();
        let g = FingerGains {
            slew_per_s: 2.0,
            deadband: 0.0,
            ..gains()
        };
        let sp = c.step(1.0, &g, 0.05);
        assert!((sp.label - 0.1).abs() < 1e-12);
        let sp = c.step(-1.0, &g, 0.05);
        assert!(sp.label.abs() < 1e-12);
    }

    #[test]
    fn non_finite_label_commands_nothing() {
        let mut c = FingerConditioner::default();
        let sp = c.step(f64::NAN, &gains(), 0.05);
        assert_eq!(sp, Setpoint::default());
    }
}
