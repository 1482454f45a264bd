//! The calibration protocol: which trials, how many repetitions, how long each phase lasts.
//!
//! The built-in default is the paper's: rest, then maximal flexion and maximal extension of
//! each finger and of the whole hand, 3 repetitions, 3 s to prepare, 5 s to hold, 5 s to relax.
//! A TOML file overrides any of it (every key optional, unknown keys refused):
//!
//! ```toml
//! repetitions = 3          # rounds of the whole list; each round starts with a rest trial
//! prepare_s = 3.0          # "get ready": the cue and a countdown, nothing recorded as a trial
//! hold_s = 5.0             # the contraction (or the rest trial's relaxed hold)
//! relax_s = 5.0            # relax between trials
//! rest_s = 5.0             # length of the rest trial's hold (default hold_s)
//! fingers = ["thumb", "index", "middle", "ring", "pinky", "all"]
//! kinds = ["flexion", "extension"]   # both, in this order or the other (one alone is refused)
//! max_attempts = 3         # a trial failing its check this often fails the calibration
//! ```

use std::path::Path;

use decoder::session::{TrialKind, FINGER_NAMES, N_FINGERS};
use serde::Deserialize;

/// A bad protocol file: what and where.
#[derive(Debug, thiserror::Error)]
pub enum ProtocolError {
    /// The file could not be read.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// What the OS said.
        source: std::io::Error,
    },
    /// Not TOML, an unknown key or a wrong type (the toml crate's message names the line).
    #[error("{path}: {message}")]
    Toml {
        /// The file.
        path: String,
        /// The parser's message, with line and column.
        message: String,
    },
    /// A value out of range.
    #[error("{path}: {key}: {message}")]
    Invalid {
        /// The file.
        path: String,
        /// The key.
        key: &'static str,
        /// What is wrong and what is allowed.
        message: String,
    },
}

/// The protocol file as written (every key optional).
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct ProtocolFile {
    repetitions: Option<i64>,
    prepare_s: Option<f64>,
    hold_s: Option<f64>,
    relax_s: Option<f64>,
    rest_s: Option<f64>,
    fingers: Option<Vec<String>>,
    kinds: Option<Vec<String>>,
    max_attempts: Option<i64>,
}

/// One movement the protocol asks for: a finger (None = the whole hand) and a kind.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Movement {
    /// 0 thumb .. 4 pinky, None = whole hand (and every rest trial).
    pub finger: Option<usize>,
    /// Flexion, extension or rest.
    pub kind: TrialKind,
}

/// A validated protocol (immutable).
#[derive(Debug, Clone, PartialEq)]
pub struct Protocol {
    /// Rounds of the movement list, each starting with a rest trial.
    pub repetitions: u32,
    /// Preparation phase, µs.
    pub prepare_us: u64,
    /// Hold of a contraction, µs.
    pub hold_us: u64,
    /// Hold of a rest trial, µs.
    pub rest_us: u64,
    /// Relax phase, µs.
    pub relax_us: u64,
    /// The movements of one round, after its rest trial.
    pub movements: Vec<Movement>,
    /// Attempts of one trial before the calibration fails.
    pub max_attempts: u32,
}

/// Shortest hold the quality gates can use: a few 200 ms feature windows after the onset.
const MIN_HOLD_S: f64 = 1.0;
/// Longest phase accepted (the cue's TimeLeft signal reaches 655.35 s).
const MAX_PHASE_S: f64 = 600.0;
/// Most repetitions and attempts the cue's 4-bit signals can number.
const MAX_COUNT: i64 = 15;

impl Default for Protocol {
    fn default() -> Self {
        let file = ProtocolFile::default();
        file.validate("built-in protocol")
            .expect("the built-in protocol is valid")
    }
}

impl Protocol {
    /// Reads and validates a protocol file.
    pub fn load(path: &Path) -> Result<Self, ProtocolError> {
        let name = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|source| ProtocolError::Io {
            path: name.clone(),
            source,
        })?;
        Self::parse(&text, &name)
    }

    /// Parses and validates protocol text; `name` is used in messages.
    pub fn parse(text: &str, name: &str) -> Result<Self, ProtocolError> {
        let file: ProtocolFile = toml::from_str(text).map_err(|e| ProtocolError::Toml {
            path: name.to_owned(),
            message: e.to_string(),
        })?;
        file.validate(name)
    }

    /// Every trial of the protocol in order: (movement, repetition 0-based).
    pub fn trials(&self) -> Vec<(Movement, u32)> {
        let rest = Movement {
            finger: None,
            kind: TrialKind::Rest,
        };
        (0..self.repetitions)
            .flat_map(|r| {
                std::iter::once((rest, r)).chain(self.movements.iter().map(move |&m| (m, r)))
            })
            .collect()
    }

    /// The hold of a trial of `kind`, µs.
    pub fn hold_of(&self, kind: TrialKind) -> u64 {
        if kind == TrialKind::Rest {
            self.rest_us
        } else {
            self.hold_us
        }
    }
}

impl ProtocolFile {
    fn validate(self, name: &str) -> Result<Protocol, ProtocolError> {
        let bad = |key: &'static str, message: String| ProtocolError::Invalid {
            path: name.to_owned(),
            key,
            message,
        };
        let count = |key, v: Option<i64>, default: i64| match v.unwrap_or(default) {
            n if (1..=MAX_COUNT).contains(&n) => Ok(n as u32),
            n => Err(bad(key, format!("{n} is not 1..={MAX_COUNT}"))),
        };
        let time = |key, v: Option<f64>, default: f64, min: f64| match v.unwrap_or(default) {
            s if s.is_finite() && (min..=MAX_PHASE_S).contains(&s) => Ok((s * 1e6).round() as u64),
            s => Err(bad(key, format!("{s} s is not {min}..={MAX_PHASE_S} s"))),
        };
        let hold_s = self.hold_s.unwrap_or(5.0);
        let movements = movements(self.fingers, self.kinds).map_err(|(k, m)| bad(k, m));
        Ok(Protocol {
            repetitions: count("repetitions", self.repetitions, 3)?,
            prepare_us: time("prepare_s", self.prepare_s, 3.0, 0.0)?,
            hold_us: time("hold_s", self.hold_s, 5.0, MIN_HOLD_S)?,
            rest_us: time("rest_s", self.rest_s, hold_s, MIN_HOLD_S)?,
            relax_us: time("relax_s", self.relax_s, 5.0, 0.0)?,
            movements: movements?,
            max_attempts: count("max_attempts", self.max_attempts, 3)?,
        })
    }
}

/// The movements of one round: every finger in `fingers` with every kind in `kinds`.
fn movements(
    fingers: Option<Vec<String>>,
    kinds: Option<Vec<String>>,
) -> Result<Vec<Movement>, (&'static str, String)> {
    let fingers = fingers.unwrap_or_else(|| {
        FINGER_NAMES
            .iter()
            .map(|s| s.to_string())
            .chain(std::iter::once("all".to_string()))
            .collect()
    });
    let kinds = kinds.unwrap_or_else(|| vec!["flexion".into(), "extension".into()]);
    build_movements(&fingers, &kinds)
}

fn build_movements(
    fingers: &[String],
    kinds: &[String],
) -> Result<Vec<Movement>, (&'static str, String)> {
    if fingers.is_empty() {
        return Err(("fingers", "is empty: name at least one finger".into()));
    }
    if kinds.is_empty() {
        return Err(("kinds", "is empty: flexion, extension or both".into()));
    }
    let mut fs = Vec::new();
    for f in fingers {
        let name = f.trim().to_ascii_lowercase();
        let finger = match FINGER_NAMES.iter().position(|n| *n == name) {
            Some(i) => Some(i),
            None if name == "all" => None,
            None => {
                return Err((
                    "fingers",
                    format!(
                        "{f:?} is not a finger: {} or \"all\"",
                        FINGER_NAMES.join(", ")
                    ),
                ))
            }
        };
        if fs.contains(&finger) {
            return Err(("fingers", format!("{f:?} is named twice")));
        }
        fs.push(finger);
    }
    let mut ks = Vec::new();
    for k in kinds {
        let kind = match k.trim().to_ascii_lowercase().as_str() {
            "flexion" => TrialKind::Flexion,
            "extension" => TrialKind::Extension,
            _ => {
                return Err((
                    "kinds",
                    format!("{k:?} is not flexion or extension (rest trials come by themselves)"),
                ))
            }
        };
        if ks.contains(&kind) {
            return Err(("kinds", format!("{k:?} is named twice")));
        }
        ks.push(kind);
    }
    if let [only] = ks[..] {
        let other = if only == TrialKind::Flexion {
            TrialKind::Extension
        } else {
            TrialKind::Flexion
        };
        return Err((
            "kinds",
            format!(
                "names {} alone: every finger would be trained with one anchor and never \
                 driven the other way; name both, [\"flexion\", \"extension\"] (the quality \
                 gates refuse a session without {} too)",
                only.name(),
                other.name()
            ),
        ));
    }
    debug_assert!(fs.iter().flatten().all(|&f| f < N_FINGERS));
    Ok(fs
        .iter()
        .flat_map(|&finger| ks.iter().map(move |&kind| Movement { finger, kind }))
        .collect())
}

impl Protocol {
    /// The protocol as a TOML file that [`Protocol::parse`] reads back equal (kept beside the
    /// session, so that `--resume` continues the same protocol).
    pub fn to_toml(&self) -> String {
        let mut fingers: Vec<String> = Vec::new();
        let mut kinds: Vec<String> = Vec::new();
        for m in &self.movements {
            let f = m.finger.map_or("all", |f| FINGER_NAMES[f]).to_string();
            if !fingers.contains(&f) {
                fingers.push(f);
            }
            let k = m.kind.name().to_string();
            if !kinds.contains(&k) {
                kinds.push(k);
            }
        }
        let list = |v: &[String]| {
            v.iter()
                .map(|s| format!("{s:?}"))
                .collect::<Vec<_>>()
                .join(", ")
        };
        format!(
            "repetitions = {}\nprepare_s = {:?}\nhold_s = {:?}\nrest_s = {:?}\nrelax_s = {:?}\n\
             fingers = [{}]\nkinds = [{}]\nmax_attempts = {}\n",
            self.repetitions,
            self.prepare_us as f64 / 1e6,
            self.hold_us as f64 / 1e6,
            self.rest_us as f64 / 1e6,
            self.relax_us as f64 / 1e6,
            list(&fingers),
            list(&kinds),
            self.max_attempts
        )
    }
}
