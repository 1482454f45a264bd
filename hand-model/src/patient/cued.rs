//! The cued patient: follows the CALIBRATION_CUE frames that `handctl calibrate` sends, as a
//! person follows cues on a screen, so the real calibration workflow runs without a person.
//!
//! - Only frames whose E2E check is OK are read (CRC right, alive counter advanced by at most
//!   [`CuedConfig::max_counter_delta`]); the first frame of a stream is accepted as its start.
//! - HOLD with a finger (0..4) or the whole hand (5), FLEXION or EXTENSION and some effort:
//!   contract that finger (or all five) in that direction at `Effort` % of maximal. Every other
//!   cue (IDLE, PREPARE, RELAX, DONE, ABORTED, Kind REST, Finger none) means rest.
//! - Each new instruction (a cue differing in anything but `TimeLeft`) takes effect after a
//!   reaction delay drawn uniformly from `reaction_min_us..reaction_max_us` (seeded); the
//!   contraction then builds up over `rise_us` and lets go over the slower `relax_us`
//!   ([`super::reaction::Reaction`]). Each hold's level is `effort · (1 - u · effort_jitter)`,
//!   `u` uniform in 0..1, so repetitions differ a little as a person's do.
//! - No valid cue for `cue_timeout_us` (1 s): back to rest at once (the pause was the delay).
//! - [`CuedConfig::weak_trial`]: the first attempt (`Attempt` 0) of that trial is held at
//!   `weak_level` (50 %) whatever the cue asks, so a quality check can catch and repeat it.
//! - [`CuedConfig::inverted_finger`]: at that finger's own FLEXION cue the patient extends it,
//!   at its EXTENSION cue flexes it (the two directions the wrong way round for one finger,
//!   every repetition alike), so the calibration's pattern gates can catch the inverted finger.
//!   Whole-hand cues are followed as cued.
//!
//! With the defaults a HOLD's plateau is reached at most 450 + 200 = 650 ms after the cue, and
//! rest at most 450 + 500 = 950 ms after the RELAX.
//!
//! ```
//! use hand_dbc::e2e::E2eProtector;
//! use hand_dbc::messages::{CalibrationCue, CueKind, CuePhase};
//! use hand_model::patient::{CuedConfig, CuedPatient};
//!
//! let mut patient = CuedPatient::try_new(CuedConfig { seed: 7, ..CuedConfig::default() })?;
//! let mut tool = E2eProtector::new(CalibrationCue::E2E);
//! // HOLD: maximal flexion of the index finger (1), trial 2, first repetition and attempt.
//! let hold = CalibrationCue::new(CuePhase::Hold, 2, 1, CueKind::Flexion, 0, 0, 5.0, 100)?;
//! for t in (0..=1_000_000u64).step_by(1000) {
//!     if t % 100_000 == 0 {
//!         patient.observe(t, &tool.protect_message(&hold)?); // the tool's 10 Hz
//!     }
//!     patient.intent_at(t);
//! }
//! let index = patient.intent_at(1_000_000).0[1];
//! assert!(index > 0.9, "{index}"); // flexing after the reaction delay and the rise
//! assert_eq!(patient.intent_at(1_000_000).0[0], 0.0); // the thumb rests
//! // The cues stop: after 1 s without one the patient rests again.
//! let rest = (1_001_000..=3_500_000u64).step_by(1000).map(|t| patient.intent_at(t)).last();
//! assert_eq!(rest.map(|i| i.0[1]), Some(0.0));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use hand_dbc::e2e::{E2eChecker, E2eStatus};
use hand_dbc::messages::CalibrationCue;
use hand_dbc::CanFrame;

use super::cue::CueKey;
use super::intent::Intent;
use super::reaction::Reaction;
use crate::emg::noise::GaussianNoise;
use crate::error::{check_range, SimError};
use crate::finger::N_FINGERS;
use crate::nodes::std_id;

/// Settings of the cued patient (checked once by [`CuedPatient::try_new`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CuedConfig {
    /// Seed of the reaction delays and effort jitter.
    pub seed: u64,
    /// Shortest reaction delay, µs.
    pub reaction_min_us: u64,
    /// Longest reaction delay, µs (>= `reaction_min_us`, at most 2 s).
    pub reaction_max_us: u64,
    /// Time to go from rest to a full contraction, µs (1 ms..=5 s).
    pub rise_us: u64,
    /// Time to let go of a full contraction, µs (1 ms..=5 s; slower than `rise_us` in people).
    pub relax_us: u64,
    /// Largest fraction by which a hold falls short of the requested effort, 0..=0.5.
    pub effort_jitter: f64,
    /// Without a valid cue for this long the patient rests, µs (100 ms..=10 s).
    pub cue_timeout_us: u64,
    /// Largest alive-counter step accepted (1..=15; 1 = no lost frame tolerated).
    pub max_counter_delta: u16,
    /// The trial (`Trial` of the cue, 0..=254) whose first attempt is held weakly.
    pub weak_trial: Option<u8>,
    /// The effort of that weak attempt, 0..=1, whatever the cue asks.
    pub weak_level: f64,
    /// The finger (0..=4) whose own cues are followed the wrong way round: extension at its
    /// flexion cue, flexion at its extension cue. Whole-hand cues are not inverted.
    pub inverted_finger: Option<u8>,
}

impl Default for CuedConfig {
    fn default() -> Self {
        Self {
            seed: 1,
            reaction_min_us: 250_000,
            reaction_max_us: 450_000,
            rise_us: 200_000,
            relax_us: 500_000,
            effort_jitter: 0.05,
            cue_timeout_us: 1_000_000,
            max_counter_delta: 3,
            weak_trial: None,
            weak_level: 0.5,
            inverted_finger: None,
        }
    }
}

impl CuedConfig {
    /// Checks every field; the error names the first one out of range.
    pub fn validate(&self) -> Result<(), SimError> {
        let us = |name, v: u64, lo: u64, hi: u64, allowed| {
            check_range(name, v as f64, lo as f64, hi as f64, allowed)
        };
        us(
            "reaction_max_us",
            self.reaction_max_us,
            0,
            2_000_000,
            "0..=2000000 µs",
        )?;
        let max = self.reaction_max_us;
        us(
            "reaction_min_us",
            self.reaction_min_us,
            0,
            max,
            "0..=reaction_max_us",
        )?;
        us(
            "rise_us",
            self.rise_us,
            1000,
            5_000_000,
            "1000..=5000000 µs",
        )?;
        us(
            "relax_us",
            self.relax_us,
            1000,
            5_000_000,
            "1000..=5000000 µs",
        )?;
        check_range("effort_jitter", self.effort_jitter, 0.0, 0.5, "0..=0.5")?;
        let timeout = self.cue_timeout_us;
        us(
            "cue_timeout_us",
            timeout,
            100_000,
            10_000_000,
            "100000..=10000000 µs",
        )?;
        let delta = u64::from(self.max_counter_delta);
        us("max_counter_delta", delta, 1, 15, "1..=15")?;
        if let Some(t) = self.weak_trial {
            us(
                "weak_trial",
                u64::from(t),
                0,
                254,
                "0..=254 (255 is no trial)",
            )?;
        }
        if let Some(f) = self.inverted_finger {
            us(
                "inverted_finger",
                u64::from(f),
                0,
                N_FINGERS as u64 - 1,
                "0..=4 (a finger; the whole hand is not inverted)",
            )?;
        }
        check_range("weak_level", self.weak_level, 0.0, 1.0, "0..=1")
    }
}

/// What the cued patient has read from the bus.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct CueStats {
    /// Cue frames read (E2E OK, decoded).
    pub accepted: u64,
    /// Cue frames refused: wrong CRC or length, counter jump, or a value hand.dbc does not
    /// define.
    pub refused: u64,
    /// The same frame again (counter unchanged): ignored.
    pub repeated: u64,
    /// Distinct instructions reacted to.
    pub instructions: u64,
    /// Times the cues stopped for longer than the timeout.
    pub timeouts: u64,
    /// Holds made at the weak level.
    pub weak_holds: u64,
    /// Holds made in the direction opposite to the cue (the inverted finger's).
    pub inverted_holds: u64,
}

/// A patient who does what the CALIBRATION_CUE frames say (see the module documentation).
#[derive(Debug, Clone)]
pub struct CuedPatient {
    cfg: CuedConfig,
    checker: E2eChecker,
    random: GaussianNoise,
    following: Option<CueKey>,
    last_cue_us: Option<u64>,
    reaction: Reaction,
    stats: CueStats,
}

impl CuedPatient {
    /// Checks `cfg` and builds a patient at rest, following no cue yet.
    pub fn try_new(cfg: CuedConfig) -> Result<Self, SimError> {
        cfg.validate()?;
        let checker = E2eChecker::try_new(CalibrationCue::E2E, cfg.max_counter_delta)
            .map_err(|e| SimError::BadScript(format!("cue E2E checker: {e}")))?;
        Ok(Self {
            cfg,
            checker,
            random: GaussianNoise::new(cfg.seed, 400),
            following: None,
            last_cue_us: None,
            reaction: Reaction::new(cfg.rise_us, cfg.relax_us),
            stats: CueStats::default(),
        })
    }

    /// The settings.
    pub fn config(&self) -> &CuedConfig {
        &self.cfg
    }

    /// What was read so far.
    pub fn stats(&self) -> CueStats {
        self.stats
    }

    /// The instruction being followed (the last valid cue), `None` before the first and after
    /// a timeout.
    pub fn following(&self) -> Option<CueKey> {
        self.following
    }

    /// Reads one frame received at `t_us`; frames other than CALIBRATION_CUE are ignored.
    pub fn observe(&mut self, t_us: u64, frame: &CanFrame) {
        if std_id(frame) != CalibrationCue::ID {
            return;
        }
        match self.checker.check_frame(Some(frame)) {
            E2eStatus::Ok => {}
            E2eStatus::Repeated => {
                self.stats.repeated += 1;
                return;
            }
            _ => {
                self.stats.refused += 1;
                return;
            }
        }
        let Ok(cue) = CalibrationCue::try_from_frame(frame) else {
            self.stats.refused += 1;
            return;
        };
        self.stats.accepted += 1;
        self.last_cue_us = Some(t_us);
        let key = CueKey::of(&cue);
        if self.following != Some(key) {
            self.following = Some(key);
            self.react(t_us, key);
        }
    }

    /// Advances to `t_us` (non-decreasing) and returns the intent of every finger.
    pub fn intent_at(&mut self, t_us: u64) -> Intent {
        let silent = self
            .last_cue_us
            .is_some_and(|last| t_us.saturating_sub(last) > self.cfg.cue_timeout_us);
        if silent {
            self.stats.timeouts += 1;
            self.following = None;
            self.last_cue_us = None;
            self.checker.reset();
            self.reaction.schedule(t_us, Intent::REST);
        }
        self.reaction.advance(t_us)
    }

    /// A new instruction read at `t_us`: its aim, after a reaction delay.
    fn react(&mut self, t_us: u64, key: CueKey) {
        self.stats.instructions += 1;
        let (lo, hi) = (self.cfg.reaction_min_us, self.cfg.reaction_max_us);
        let delay = self.random.uniform(lo as f64, hi as f64).round() as u64;
        let shortfall = self.random.uniform(0.0, self.cfg.effort_jitter);
        let weak =
            key.is_contraction() && key.attempt == 0 && self.cfg.weak_trial == Some(key.trial);
        let level = if weak {
            self.stats.weak_holds += 1;
            self.cfg.weak_level
        } else {
            key.requested_level()
        };
        let mut aim = key.intent(level * (1.0 - shortfall));
        let inverted = key.is_contraction() && self.cfg.inverted_finger == Some(key.finger);
        if inverted {
            self.stats.inverted_holds += 1;
            aim = aim.reversed();
        }
        self.reaction.schedule(t_us + delay, aim);
    }
}

#[cfg(test)]
mod tests {
    use hand_dbc::e2e::E2eProtector;
    use hand_dbc::messages::{CueKind, CuePhase};

    use super::*;

    fn cue(phase: CuePhase, trial: u8, finger: u8, attempt: u8) -> CalibrationCue {
        CalibrationCue::new(phase, trial, finger, CueKind::Flexion, 0, attempt, 1.0, 100)
            .expect("valid")
    }

    #[test]
    fn refuses_bad_frames_and_bad_settings() {
        let mut p = CuedPatient::try_new(CuedConfig::default()).expect("valid");
        let mut tool = E2eProtector::new(CalibrationCue::E2E);
        let mut bad = tool
            .protect_message(&cue(CuePhase::Hold, 1, 1, 0))
            .expect("ok");
        bad.data_mut()[0] ^= 0x55;
        p.observe(0, &bad);
        let good = tool
            .protect_message(&cue(CuePhase::Hold, 1, 1, 0))
            .expect("ok");
        p.observe(1000, &good);
        p.observe(2000, &good);
        let st = p.stats();
        assert_eq!((st.refused, st.accepted, st.repeated), (1, 1, 1));
        assert_eq!(st.instructions, 1);
        let bad_cfgs = [
            CuedConfig {
                reaction_min_us: 500_000,
                ..CuedConfig::default()
            },
            CuedConfig {
                weak_trial: Some(255),
                ..CuedConfig::default()
            },
            CuedConfig {
                effort_jitter: 0.9,
                ..CuedConfig::default()
            },
            CuedConfig {
                inverted_finger: Some(5),
                ..CuedConfig::default()
            },
        ];
        for c in bad_cfgs {
            assert!(CuedPatient::try_new(c).is_err(), "{c:?}");
        }
    }
}
