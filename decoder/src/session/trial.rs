//! Trials: what the user was asked to do, and when. The single definition of a calibration
//! trial for the whole stack: the decoder's sessions, `handctl record`, and the simulator's
//! calibration protocol (`hand-model` uses these types).

use std::fmt;

use serde::{Deserialize, Serialize};

/// Number of fingers and their names by index (0 thumb .. 4 pinky), from hand.dbc.
pub use hand_dbc::hand::{FINGER_NAMES, N_FINGERS};

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
/// timestamps; for sample files, `sample index * 1e6 / sample rate`). Serialised as a
/// `session.toml` `[[trial]]` table with times in µs (`finger` as 0..=4 or `"all"`; a finger
/// name is read too).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Trial {
    /// Identifier, unique in the session; messages name trials by it.
    pub id: u32,
    /// The finger moved; `None` = all five (a whole-hand trial, and every rest trial).
    #[serde(with = "finger_field")]
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

/// `finger` in a `[[trial]]` table: 0 thumb .. 4 pinky, a finger name, or `"all"`.
#[derive(Debug, Serialize, Deserialize)]
#[serde(untagged)]
pub(crate) enum FingerField {
    Index(i64),
    Name(String),
}

impl FingerField {
    /// `Some(finger)`, or `None` for all fingers.
    pub(crate) fn parse(&self) -> Result<Option<usize>, String> {
        match self {
            FingerField::Index(i) if (0..N_FINGERS as i64).contains(i) => Ok(Some(*i as usize)),
            FingerField::Index(i) => Err(format!(
                "finger {i} is not 0..4 (0 thumb .. 4 pinky) or \"all\""
            )),
            FingerField::Name(s) => {
                let s = s.trim().to_ascii_lowercase();
                if s == "all" {
                    return Ok(None);
                }
                FINGER_NAMES
                    .iter()
                    .position(|n| *n == s)
                    .map(Some)
                    .ok_or_else(|| format!("finger \"{s}\" is not 0..4, a finger name or \"all\""))
            }
        }
    }

    /// The index, or `"all"`.
    pub(crate) fn of(finger: Option<usize>) -> Self {
        match finger {
            Some(f) => FingerField::Index(f as i64),
            None => FingerField::Name("all".into()),
        }
    }
}

mod finger_field {
    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    use super::FingerField;

    pub fn serialize<S: Serializer>(f: &Option<usize>, s: S) -> Result<S::Ok, S::Error> {
        FingerField::of(*f).serialize(s)
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Option<usize>, D::Error> {
        FingerField::deserialize(d)?
            .parse()
            .map_err(serde::de::Error::custom)
    }
}

/// A file of `[[trial]]` tables alone (times in µs): what `handsim --trials-out` writes and
/// `handctl record` reads to make a session of its recording.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TrialTable {
    /// The trials, in file order.
    pub trial: Vec<Trial>,
}

impl TrialTable {
    /// The TOML text.
    pub fn to_toml(&self) -> String {
        // Plain integers and strings: serialising cannot fail.
        toml::to_string(self).unwrap_or_else(|e| panic!("trial table serialisation: {e}"))
    }

    /// Parses the TOML text; the message carries the line and column.
    pub fn parse(text: &str) -> Result<Self, String> {
        toml::from_str(text).map_err(|e| e.to_string())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finger_is_written_as_index_or_all_and_read_back() {
        let table = TrialTable {
            trial: vec![
                Trial {
                    id: 1,
                    finger: Some(3),
                    kind: TrialKind::Extension,
                    repetition: 1,
                    start_us: 10,
                    end_us: 20,
                },
                Trial {
                    id: 2,
                    finger: None,
                    kind: TrialKind::Rest,
                    repetition: 1,
                    start_us: 20,
                    end_us: 30,
                },
            ],
        };
        let text = table.to_toml();
        assert!(text.contains("finger = 3"), "{text}");
        assert!(text.contains("finger = \"all\""), "{text}");
        assert!(text.contains("kind = \"extension\""), "{text}");
        assert_eq!(TrialTable::parse(&text).expect("parse"), table);
        let named = text.replace("finger = 3", "finger = \"ring\"");
        assert_eq!(TrialTable::parse(&named).expect("name"), table);
        assert!(TrialTable::parse(&text.replace("finger = 3", "finger = 7")).is_err());
        assert!(TrialTable::parse(&text.replace("id = 1", "id = 1\nextra = 0")).is_err());
    }
}
