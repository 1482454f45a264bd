//! Trials: what the user was asked to do, and when.

use std::fmt;

use serde::{Deserialize, Serialize};

/// Number of fingers (0 thumb, 1 index, 2 middle, 3 ring, 4 pinky).
pub const N_FINGERS: usize = 5;
/// Finger names by index.
pub const FINGER_NAMES: [&str; N_FINGERS] = ["thumb", "index", "middle", "ring", "pinky"];

/// What a trial asked for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum TrialKind {
    /// Maximal flexion: target +1.
    Flexion,
    /// Maximal extension: target -1.
    Extension,
    /// Relaxed hand: target 0 for every finger.
    Rest,
}

impl TrialKind {
    /// The trial's target for an involved finger.
    pub fn target(self) -> f64 {
        match self {
            TrialKind::Flexion => 1.0,
            TrialKind::Extension => -1.0,
            TrialKind::Rest => 0.0,
        }
    }

    /// Lower-case name as written in `session.toml`.
    pub fn name(self) -> &'static str {
        match self {
            TrialKind::Flexion => "flexion",
            TrialKind::Extension => "extension",
            TrialKind::Rest => "rest",
        }
    }
}

/// One calibration trial. Times are µs on the recording's time base (for a candump log, its
/// timestamps; for sample files, `sample index * 1e6 / sample rate`).
#[derive(Debug, Clone, PartialEq)]
pub struct Trial {
    /// Identifier, unique in the session; messages name trials by it.
    pub id: u32,
    /// The finger moved; `None` = all five (a whole-hand trial, and every rest trial).
    pub finger: Option<usize>,
    /// Flexion, extension or rest.
    pub kind: TrialKind,
    /// Repetition number of this finger and kind (1-based by convention).
    pub repetition: u32,
    /// Start, µs, inclusive.
    pub start_us: u64,
    /// End, µs, exclusive.
    pub end_us: u64,
}

impl Trial {
    /// Fingers whose label this trial fixes: rest and "all" trials fix all five.
    pub fn involved(&self) -> [bool; N_FINGERS] {
        match (self.kind, self.finger) {
            (TrialKind::Rest, _) | (_, None) => [true; N_FINGERS],
            (_, Some(f)) => {
                let mut m = [false; N_FINGERS];
                m[f] = true;
                m
            }
        }
    }

    /// Per-finger targets (0 where not involved; the mask says which count).
    pub fn targets(&self) -> [f64; N_FINGERS] {
        let m = self.involved();
        let t = self.kind.target();
        std::array::from_fn(|f| if m[f] { t } else { 0.0 })
    }

    /// "all", or the finger's name.
    pub fn finger_name(&self) -> &'static str {
        match self.finger {
            None => "all",
            Some(f) => FINGER_NAMES.get(f).copied().unwrap_or("?"),
        }
    }
}

impl fmt::Display for Trial {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.kind == TrialKind::Rest {
            write!(
                f,
                "trial {} (rest, repetition {})",
                self.id, self.repetition
            )
        } else {
            write!(
                f,
                "trial {} ({} {}, repetition {})",
                self.id,
                self.finger_name(),
                self.kind.name(),
                self.repetition
            )
        }
    }
}
