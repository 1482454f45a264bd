//! `session.toml`: what a calibration session recorded and how to read it.
//!
//! ```toml
//! format_version = 1
//! onset_skip_ms = 0.0        # windows starting this soon after a trial's start are left out
//! recorded_utc = "2026-12-02T13:15:28Z"  # optional: when the recording started (UTC); the
//!                            # model file's calibration date (handctl calibrate/record write it)
//!
//! [chain]                    # decoder::dsp::ChainConfig; missing fields take the defaults
//! channels = 12
//! sample_rate_hz = 1000.0
//!
//! [recording]
//! format = "candump"         # or "npy": samples n x channels, sample i at i * 1e6 / rate µs
//! file = "frames.log"        # relative to the session directory, or absolute
//! full_scale = 2047.0        # optional: |raw| (bus LSB, or file units) at or beyond this saturates
//!
//! [[segment]]                # optional: separate recordings, each filtered on its own
//! start_us = 0
//! end_us = 5000000
//!
//! [[trial]]
//! id = 1
//! finger = 1                 # 0 thumb .. 4 pinky, a finger name, or "all"
//! kind = "flexion"           # flexion | extension | rest
//! repetition = 1
//! start_us = 1000000         # or start_sample / end_sample
//! end_us = 4000000
//! ```

use std::collections::HashSet;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::error::SessionError;
use super::reference::ReferenceSpec;
use super::trial::{FingerField, Trial, TrialKind, N_FINGERS};
use crate::dsp::ChainConfig;
use crate::fsio::write_atomic;
use crate::model::provenance::{is_utc_text, utc_now, utc_text};

/// The `session.toml` format this code writes and reads.
pub const FORMAT_VERSION: u32 = 1;
/// Name of the metadata file in a session directory.
pub const META_FILE: &str = "session.toml";
/// Latest time a session may name, µs (292 000 years): TOML integers are signed 64-bit, so
/// a later time (e.g. from a huge `end_sample`) could not be written back.
pub const MAX_TIME_US: u64 = i64::MAX as u64;

/// How the raw signal is stored.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum RecordingFormat {
    /// A candump log of the bus (EMG_SAMPLES frames), as recorded on the device.
    Candump,
    /// A NumPy array `n_samples x channels` (int16, float32 or float64).
    Npy,
}

/// Where the raw signal is.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RecordingSpec {
    /// Storage format.
    pub format: RecordingFormat,
    /// File, relative to the session directory or absolute.
    pub file: PathBuf,
    /// Magnitude at which the front end saturates, in the stored integer units: raw bus LSB
    /// for a candump log (2047 for the 12-bit EMG signals), file units for a sample file.
    /// `None`: unknown, saturation is then not checked.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub full_scale: Option<f64>,
}

/// A stretch of the recording filtered on its own (the filter state starts from reset).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Segment {
    /// Start, µs, inclusive.
    pub start_us: u64,
    /// End, µs, exclusive.
    pub end_us: u64,
}

/// The parsed and checked contents of `session.toml`.
#[derive(Debug, Clone, PartialEq)]
pub struct SessionMeta {
    /// Chain configuration the session was recorded with (channel count, rate, filters).
    pub chain: ChainConfig,
    /// Windows that start less than this after a trial's start are not used (reaction time).
    pub onset_skip_ms: f64,
    /// The raw signal.
    pub recording: RecordingSpec,
    /// Separate recordings; empty = the whole recording is one.
    pub segments: Vec<Segment>,
    /// The trials, in file order.
    pub trials: Vec<Trial>,
    /// A force or angle recorded beside the EMG, if the import named one.
    pub reference: Option<ReferenceSpec>,
    /// When the recording started, UTC to the second (`2026-12-02T13:15:28Z`); None when not
    /// known (an imported recording).
    pub recorded_utc: Option<String>,
}

#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct TrialFile {
    id: u32,
    finger: FingerField,
    kind: TrialKind,
    repetition: u32,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    start_us: Option<u64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    end_us: Option<u64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    start_sample: Option<u64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    end_sample: Option<u64>,
}

#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct SessionFile {
    format_version: u32,
    #[serde(default)]
    onset_skip_ms: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    recorded_utc: Option<String>,
    chain: ChainConfig,
    recording: RecordingSpec,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    reference: Option<ReferenceSpec>,
    #[serde(default, rename = "segment", skip_serializing_if = "Vec::is_empty")]
    segments: Vec<Segment>,
    #[serde(default, rename = "trial")]
    trials: Vec<TrialFile>,
}

fn us_of_sample(sample: u64, rate_hz: f64) -> u64 {
    (sample as f64 * 1e6 / rate_hz).round() as u64
}

impl SessionMeta {
    /// The metadata of a recorded candump log `file` (relative to the session directory): the
    /// bus's EMG signals saturate at `full_scale` LSB, no onset skip, one segment. The writer
    /// of every recorded session (`handctl record`, the simulator's sessions, the demo).
    pub fn candump(
        chain: ChainConfig,
        file: impl Into<PathBuf>,
        full_scale: f64,
        trials: Vec<Trial>,
    ) -> Self {
        SessionMeta {
            chain,
            onset_skip_ms: 0.0,
            recording: RecordingSpec {
                format: RecordingFormat::Candump,
                file: file.into(),
                full_scale: Some(full_scale),
            },
            segments: Vec::new(),
            trials,
            reference: None,
            recorded_utc: None,
        }
    }

    /// The same, recorded from `unix_s` seconds after the Unix epoch.
    pub fn recorded_at(mut self, unix_s: u64) -> Self {
        self.recorded_utc = Some(utc_text(unix_s));
        self
    }

    /// The same, recorded from now.
    pub fn recorded_now(mut self) -> Self {
        self.recorded_utc = Some(utc_now());
        self
    }

    /// Parses and checks the text of a `session.toml`; `path` is only used in messages.
    pub fn parse(text: &str, path: &Path) -> Result<Self, SessionError> {
        let file: SessionFile = toml::from_str(text).map_err(|e| SessionError::Toml {
            path: path.to_path_buf(),
            message: e.to_string(),
        })?;
        if file.format_version != FORMAT_VERSION {
            return Err(SessionError::invalid(
                path,
                format!(
                    "format_version {} is not supported (this build reads {FORMAT_VERSION})",
                    file.format_version
                ),
            ));
        }
        let settings = file.chain.validate()?;
        let rate = settings.sample_rate_hz();
        let mut trials = Vec::with_capacity(file.trials.len());
        for t in &file.trials {
            let bad = |m: String| SessionError::invalid(path, format!("trial {}: {m}", t.id));
            let finger = t.finger.parse().map_err(bad)?;
            let (start_us, end_us) = match (t.start_us, t.end_us, t.start_sample, t.end_sample) {
                (Some(s), Some(e), None, None) => (s, e),
                (None, None, Some(s), Some(e)) => (us_of_sample(s, rate), us_of_sample(e, rate)),
                _ => {
                    return Err(bad(
                        "give either start_us and end_us, or start_sample and end_sample".into(),
                    ))
                }
            };
            let trial = Trial {
                id: t.id,
                finger,
                kind: t.kind,
                repetition: t.repetition,
                start_us,
                end_us,
            };
            trials.push(trial);
        }
        let meta = SessionMeta {
            chain: file.chain,
            onset_skip_ms: file.onset_skip_ms,
            recording: file.recording,
            segments: file.segments,
            trials,
            reference: file.reference,
            recorded_utc: file.recorded_utc,
        };
        meta.check(path)?;
        Ok(meta)
    }

    /// Checks what parsing cannot: ids unique, times ordered, trials inside one segment.
    pub fn check(&self, path: &Path) -> Result<(), SessionError> {
        self.chain.validate()?;
        if !(self.onset_skip_ms >= 0.0 && self.onset_skip_ms.is_finite()) {
            return Err(SessionError::invalid(
                path,
                format!(
                    "onset_skip_ms {} must be finite and >= 0",
                    self.onset_skip_ms
                ),
            ));
        }
        if let Some(t) = &self.recorded_utc {
            if !is_utc_text(t) {
                return Err(SessionError::invalid(
                    path,
                    format!("recorded_utc {t:?} is not a UTC time like \"2026-12-02T13:15:28Z\""),
                ));
            }
        }
        if let Some(fs) = self.recording.full_scale {
            if !(fs.is_finite() && fs > 0.0) {
                return Err(SessionError::invalid(
                    path,
                    format!("recording.full_scale {fs} must be finite and > 0"),
                ));
            }
        }
        if self.trials.is_empty() {
            return Err(SessionError::invalid(path, "the session has no [[trial]]"));
        }
        for (i, s) in self.segments.iter().enumerate() {
            if s.end_us > MAX_TIME_US {
                return Err(SessionError::invalid(
                    path,
                    format!("segment {i}: end_us {} is beyond {MAX_TIME_US}", s.end_us),
                ));
            }
            if s.end_us <= s.start_us {
                return Err(SessionError::invalid(
                    path,
                    format!(
                        "segment {i}: end_us {} is not after start_us {}",
                        s.end_us, s.start_us
                    ),
                ));
            }
        }
        let mut ids = HashSet::new();
        for t in &self.trials {
            if !ids.insert(t.id) {
                return Err(SessionError::invalid(
                    path,
                    format!("trial id {} appears twice", t.id),
                ));
            }
            self.check_trial(t)
                .map_err(|m| SessionError::invalid(path, m))?;
        }
        Ok(())
    }

    /// What is wrong with one trial's times and finger, if anything.
    fn check_trial(&self, t: &Trial) -> Result<(), String> {
        if t.end_us > MAX_TIME_US {
            return Err(format!(
                "{t}: end {} µs is beyond {MAX_TIME_US} µs",
                t.end_us
            ));
        }
        if t.end_us <= t.start_us {
            return Err(format!(
                "{t}: end {} µs is not after start {} µs",
                t.end_us, t.start_us
            ));
        }
        if let Some(f) = t.finger.filter(|&f| f >= N_FINGERS) {
            return Err(format!("{t}: finger {f} is not 0..4"));
        }
        if !self.segments.is_empty() && self.segment_of(t).is_none() {
            return Err(format!(
                "{t} ({}..{} µs) does not lie inside one [[segment]]",
                t.start_us, t.end_us
            ));
        }
        Ok(())
    }

    /// Index of the segment holding the whole trial (0 when there are no segments).
    pub fn segment_of(&self, trial: &Trial) -> Option<usize> {
        if self.segments.is_empty() {
            return Some(0);
        }
        self.segments
            .iter()
            .position(|s| s.start_us <= trial.start_us && trial.end_us <= s.end_us)
    }

    /// The TOML text of this metadata (trial times in µs).
    pub fn to_toml(&self) -> String {
        let file = SessionFile {
            format_version: FORMAT_VERSION,
            onset_skip_ms: self.onset_skip_ms,
            recorded_utc: self.recorded_utc.clone(),
            chain: self.chain.clone(),
            recording: self.recording.clone(),
            reference: self.reference.clone(),
            segments: self.segments.clone(),
            trials: self
                .trials
                .iter()
                .map(|t| TrialFile {
                    id: t.id,
                    finger: FingerField::of(t.finger),
                    kind: t.kind,
                    repetition: t.repetition,
                    start_us: Some(t.start_us),
                    end_us: Some(t.end_us),
                    start_sample: None,
                    end_sample: None,
                })
                .collect(),
        };
        // Serialising plain data with finite numbers cannot fail.
        toml::to_string(&file).unwrap_or_else(|e| panic!("session.toml serialisation: {e}"))
    }

    /// Reads `dir/session.toml`.
    pub fn read(dir: &Path) -> Result<Self, SessionError> {
        let path = dir.join(META_FILE);
        let text = crate::textfile::read_text(&path).map_err(|e| SessionError::io(&path, e))?;
        Self::parse(&text, &path)
    }

    /// Writes `dir/session.toml` atomically ([`crate::fsio::write_atomic`]).
    pub fn write(&self, dir: &Path) -> Result<(), SessionError> {
        std::fs::create_dir_all(dir).map_err(|e| SessionError::io(dir, e))?;
        Ok(write_atomic(
            &dir.join(META_FILE),
            self.to_toml().as_bytes(),
        )?)
    }

    /// The recording's file, resolved against the session directory.
    pub fn recording_path(&self, dir: &Path) -> PathBuf {
        if self.recording.file.is_absolute() {
            self.recording.file.clone()
        } else {
            dir.join(&self.recording.file)
        }
    }
}
