//! The generic importer: samples as NPY (int16/int32/float32/float64, `n x columns`) or CSV
//! (one sample per line, optional header naming the columns), plus a label table CSV with the
//! header `finger,kind,repetition,start_sample,end_sample` (an `id` column is optional; finger
//! is 0..4, a finger name or `all`; kind is flexion, extension or rest). One column may be a
//! reference signal (force, angle: see [`super::Reference`]) and some may be ignored (a time
//! stamp); the rest are the EMG channels.

use std::path::{Path, PathBuf};

use super::columns::SampleTable;
use super::error::SessionError;
use super::import::read_text;
use super::meta::{RecordingFormat, RecordingSpec, Segment, SessionMeta};
use super::npy::write_npy_f64;
use super::recording::Recording;
use super::reference::{Reference, ReferenceSpec, REFERENCE_FILE};
use super::trial::{Trial, TrialKind, FINGER_NAMES};
use super::Session;
use crate::dsp::ChainConfig;

/// Where the samples of a generic import come from.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum SamplesSource {
    /// An NPY file `n x columns`; the session refers to it by absolute path when every column
    /// is a channel, else the channels are copied to `samples.npy` in the session directory.
    Npy(PathBuf),
    /// A CSV file, one sample per line (a non-numeric first line is a header naming the
    /// columns); converted to `samples.npy` in the session directory.
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
    /// The column holding a reference signal (force, angle), by header name or 0-based index;
    /// stored as the session's [`super::Reference`], not as a channel.
    pub reference: Option<String>,
    /// Columns that are neither EMG nor the reference (a time stamp), by name or index.
    pub ignore_columns: Vec<String>,
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

/// Where the session's samples are: the original NPY file (every column a channel), or
/// `samples.npy` (and `reference.npy`) written into `out`. Returns the recording's file and the
/// reference's spec.
fn store_samples(
    spec: &TableImport,
    out: &Path,
) -> Result<(PathBuf, Option<ReferenceSpec>), SessionError> {
    let channels = spec.chain.channels;
    let table = match &spec.samples {
        SamplesSource::Npy(p) if spec.reference.is_none() && spec.ignore_columns.is_empty() => {
            let abs = std::fs::canonicalize(p).map_err(|e| SessionError::io(p, e))?;
            return Ok((abs, None));
        }
        SamplesSource::Npy(p) => SampleTable::read_npy(p)?,
        SamplesSource::Csv(p) => SampleTable::read_csv(p)?,
    };
    let split = table.split(spec.reference.as_deref(), &spec.ignore_columns, channels)?;
    let rows = split.emg.len() / channels.max(1);
    std::fs::create_dir_all(out).map_err(|e| SessionError::io(out, e))?;
    write_npy_f64(&out.join("samples.npy"), rows, channels, &split.emg)?;
    let reference = match split.reference {
        Some((name, values)) => {
            write_npy_f64(&out.join(REFERENCE_FILE), values.len(), 1, &values)?;
            Some(ReferenceSpec {
                name,
                file: PathBuf::from(REFERENCE_FILE),
            })
        }
        None => None,
    };
    Ok((PathBuf::from("samples.npy"), reference))
}

/// Writes a session directory from samples and a label table. Everything is read and checked
/// before `session.toml` is written.
pub fn import_table(spec: &TableImport, out: &Path) -> Result<SessionMeta, SessionError> {
    let settings = spec.chain.validate()?;
    let trials = load_label_table(&spec.labels, settings.sample_rate_hz())?;
    let (file, reference) = store_samples(spec, out)?;
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
        reference,
        recorded_utc: None,
    };
    let recording = Recording::load(&meta, out)?;
    Reference::load(&meta, out, recording.len())?;
    Session::from_parts(out.to_path_buf(), meta.clone(), recording)?;
    meta.write(out)?;
    Ok(meta)
}
