//! The calibration protocol: which contractions the patient makes, and the trial metadata the
//! calibration session records (contracts.md, "session.toml": per trial id, finger 0-4 or
//! "all", kind flexion|extension|rest, start and end in µs, repetition). The trial types are
//! the decoder's ([`decoder::session::Trial`], [`decoder::session::TrialKind`]): one
//! definition for the simulator, the recorder and the trainer. A trial's plateau excludes the
//! ramps in and out, so every sample inside a trial has the trial's label.

use decoder::session::{Trial, TrialKind};
use serde::{Deserialize, Serialize};

use super::intent::Intent;
use super::script::{target_intent, Script};
use crate::error::{check_range, SimError};
use crate::finger::N_FINGERS;

/// The instructed contractions of a calibration session.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CalibrationProtocol {
    /// Times the whole protocol is repeated.
    pub repetitions: usize,
    /// Rest before the first trial and between contractions, µs.
    pub rest_us: u64,
    /// Ramp into and out of each contraction, µs.
    pub ramp_us: u64,
    /// Plateau of each contraction (and length of each rest trial), µs.
    pub hold_us: u64,
    /// Effort of each contraction, 0 < level <= 1.
    pub level: f64,
    /// Include a whole-hand flexion and extension after the single fingers.
    pub whole_hand: bool,
    /// Include one labelled rest trial per repetition.
    pub rest_trial: bool,
}

impl Default for CalibrationProtocol {
    fn default() -> Self {
        Self {
            repetitions: 3,
            rest_us: 1_000_000,
            ramp_us: 300_000,
            hold_us: 2_000_000,
            level: 1.0,
            whole_hand: true,
            rest_trial: true,
        }
    }
}

/// A calibration session's script and the trials it contains.
#[derive(Debug, Clone, PartialEq)]
pub struct CalibrationPlan {
    /// What the simulated patient does.
    pub script: Script,
    /// The labelled trials, in time order.
    pub trials: Vec<Trial>,
}

impl CalibrationProtocol {
    /// A short protocol for tests: one repetition, 0.5 s plateaus.
    pub fn quick() -> Self {
        Self {
            repetitions: 1,
            rest_us: 300_000,
            ramp_us: 100_000,
            hold_us: 500_000,
            ..Self::default()
        }
    }

    /// Checks the protocol.
    pub fn validate(&self) -> Result<(), SimError> {
        if self.repetitions == 0 || self.repetitions > 100 {
            return Err(SimError::BadScript(format!(
                "repetitions must be 1..=100, got {}",
                self.repetitions
            )));
        }
        if self.hold_us < 100_000 {
            return Err(SimError::BadScript(format!(
                "hold_us must be at least 100000 (one 100 ms window), got {}",
                self.hold_us
            )));
        }
        check_range("level", self.level, 0.05, 1.0, "0.05..=1")
    }

    /// Builds the script and trial list: per repetition, each finger 0..=4 flexes then
    /// extends, then (if enabled) the whole hand, then (if enabled) a rest trial.
    pub fn plan(&self) -> Result<CalibrationPlan, SimError> {
        self.validate()?;
        let mut script = Script::new();
        let mut trials = Vec::new();
        let mut targets: Vec<Option<usize>> = (0..N_FINGERS).map(Some).collect();
        if self.whole_hand {
            targets.push(None);
        }
        script.rest(self.rest_us);
        for repetition in 1..=self.repetitions as u32 {
            for &finger in &targets {
                for kind in [TrialKind::Flexion, TrialKind::Extension] {
                    let target = target_intent(finger, kind.target() * self.level)?;
                    script.ramp_to(target, self.ramp_us);
                    let start_us = script.duration_us();
                    script.hold(target, self.hold_us);
                    trials.push(Trial {
                        id: next_id(&trials),
                        finger,
                        kind,
                        start_us,
                        end_us: script.duration_us(),
                        repetition,
                    });
                    script
                        .ramp_to(Intent::REST, self.ramp_us)
                        .rest(self.rest_us);
                }
            }
            if self.rest_trial {
                let start_us = script.duration_us();
                script.rest(self.hold_us);
                trials.push(Trial {
                    id: next_id(&trials),
                    finger: None,
                    kind: TrialKind::Rest,
                    start_us,
                    end_us: script.duration_us(),
                    repetition,
                });
                script.rest(self.rest_us);
            }
        }
        Ok(CalibrationPlan { script, trials })
    }
}

/// Trial ids count from 1 in protocol order (at most 100 repetitions of 12 trials).
fn next_id(trials: &[Trial]) -> u32 {
    trials.len() as u32 + 1
}
