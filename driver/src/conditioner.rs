//! The output conditioner and the control law, per finger: the last stage before the motor.
//!
//! A model label goes through clamp -> deadband -> slew limit, then becomes setpoints:
//! `F = kF·label` and a joint velocity ω driven by `α = kα·label`:
//!
//! ```text
//! dω/dt = α − d·ω        (d = damping, or the rest damping while the label is zero)
//! ```
//!
//! integrated exactly over each tick (`ω ← ω·e^(−d·Δt) + α·(1 − e^(−d·Δt))/d`), so the update is
//! stable, and never changes sign by itself, for every damping and tick the config allows (an
//! explicit Euler step flips sign every tick once `d·Δt > 1` and diverges past 2). ω is then
//! clamped to ±ω_max.
//!
//! The defaults stop a finger when the patient relaxes (no wind-up): with `d = 0` the paper's
//! law `ω = ω0 + α·t` holds the velocity when the label returns to zero, so after a grip the
//! finger keeps closing at ω_max, and a rest offset just above the deadband winds up to full
//! speed. Here ω decays at `damping` while the patient acts (a steady label `x` gives the steady
//! speed `kα·x/d`: with the defaults full effort just reaches ω_max) and at `rest_damping` while
//! the label is inside the deadband (2 rad/s falls below 0.05 rad/s within 0.4 s). `damping = 0`
//! and `rest_damping = 0` give the paper's pure integrator back.
//!
//! Further guards, each against a way a finger could move without the patient asking:
//! - a reported joint limit (FINGER_STATUS fault bit 5: the joint sits at a stop and the command
//!   pushes into it) stops the integration into that stop: ω may leave the stop, never grow
//!   into it;
//! - gains move toward new settings (a live `tune`) at most their full range per `ramp_s`, and
//!   start from zero after every reset (arm, a model swap, any safe stop), so neither a tune nor a
//!   restart makes the force jump;
//! - the slew limit is validated to at most half the label's range per tick (`config`), so one
//!   window can never reverse a finger.
//!
//! Settings are validated once by the config layer; this code cannot fail and does not allocate.

use crate::units::{Newton, RadPerSec, RadPerSec2};
use decoder::model::hand_label;

/// Largest kF, N per label unit: the gains' ramp rate is this range per `ramp_s`.
pub const KF_MAX: f64 = 40.0;
/// Largest kα, rad/s² per label unit: the gains' ramp rate is this range per `ramp_s`.
pub const KALPHA_MAX: f64 = 50.0;

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
    /// Velocity damping toward zero while the label is not zero, 1/s (0: the paper's law).
    pub damping_per_s: f64,
    /// Velocity damping toward zero while the label is zero (inside the deadband), 1/s; the
    /// larger of this and `damping_per_s` applies at rest (0 with `damping_per_s` 0: the
    /// paper's law).
    pub rest_damping_per_s: f64,
    /// Time a gain takes to move across its whole range (kF 0 to [`KF_MAX`], kα 0 to
    /// [`KALPHA_MAX`]), s: the ramp of a live tune and of every start from rest.
    pub ramp_s: f64,
}

impl FingerGains {
    /// The paper's law: a pure integrator (`ω = ω0 + α·t`, velocity held at rest), gains
    /// otherwise as given.
    pub fn paper_law(self) -> Self {
        Self {
            damping_per_s: 0.0,
            rest_damping_per_s: 0.0,
            ..self
        }
    }
}

impl Default for FingerGains {
    fn default() -> Self {
        Self {
            kf: 10.0,
            kalpha: 3.0,
            omega_max: 2.0,
            deadband: 0.05,
            slew_per_s: 10.0,
            // kα/d = ω_max: full effort's steady speed is the velocity limit.
            damping_per_s: 1.5,
            rest_damping_per_s: 10.0,
            ramp_s: 1.0,
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

/// What the finger's controller last reported that the control law takes into account.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Feedback {
    /// FINGER_STATUS fault bit 5: the joint is at a stop and the command pushes into it.
    pub at_joint_limit: bool,
}

/// The state of one finger's conditioner: the last conditioned label, the integrated velocity,
/// the gains in force (ramping toward the settings) and the stop the joint sits at.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct FingerConditioner {
    label: f64,
    omega: f64,
    kf: f64,
    kalpha: f64,
    /// +1: the joint sits at its flexion stop, -1 at its extension stop, 0 at neither.
    stop: i8,
}

fn approach(x: f64, target: f64, max_step: f64) -> f64 {
    x + (target - x).clamp(-max_step, max_step)
}

fn sign(x: f64) -> i8 {
    if x > 0.0 {
        1
    } else if x < 0.0 {
        -1
    } else {
        0
    }
}

impl FingerConditioner {
    /// Condition one raw label and integrate the control law over `dt_s` seconds.
    ///
    /// A non-finite label is treated as zero: the caller reports it as a fault, and the hand must
    /// not move on it.
    pub fn step(
        &mut self,
        raw: f64,
        gains: &FingerGains,
        dt_s: f64,
        feedback: Feedback,
    ) -> Setpoint {
        let x = deadband(hand_label(raw), gains.deadband);
        let max_step = gains.slew_per_s * dt_s;
        self.label += (x - self.label).clamp(-max_step, max_step);

        let ramp = dt_s / gains.ramp_s;
        self.kf = approach(self.kf, gains.kf, KF_MAX * ramp);
        self.kalpha = approach(self.kalpha, gains.kalpha, KALPHA_MAX * ramp);

        let alpha = self.kalpha * self.label;
        let d = if self.label == 0.0 {
            gains.damping_per_s.max(gains.rest_damping_per_s)
        } else {
            gains.damping_per_s
        };
        self.omega = decay(self.omega, alpha, d, dt_s).clamp(-gains.omega_max, gains.omega_max);
        self.hold_at_stop(feedback);
        Setpoint {
            label: self.label,
            force: Newton(self.kf * self.label),
            alpha: RadPerSec2(alpha),
            velocity: RadPerSec(self.omega),
        }
    }

    /// At a reported joint limit the velocity may leave the stop, never grow into it. The stop
    /// is the one the finger was moving toward when the limit was first reported.
    fn hold_at_stop(&mut self, feedback: Feedback) {
        if !feedback.at_joint_limit {
            self.stop = 0;
            return;
        }
        if self.stop == 0 {
            self.stop = sign(self.omega);
        }
        match self.stop {
            1 => self.omega = self.omega.min(0.0),
            -1 => self.omega = self.omega.max(0.0),
            _ => {}
        }
    }

    /// Forget the label, velocity and gains: after a safe stop (and at arm, and after a model
    /// swap) the finger starts again from rest, its gains ramping in from zero.
    pub fn reset(&mut self) {
        *self = Self::default();
    }

    /// The current integrated velocity, rad/s.
    pub fn omega(&self) -> f64 {
        self.omega
    }

    /// The force gain in force now (ramping toward the setting), N per label unit.
    pub fn kf(&self) -> f64 {
        self.kf
    }
}

/// `dω/dt = α − d·ω` integrated exactly over `dt` with α constant: stable for every `d ≥ 0`.
fn decay(omega: f64, alpha: f64, d: f64, dt: f64) -> f64 {
    if d == 0.0 {
        return omega + alpha * dt;
    }
    let k = (-d * dt).exp();
    // (1 − e^(−d·dt))/d without cancellation for small d·dt.
    omega * k + alpha * (-(-d * dt).exp_m1()) / d
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
mod tests;
