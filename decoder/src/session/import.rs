//! Importers: external recordings as sessions. The generic one (samples plus a label table)
//! is in `table_import`; here, session specs on a command line and:
//!
//! * The 3DC armband recordings (`../shared/data/3dc-armband-p{4,6,7}`, any participant: the
//!   files' `P<n>_` prefix is read from the directory) as a proxy calibration: Power
//!   Grip (gesture 7) = all fingers +1, Open Hand (8) = all fingers -1, Neutral (0) = rest. Each
//!   of its recordings is a separate segment, filtered on its own.

use std::path::{Path, PathBuf};

use super::error::SessionError;
use super::meta::{RecordingFormat, RecordingSpec, Segment, SessionMeta};
use super::recording::Recording;
use super::trial::{Trial, TrialKind};
use super::Session;
use crate::dsp::ChainConfig;

/// Which half of the 3DC recordings.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Split {
    /// `P<n>_train_*`.
    Train,
    /// `P<n>_test_*`.
    Test,
}

impl Split {
    /// "train" or "test".
    pub fn name(self) -> &'static str {
        match self {
            Split::Train => "train",
            Split::Test => "test",
        }
    }
}

impl std::str::FromStr for Split {
    type Err = SessionError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "train" => Ok(Split::Train),
            "test" => Ok(Split::Test),
            other => Err(SessionError::Spec(format!(
                "split \"{other}\" is not train or test"
            ))),
        }
    }
}

/// A session named on a command line.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum SessionSpec {
    /// A session directory.
    Dir(PathBuf),
    /// `3dc:DIR:SPLIT`: the 3DC recordings read directly.
    ThreeDc {
        /// Directory holding one participant's `P<n>_{split}_emg.npy` and
        /// `P<n>_{split}_index.csv`.
        dir: PathBuf,
        /// Which half.
        split: Split,
    },
}

/// Parses `DIR` or `3dc:DIR:train|test`.
pub fn parse_session_spec(spec: &str) -> Result<SessionSpec, SessionError> {
    match spec.strip_prefix("3dc:") {
        None => Ok(SessionSpec::Dir(PathBuf::from(spec))),
        Some(rest) => {
            let (dir, split) = rest.rsplit_once(':').ok_or_else(|| {
                SessionError::Spec(format!(
                    "\"{spec}\": a 3DC session is written 3dc:DIR:train or 3dc:DIR:test"
                ))
            })?;
            Ok(SessionSpec::ThreeDc {
                dir: PathBuf::from(dir),
                split: split.parse()?,
            })
        }
    }
}

/// Gesture ids of the 3DC recordings used as the proxy calibration.
const GESTURE_NEUTRAL: u32 = 0;
const GESTURE_POWER_GRIP: u32 = 7;
const GESTURE_OPEN_HAND: u32 = 8;
/// Channels of the 3DC armband.
pub const THREE_DC_CHANNELS: usize = 10;
/// The contraction builds up over the first 0.25-1 s of each 3DC recording: windows from the
/// first half second are not used.
const THREE_DC_ONSET_SKIP_MS: f64 = 500.0;

pub(super) fn read_text(path: &Path) -> Result<String, SessionError> {
    std::fs::read_to_string(path).map_err(|e| SessionError::io(path, e))
}

/// The participant prefix (`P4`, `P6`, ...) of the one `P<n>_{split}_emg.npy` in `dir`.
fn three_dc_participant(dir: &Path, split: Split) -> Result<String, SessionError> {
    let suffix = format!("_{}_emg.npy", split.name());
    let entries = std::fs::read_dir(dir).map_err(|e| SessionError::io(dir, e))?;
    let mut found = Vec::new();
    for entry in entries {
        let name = entry.map_err(|e| SessionError::io(dir, e))?.file_name();
        let Some(prefix) = name.to_str().and_then(|n| n.strip_suffix(&suffix)) else {
            continue;
        };
        let digits = prefix.strip_prefix('P').unwrap_or("");
        if !digits.is_empty() && digits.bytes().all(|b| b.is_ascii_digit()) {
            found.push(prefix.to_string());
        }
    }
    found.sort();
    match found.as_slice() {
        [one] => Ok(one.clone()),
        [] => Err(SessionError::invalid(
            dir,
            format!("no 3DC recording P<n>{suffix} in this directory"),
        )),
        many => Err(SessionError::invalid(
            dir,
            format!(
                "several participants' 3DC recordings ({}): keep one per directory",
                many.join(", ")
            ),
        )),
    }
}

/// The 3DC armband's signal chain: 10 channels at 1 kHz.
fn three_dc_chain() -> ChainConfig {
    ChainConfig {
        channels: THREE_DC_CHANNELS,
        sample_rate_hz: 1000.0,
        // Recorded in Canada; the recordings show no mains line either way.
        mains_hz: 60,
        ..ChainConfig::default()
    }
}

/// Positions of rep, gesture_id, start_sample and end_sample_exclusive in the index's header.
fn index_columns(header: &str, index: &Path) -> Result<[usize; 4], SessionError> {
    let cols: Vec<&str> = header.split(',').map(str::trim).collect();
    let col = |name: &str| {
        cols.iter().position(|c| *c == name).ok_or_else(|| {
            SessionError::invalid(index, format!("line 1: no column \"{name}\" in the header"))
        })
    };
    Ok([
        col("rep")?,
        col("gesture_id")?,
        col("start_sample")?,
        col("end_sample_exclusive")?,
    ])
}

fn three_dc_meta(dir: &Path, split: Split) -> Result<(SessionMeta, PathBuf), SessionError> {
    let who = three_dc_participant(dir, split)?;
    let npy = dir.join(format!("{who}_{}_emg.npy", split.name()));
    let index = dir.join(format!("{who}_{}_index.csv", split.name()));
    let text = read_text(&index)?;
    let mut lines = text.lines().enumerate();
    let header = lines.next().map(|(_, h)| h).unwrap_or("");
    let [c_rep, c_gesture, c_start, c_end] = index_columns(header, &index)?;
    let us = |s: u64| s * 1000;
    let mut trials = Vec::new();
    let mut segments = Vec::new();
    for (i, line) in lines {
        if line.trim().is_empty() {
            continue;
        }
        let f: Vec<&str> = line.split(',').map(str::trim).collect();
        let num = |c: usize| -> Result<u64, SessionError> {
            f.get(c).and_then(|v| v.parse().ok()).ok_or_else(|| {
                SessionError::invalid(
                    &index,
                    format!("line {}: column {} is not a number", i + 1, c + 1),
                )
            })
        };
        let gesture = num(c_gesture)? as u32;
        let kind = match gesture {
            GESTURE_NEUTRAL => TrialKind::Rest,
            GESTURE_POWER_GRIP => TrialKind::Flexion,
            GESTURE_OPEN_HAND => TrialKind::Extension,
            _ => continue,
        };
        let (start, end) = (num(c_start)?, num(c_end)?);
        segments.push(Segment {
            start_us: us(start),
            end_us: us(end),
        });
        trials.push(Trial {
            id: trials.len() as u32 + 1,
            finger: None,
            kind,
            repetition: num(c_rep)? as u32 + 1,
            start_us: us(start),
            end_us: us(end),
        });
    }
    let meta = SessionMeta {
        chain: three_dc_chain(),
        onset_skip_ms: THREE_DC_ONSET_SKIP_MS,
        recording: RecordingSpec {
            format: RecordingFormat::Npy,
            file: npy.clone(),
            full_scale: Some(f64::from(i16::MAX)),
        },
        segments,
        trials,
        reference: None,
        recorded_utc: None,
    };
    meta.check(&index)?;
    Ok((meta, npy))
}

/// Reads the 3DC recordings of `split` directly as a session.
pub fn load_3dc(dir: &Path, split: Split) -> Result<Session, SessionError> {
    // Absolute, so the recording path in the metadata does not depend on the working directory.
    let abs = std::fs::canonicalize(dir).map_err(|e| SessionError::io(dir, e))?;
    let (meta, _) = three_dc_meta(&abs, split)?;
    let recording = Recording::load(&meta, &abs)?;
    Session::from_parts(
        PathBuf::from(format!("3dc:{}:{}", dir.display(), split.name())),
        meta,
        recording,
    )
}

/// Writes a session directory for the 3DC recordings of `split`: a `session.toml` that refers
/// to the original NPY file by absolute path (the data is not copied).
pub fn import_3dc(dir: &Path, split: Split, out: &Path) -> Result<SessionMeta, SessionError> {
    let abs = std::fs::canonicalize(dir).map_err(|e| SessionError::io(dir, e))?;
    let (meta, _) = three_dc_meta(&abs, split)?;
    // Check the samples load before writing anything.
    let recording = Recording::load(&meta, &abs)?;
    Session::from_parts(out.to_path_buf(), meta.clone(), recording)?;
    meta.write(out)?;
    Ok(meta)
}
