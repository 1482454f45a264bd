//! The closed-loop patient: watches one finger's reported force and steers its intent toward a
//! target, as a person following a trace on a screen would.
//!
//! Model: the person sees the target and the finger's force with a visual-motor delay (about
//! 200 ms). The intent is a feed-forward of the target as currently shown plus a correction
//! integrated from the *perceived* error, `dc/dt = gain · (target(t - d) - force(t - d))`,
//! clamped to ±1 (a person does not wind up forever), plus motor noise: white noise low-passed
//! at a few Hz. Force is normalised by `full_scale_force_n` (the force the daemon commands at
//! label 1). An integral loop with 200 ms delay is stable for `gain` below π/(2·0.2 s) ≈ 7.8/s;
//! validation keeps it below 6/s.

use std::collections::VecDeque;

use super::intent::Intent;
use crate::emg::noise::GaussianNoise;
use crate::error::{check_range, SimError};
use crate::finger::N_FINGERS;

/// What the patient is asked to follow, in normalised force (-1..=1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Target {
    /// `amplitude · sin(2π t / period)`.
    Sine {
        /// Peak value, 0..=1.
        amplitude: f64,
        /// Period in µs.
        period_us: u64,
    },
    /// A constant level.
    Constant(f64),
}

impl Target {
    /// The sine of the issue: amplitude 1, period 4 s.
    pub const SINE_4S: Target = Target::Sine {
        amplitude: 1.0,
        period_us: 4_000_000,
    };

    /// The target at `t_us`.
    pub fn at(&self, t_us: u64) -> f64 {
        match *self {
            Target::Sine {
                amplitude,
                period_us,
            } => {
                let phase = (t_us % period_us) as f64 / period_us as f64;
                amplitude * (std::f64::consts::TAU * phase).sin()
            }
            Target::Constant(x) => x,
        }
    }
}

/// Parameters of the closed-loop patient.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrackingConfig {
    /// The finger being steered (0 thumb ..= 4 pinky).
    pub finger: usize,
    /// The trace to follow.
    pub target: Target,
    /// Visual-motor delay, µs.
    pub delay_us: u64,
    /// Integral gain of the correction, 1/s.
    pub gain_per_s: f64,
    /// Feed-forward of the shown target into the intent (1 = "I push as hard as the trace").
    pub feedforward: f64,
    /// Standard deviation of the motor noise added to the intent.
    pub noise: f64,
    /// Bandwidth of the motor noise, Hz.
    pub noise_hz: f64,
    /// Reported force that counts as 1.0, N.
    pub full_scale_force_n: f64,
    /// Seed of the motor noise.
    pub seed: u64,
}

impl Default for TrackingConfig {
    fn default() -> Self {
        Self {
            finger: 1,
            target: Target::SINE_4S,
            delay_us: 200_000,
            gain_per_s: 3.0,
            feedforward: 1.0,
            noise: 0.05,
            noise_hz: 2.0,
            full_scale_force_n: 10.0,
            seed: 1,
        }
    }
}

/// Most observations kept for the delay line (status arrives at 50 Hz: 200 ms is 10).
const HISTORY: usize = 256;

/// A patient closing the loop on one finger; the other fingers rest.
#[derive(Debug, Clone)]
pub struct ClosedLoopUser {
    cfg: TrackingConfig,
    history: VecDeque<(u64, f64)>,
    perceived: f64,
    correction: f64,
    noise_state: f64,
    noise: GaussianNoise,
    last_t: Option<u64>,
}

impl ClosedLoopUser {
    /// Checks `cfg` and builds the patient.
    pub fn try_new(cfg: TrackingConfig) -> Result<Self, SimError> {
        if cfg.finger >= N_FINGERS {
            return Err(SimError::BadFinger(cfg.finger));
        }
        if cfg.delay_us > 2_000_000 {
            return Err(SimError::OutOfRange {
                name: "delay_us",
                value: cfg.delay_us as f64,
                allowed: "0..=2000000 µs",
            });
        }
        check_range("gain_per_s", cfg.gain_per_s, 0.0, 6.0, "0..=6 /s")?;
        check_range("feedforward", cfg.feedforward, 0.0, 2.0, "0..=2")?;
        check_range("noise", cfg.noise, 0.0, 1.0, "0..=1")?;
        check_range("noise_hz", cfg.noise_hz, 0.01, 50.0, "0.01..=50 Hz")?;
        check_range(
            "full_scale_force_n",
            cfg.full_scale_force_n,
            0.1,
            50.0,
            "0.1..=50 N",
        )?;
        match cfg.target {
            Target::Sine {
                amplitude,
                period_us,
            } => {
                check_range("amplitude", amplitude, 0.0, 1.0, "0..=1")?;
                if period_us < 100_000 {
                    return Err(SimError::OutOfRange {
                        name: "period_us",
                        value: period_us as f64,
                        allowed: ">= 100000 µs",
                    });
                }
            }
            Target::Constant(x) => check_range("target", x, -1.0, 1.0, "-1..=1")?,
        }
        Ok(Self {
            cfg,
            history: VecDeque::with_capacity(HISTORY),
            perceived: 0.0,
            correction: 0.0,
            noise_state: 0.0,
            noise: GaussianNoise::new(cfg.seed, 300),
            last_t: None,
        })
    }

    /// The config.
    pub fn config(&self) -> &TrackingConfig {
        &self.cfg
    }

    /// Records the finger's reported force (N) as received at `t_us`; it is perceived
    /// `delay_us` later.
    pub fn observe(&mut self, t_us: u64, force_n: f64) {
        if self.history.len() == HISTORY {
            self.history.pop_front();
        }
        self.history
            .push_back((t_us, force_n / self.cfg.full_scale_force_n));
    }

    /// Advances the patient to `t_us` and returns the intent for all fingers.
    pub fn intent_at(&mut self, t_us: u64) -> Intent {
        let dt = self
            .last_t
            .map_or(0.0, |l| t_us.saturating_sub(l) as f64 * 1e-6);
        self.last_t = Some(t_us);
        let seen_until = t_us.saturating_sub(self.cfg.delay_us);
        while let Some(&(t, y)) = self.history.front() {
            if t > seen_until {
                break;
            }
            self.perceived = y;
            self.history.pop_front();
        }
        if t_us >= self.cfg.delay_us {
            let err = self.cfg.target.at(seen_until) - self.perceived;
            self.correction = (self.correction + dt * self.cfg.gain_per_s * err).clamp(-1.0, 1.0);
        }
        // First-order low-pass of white noise, scaled so its stationary std is `noise`.
        let a = (-std::f64::consts::TAU * self.cfg.noise_hz * dt).exp();
        let w = self.noise.next_std();
        self.noise_state = a * self.noise_state + (1.0 - a * a).sqrt() * w;
        let u = self.cfg.feedforward * self.cfg.target.at(t_us)
            + self.correction
            + self.cfg.noise * self.noise_state;
        Intent::finger(self.cfg.finger, u.clamp(-1.0, 1.0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A plant that doubles the intent (the daemon's gain is unknown to the patient) with a
    /// 50 ms reporting delay: the integral correction must pull the force onto the target.
    #[test]
    fn corrects_a_wrong_plant_gain() {
        let cfg = TrackingConfig {
            target: Target::Constant(0.4),
            noise: 0.0,
            ..TrackingConfig::default()
        };
        let mut u = ClosedLoopUser::try_new(cfg).expect("valid");
        let mut force = 0.0;
        for k in 0..10_000u64 {
            let t = k * 1000;
            let i = u.intent_at(t).0[1];
            if k % 20 == 0 {
                u.observe(t, force);
            }
            force = 2.0 * i * cfg.full_scale_force_n;
        }
        let err = force / cfg.full_scale_force_n - 0.4;
        assert!(err.abs() < 0.02, "steady-state error {err}");
    }

    #[test]
    fn rejects_bad_configs() {
        let bad = [
            TrackingConfig {
                finger: 5,
                ..Default::default()
            },
            TrackingConfig {
                gain_per_s: 10.0,
                ..Default::default()
            },
            TrackingConfig {
                target: Target::Constant(2.0),
                ..Default::default()
            },
        ];
        for c in bad {
            assert!(ClosedLoopUser::try_new(c).is_err(), "{c:?}");
        }
    }
}
