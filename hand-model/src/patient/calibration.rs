//! The calibration protocol: which contractions the patient makes, and the trial metadata the
//! calibration session records (contracts.md, "session.toml": per trial id, finger 0-4 or
//! "all", kind flexion|extension|rest, start and end in µs, repetition).

use serde::{Deserialize, Serialize};

use super::intent::Intent;
use super::script::{target_intent, Script};
use crate::error::{check_range, SimError};
use crate::finger::N_FINGERS;

/// What the patient does during a trial.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum TrialKind {
    /// Flexion (label +1).
    Flexion,
    /// Extension (label -1).
    Extension,
    /// Rest (label 0 on every finger).
    Rest,
}

impl TrialKind {
    /// The label sign: +1, -1 or 0.
    pub fn sign(self) -> f64 {
        match self {
            TrialKind::Flexion => 1.0,
            TrialKind::Extension => -1.0,
            TrialKind::Rest => 0.0,
        }
    }
}

/// One calibration trial: the plateau of one instructed contraction (ramps in and out lie
/// outside `[start_us, end_us)`, so every sample inside a trial has the trial's label).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct CalibrationTrial {
    /// Trial number in protocol order, from 1 (unique in the session).
    pub id: usize,
    /// The finger (0 thumb ..= 4 pinky), or `None` for all fingers (serialised as `"all"`).
    #[serde(with = "finger_serde")]
    pub finger: Option<usize>,
    /// Flexion, extension or rest.
    pub kind: TrialKind,
    /// Start of the plateau, µs from the session start.
    pub start_us: u64,
    /// End of the plateau (exclusive), µs from the session start.
    pub end_us: u64,
    /// Repetition of the protocol this trial belongs to, from 1 (decoder::session's
    /// convention).
    pub repetition: usize,
}

impl CalibrationTrial {
    /// The per-finger label of this trial: `sign` on the trial's finger(s), 0 elsewhere.
    pub fn labels(&self) -> [f64; N_FINGERS] {
        let s = self.kind.sign();
        match self.finger {
            None => [s; N_FINGERS],
            Some(f) => std::array::from_fn(|i| if i == f { s } else { 0.0 }),
        }
    }
}

/// `finger` as `0..=4` or `"all"`.
mod finger_serde {
    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    #[derive(Serialize, Deserialize)]
    #[serde(untagged)]
    enum Repr {
        Index(usize),
        Word(String),
    }

    pub fn serialize<S: Serializer>(f: &Option<usize>, s: S) -> Result<S::Ok, S::Error> {
        match f {
            Some(i) => Repr::Index(*i),
            None => Repr::Word("all".to_owned()),
        }
        .serialize(s)
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Option<usize>, D::Error> {
        match Repr::deserialize(d)? {
            Repr::Index(i) if i < crate::finger::N_FINGERS => Ok(Some(i)),
            Repr::Index(i) => Err(serde::de::Error::custom(format!(
                "finger {i} is not 0 (thumb) ..= 4 (pinky)"
            ))),
            Repr::Word(w) if w == "all" => Ok(None),
            Repr::Word(w) => Err(serde::de::Error::custom(format!(
                "finger {w:?} is neither 0..=4 nor \"all\""
            ))),
        }
    }
}

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
    pub trials: Vec<CalibrationTrial>,
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
        for repetition in 1..=self.repetitions {
            for &finger in &targets {
                for kind in [TrialKind::Flexion, TrialKind::Extension] {
                    let target = target_intent(finger, kind.sign() * self.level)?;
                    script.ramp_to(target, self.ramp_us);
                    let start_us = script.duration_us();
                    script.hold(target, self.hold_us);
                    trials.push(CalibrationTrial {
                        id: trials.len() + 1,
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
                trials.push(CalibrationTrial {
                    id: trials.len() + 1,
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finger_serialises_as_index_or_all() {
        #[derive(Serialize, Deserialize)]
        struct Doc {
            trial: Vec<CalibrationTrial>,
        }
        let doc = Doc {
            trial: vec![
                CalibrationTrial {
                    id: 0,
                    finger: Some(3),
                    kind: TrialKind::Extension,
                    start_us: 10,
                    end_us: 20,
                    repetition: 1,
                },
                CalibrationTrial {
                    id: 1,
                    finger: None,
                    kind: TrialKind::Rest,
                    start_us: 20,
                    end_us: 30,
                    repetition: 1,
                },
            ],
        };
        let text = toml::to_string(&doc).expect("serialise");
        assert!(text.contains("finger = 3"), "{text}");
        assert!(text.contains("finger = \"all\""), "{text}");
        assert!(text.contains("kind = \"extension\""), "{text}");
        let back: Doc = toml::from_str(&text).expect("parse");
        assert_eq!(back.trial, doc.trial);
        assert!(toml::from_str::<Doc>(&text.replace("finger = 3", "finger = 7")).is_err());
    }
}
