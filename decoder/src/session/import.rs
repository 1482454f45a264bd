//! Importers: external recordings as sessions.
//!
//! * Generic: samples as NPY (int16/int32/float32/float64, `n x channels`) or CSV (one sample per
//!   line, optional header), plus a label table CSV with the header
//!   `finger,kind,repetition,start_sample,end_sample` (an `id` column is optional; finger is
//!   0..4, a finger name or `all`; kind is flexion, extension or rest).
//! * The 3DC armband recordings (`../shared/data/3dc-armband-p{4,6,7}`, any participant: the
//!   files' `P<n>_` prefix is read from the directory) as a proxy calibration: Power
//!   Grip (gesture 7) = all fingers +1, Open Hand (8) = all fingers -1, Neutral (0) = rest. Each
//!   of its recordings is a separate segment, filtered on its own.

use std::path::{Path, PathBuf};

use super::error::SessionError;
use super::meta::{RecordingFormat, RecordingSpec, Segment, SessionMeta};
use super::npy::write_npy_f64;
use super::recording::Recording;
use super::trial::{Trial, TrialKind, FINGER_NAMES};
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

fn read_text(path: &Path) -> Result<String, SessionError> {
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

/// Where the samples of a generic import come from.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum SamplesSource {
    /// An NPY file `n x channels`; the session refers to it by absolute path.
    Npy(PathBuf),
    /// A CSV file, one sample per line (a non-numeric first line is a header); converted to
    /// `samples.npy` in the session directory.
    Csv(PathBuf),
}

/// A generic import: samples plus a label table.
#[derive(Debug, Clone, PartialEq)]
pub struct TableImport {
    /// The samples.
    pub samples: SamplesSource,
    /// The label table CSV.
    pub labels: PathBuf,
    /// Chain configuration (channel count and sample rate must match the samples).
    pub chain: ChainConfig,
    /// Each label row is a separate recording, filtered on its own.
    pub rows_are_recordings: bool,
    /// Raw magnitude of saturation, if known.
    pub full_scale: Option<f64>,
    /// Windows starting this soon after a trial's start are left out.
    pub onset_skip_ms: f64,
}

/// Reads a label table (see the module docs); sample indices become µs at `sample_rate_hz`.
pub fn load_label_table(path: &Path, sample_rate_hz: f64) -> Result<Vec<Trial>, SessionError> {
    let text = read_text(path)?;
    let mut lines = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty());
    let header: Vec<String> = lines
        .next()
        .map(|(_, h)| {
            h.split(',')
                .map(|c| c.trim().to_ascii_lowercase())
                .collect()
        })
        .unwrap_or_default();
    let col = |name: &str| header.iter().position(|c| c == name);
    let need = |name: &str| {
        col(name).ok_or_else(|| {
            SessionError::invalid(
                path,
                format!("line 1: the header needs a \"{name}\" column (finger,kind,repetition,start_sample,end_sample)"),
            )
        })
    };
    let (c_f, c_k, c_r, c_s, c_e) = (
        need("finger")?,
        need("kind")?,
        need("repetition")?,
        need("start_sample")?,
        need("end_sample")?,
    );
    let c_id = col("id");
    let mut trials = Vec::new();
    for (i, line) in lines {
        let f: Vec<&str> = line.split(',').map(str::trim).collect();
        let at = |c: usize| f.get(c).copied().unwrap_or("");
        let bad = |m: String| SessionError::invalid(path, format!("line {}: {m}", i + 1));
        let num = |c: usize, what: &str| -> Result<u64, SessionError> {
            at(c)
                .parse()
                .map_err(|_| bad(format!("{what} \"{}\" is not a whole number", at(c))))
        };
        let finger = match at(c_f).to_ascii_lowercase().as_str() {
            "all" => None,
            s => match s.parse::<usize>() {
                Ok(v) if v < FINGER_NAMES.len() => Some(v),
                _ => Some(FINGER_NAMES.iter().position(|n| *n == s).ok_or_else(|| {
                    bad(format!("finger \"{s}\" is not 0..4, a finger name or all"))
                })?),
            },
        };
        let kind = match at(c_k).to_ascii_lowercase().as_str() {
            "flexion" => TrialKind::Flexion,
            "extension" => TrialKind::Extension,
            "rest" => TrialKind::Rest,
            s => {
                return Err(bad(format!(
                    "kind \"{s}\" is not flexion, extension or rest"
                )))
            }
        };
        let id = match c_id {
            Some(c) => num(c, "id")? as u32,
            None => trials.len() as u32 + 1,
        };
        let to_us = |s: u64| (s as f64 * 1e6 / sample_rate_hz).round() as u64;
        trials.push(Trial {
            id,
            finger,
            kind,
            repetition: num(c_r, "repetition")? as u32,
            start_us: to_us(num(c_s, "start_sample")?),
            end_us: to_us(num(c_e, "end_sample")?),
        });
    }
    if trials.is_empty() {
        return Err(SessionError::invalid(path, "the label table has no rows"));
    }
    Ok(trials)
}

fn read_csv_samples(path: &Path, channels: usize) -> Result<Vec<f64>, SessionError> {
    let text = read_text(path)?;
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        if line.trim().is_empty() {
            continue;
        }
        let vals: Result<Vec<f64>, _> = line.split(',').map(|v| v.trim().parse::<f64>()).collect();
        match vals {
            Ok(v) if v.len() == channels => out.extend(v),
            Ok(v) => {
                return Err(SessionError::recording(
                    path,
                    format!(
                        "line {}: {} values, expected {channels} channels",
                        i + 1,
                        v.len()
                    ),
                ))
            }
            Err(_) if i == 0 => continue, // a header
            Err(_) => {
                return Err(SessionError::recording(
                    path,
                    format!("line {}: not numbers", i + 1),
                ))
            }
        }
    }
    Ok(out)
}

/// Writes a session directory from samples and a label table.
pub fn import_table(spec: &TableImport, out: &Path) -> Result<SessionMeta, SessionError> {
    let settings = spec.chain.validate()?;
    let trials = load_label_table(&spec.labels, settings.sample_rate_hz())?;
    std::fs::create_dir_all(out).map_err(|e| SessionError::io(out, e))?;
    let file = match &spec.samples {
        SamplesSource::Npy(p) => std::fs::canonicalize(p).map_err(|e| SessionError::io(p, e))?,
        SamplesSource::Csv(p) => {
            let data = read_csv_samples(p, spec.chain.channels)?;
            let rows = data.len() / spec.chain.channels;
            write_npy_f64(&out.join("samples.npy"), rows, spec.chain.channels, &data)?;
            PathBuf::from("samples.npy")
        }
    };
    let segments = if spec.rows_are_recordings {
        trials
            .iter()
            .map(|t| Segment {
                start_us: t.start_us,
                end_us: t.end_us,
            })
            .collect()
    } else {
        Vec::new()
    };
    let meta = SessionMeta {
        chain: spec.chain.clone(),
        onset_skip_ms: spec.onset_skip_ms,
        recording: RecordingSpec {
            format: RecordingFormat::Npy,
            file,
            full_scale: spec.full_scale,
        },
        segments,
        trials,
    };
    let recording = Recording::load(&meta, out)?;
    Session::from_parts(out.to_path_buf(), meta.clone(), recording)?;
    meta.write(out)?;
    Ok(meta)
}
