//! Named scenarios: what the patient does, for how long, and (for calibration) the trials.

use std::str::FromStr;

use decoder::dsp::ChainConfig;
use decoder::session::{SessionMeta, Trial, TrialTable};

use crate::emg::{AmplifierConfig, ADC_MAX, N_CHANNELS};
use crate::error::SimError;
use crate::patient::{
    CalibrationProtocol, ClosedLoopUser, CuedConfig, Gesture, Intent, Script, Target,
    TrackingConfig,
};
use crate::world::PatientMode;

/// A named scenario.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scenario {
    /// The patient rests (tonic activity only), 60 s.
    Rest,
    /// The default calibration protocol: 3 repetitions of flexion and extension of each finger
    /// and of the whole hand, plus a rest trial, 2 s plateaus.
    Calibration,
    /// A one-repetition calibration with 0.5 s plateaus, for tests and quick demos.
    CalibrationQuick,
    /// Closed-loop tracking of a sine (amplitude 1, period 4 s) with the index finger, 40 s.
    Sine,
    /// Fist, open, pinch, point, thumbs-up, each held 2 s, twice.
    Gestures,
    /// Slow ramps of the whole hand from rest to full flexion and to full extension, 20 s.
    Ramps,
    /// The patient follows the CALIBRATION_CUE frames on the bus (`handctl calibrate`), with
    /// a human reaction delay; rests while no cue arrives. 30 min.
    Cued,
}

/// How long the cued scenario runs unless told otherwise: longer than a calibration with
/// repeats, µs.
pub const CUED_DURATION_US: u64 = 30 * 60 * 1_000_000;

impl Scenario {
    /// Every scenario.
    pub const ALL: [Scenario; 7] = [
        Scenario::Rest,
        Scenario::Calibration,
        Scenario::CalibrationQuick,
        Scenario::Sine,
        Scenario::Gestures,
        Scenario::Ramps,
        Scenario::Cued,
    ];

    /// The command-line name.
    pub fn name(self) -> &'static str {
        match self {
            Scenario::Rest => "rest",
            Scenario::Calibration => "calibration",
            Scenario::CalibrationQuick => "calibration-quick",
            Scenario::Sine => "sine",
            Scenario::Gestures => "gestures",
            Scenario::Ramps => "ramps",
            Scenario::Cued => "cued",
        }
    }

    /// One line for `--list-scenarios`.
    pub fn description(self) -> &'static str {
        match self {
            Scenario::Rest => "rest (tonic activity only), 60 s",
            Scenario::Calibration => {
                "3 x (flex + extend each finger and the whole hand, 2 s plateaus) + rest trials"
            }
            Scenario::CalibrationQuick => "1 x the calibration protocol with 0.5 s plateaus",
            Scenario::Sine => {
                "closed loop: index finger tracks a sine (amplitude 1, period 4 s), 200 ms delay, 40 s"
            }
            Scenario::Gestures => "fist, open, pinch, point, thumbs-up, held 2 s each, twice",
            Scenario::Ramps => "whole hand ramps rest -> full flexion -> rest -> full extension, 20 s",
            Scenario::Cued => {
                "follows CALIBRATION_CUE on the bus (handctl calibrate), 250-450 ms reaction; \
                 rests without cues; 30 min"
            }
        }
    }

    /// Builds the scenario; `seed` seeds the closed-loop user's motor noise and the cued
    /// patient's reaction delays (see [`ScenarioRun::cued`] for other cued settings).
    pub fn build(self, seed: u64) -> Result<ScenarioRun, SimError> {
        let scripted = |script: Script| {
            let duration_us = script.duration_us();
            ScenarioRun {
                scenario: self,
                patient: PatientMode::Script(script),
                duration_us,
                trials: Vec::new(),
            }
        };
        Ok(match self {
            Scenario::Rest => scripted(Script::resting(60_000_000)),
            Scenario::Calibration | Scenario::CalibrationQuick => {
                let protocol = if self == Scenario::Calibration {
                    CalibrationProtocol::default()
                } else {
                    CalibrationProtocol::quick()
                };
                let plan = protocol.plan()?;
                let mut run = scripted(plan.script);
                run.trials = plan.trials;
                run
            }
            Scenario::Sine => ScenarioRun {
                scenario: self,
                patient: PatientMode::ClosedLoop(Box::new(ClosedLoopUser::try_new(
                    TrackingConfig {
                        target: Target::SINE_4S,
                        seed,
                        ..TrackingConfig::default()
                    },
                )?)),
                duration_us: 40_000_000,
                trials: Vec::new(),
            },
            Scenario::Gestures => {
                let mut seq = Gesture::ALL.to_vec();
                seq.extend(Gesture::ALL);
                scripted(Script::gestures(&seq, 300_000, 2_000_000, 1_000_000))
            }
            Scenario::Ramps => {
                let mut s = Script::new();
                s.rest(1_000_000)
                    .ramp_to(Intent::all(1.0), 4_000_000)
                    .ramp_to(Intent::REST, 4_000_000)
                    .rest(1_000_000)
                    .ramp_to(Intent::all(-1.0), 4_000_000)
                    .ramp_to(Intent::REST, 4_000_000)
                    .rest(2_000_000);
                scripted(s)
            }
            Scenario::Cued => ScenarioRun::cued(CuedConfig {
                seed,
                ..CuedConfig::default()
            })?,
        })
    }

    /// The names, space separated (for error messages).
    pub fn names() -> String {
        Self::ALL.map(Scenario::name).join(" ")
    }
}

impl FromStr for Scenario {
    type Err = SimError;

    fn from_str(s: &str) -> Result<Self, SimError> {
        Self::ALL
            .into_iter()
            .find(|x| x.name() == s)
            .ok_or_else(|| SimError::UnknownScenario(s.to_owned(), Self::names()))
    }
}

/// A built scenario.
#[derive(Debug, Clone)]
pub struct ScenarioRun {
    /// Which scenario.
    pub scenario: Scenario,
    /// The patient.
    pub patient: PatientMode,
    /// How long it runs, µs.
    pub duration_us: u64,
    /// Labelled trials (calibration scenarios; empty otherwise), times relative to the start.
    pub trials: Vec<Trial>,
}

impl ScenarioRun {
    /// The cued scenario with these settings (e.g. a [`CuedConfig::weak_trial`]): runs
    /// [`CUED_DURATION_US`], no trials of its own (the cues' sender knows them).
    pub fn cued(cfg: CuedConfig) -> Result<Self, SimError> {
        Ok(Self {
            scenario: Scenario::Cued,
            patient: PatientMode::cued(cfg)?,
            duration_us: CUED_DURATION_US,
            trials: Vec::new(),
        })
    }

    /// The trials as TOML `[[trial]]` tables (the session.toml form of contracts.md).
    pub fn trials_toml(&self) -> String {
        TrialTable {
            trial: self.trials.clone(),
        }
        .to_toml()
    }

    /// The `session.toml` of a candump recording `frames_file` of this run made with `amp`
    /// (contracts.md session section; decoder::session format_version 1): the chain basics
    /// (channels, rate, mains), the recording (candump, ADC full scale) and the trials.
    pub fn session_meta(&self, frames_file: &str, amp: &AmplifierConfig) -> SessionMeta {
        let chain = ChainConfig {
            channels: N_CHANNELS,
            sample_rate_hz: amp.sample_rate_hz,
            mains_hz: amp.mains.hz() as u32,
            ..ChainConfig::default()
        };
        SessionMeta::candump(chain, frames_file, f64::from(ADC_MAX), self.trials.clone())
    }
}
