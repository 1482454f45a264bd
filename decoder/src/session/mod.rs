//! Calibration sessions: the raw recording of a calibration (a candump log of the bus, or an
//! imported sample file) with a small `session.toml` saying which trial ran when; loading cuts it
//! into labelled feature windows for training and evaluation, quality gates check it first.
//!
//! Targets per window: the trial's finger +1 (flexion) or -1 (extension), all five 0 for rest;
//! fingers a trial does not involve are masked out. Whole-hand trials (`finger = "all"`) set all
//! five. Importers turn external recordings (NPY or CSV plus a label table, and the 3DC armband
//! recordings as a proxy) into the same form.

mod candump;
mod error;
mod gates;
mod import;
mod load;
mod meta;
mod npy;
mod recording;
mod trial;
mod windows;

use std::path::{Path, PathBuf};

pub use error::SessionError;
pub use gates::{check_gates, GateConfig, GateIssue, GateKind, GateReport};
pub use import::{
    import_3dc, import_table, load_3dc, load_label_table, parse_session_spec, SamplesSource,
    SessionSpec, Split, TableImport,
};
pub use meta::{
    RecordingFormat, RecordingSpec, Segment, SessionMeta, FORMAT_VERSION, MAX_TIME_US, META_FILE,
};
pub use npy::{npy_f64_bytes, write_npy_f64};
pub use recording::Recording;
pub use trial::{Trial, TrialKind, TrialTable, FINGER_NAMES, N_FINGERS};
pub use windows::{LabelledWindows, WindowLabel, WindowOptions};

/// A loaded session: its metadata and raw recording.
#[derive(Debug, Clone)]
pub struct Session {
    /// Where it came from, for messages (a directory or an importer's description).
    pub name: PathBuf,
    /// `session.toml`.
    pub meta: SessionMeta,
    /// The raw signal.
    pub recording: Recording,
}

impl Session {
    /// Opens a session directory (`session.toml` plus the recording it names).
    pub fn open(dir: &Path) -> Result<Self, SessionError> {
        if !dir.is_dir() {
            return Err(SessionError::io(
                dir,
                std::io::Error::new(std::io::ErrorKind::NotFound, "no such session directory"),
            ));
        }
        let meta = SessionMeta::read(dir)?;
        let recording = Recording::load(&meta, dir)?;
        Self::from_parts(dir.to_path_buf(), meta, recording)
    }

    /// Builds a session from parts, checking that they agree.
    pub fn from_parts(
        name: PathBuf,
        meta: SessionMeta,
        recording: Recording,
    ) -> Result<Self, SessionError> {
        meta.check(&name)?;
        if recording.channels != meta.chain.channels {
            return Err(SessionError::invalid(
                &name,
                format!(
                    "the recording has {} channels, [chain] says {}",
                    recording.channels, meta.chain.channels
                ),
            ));
        }
        let last = recording.time_us.last().copied().unwrap_or(0);
        for t in &meta.trials {
            if t.start_us > last {
                return Err(SessionError::invalid(
                    &name,
                    format!(
                        "{t} starts at {} µs, after the recording ends ({last} µs)",
                        t.start_us
                    ),
                ));
            }
        }
        Ok(Session {
            name,
            meta,
            recording,
        })
    }

    /// Opens whatever a command line names: a directory, or `3dc:DIR:train|test`.
    pub fn open_spec(spec: &str) -> Result<Self, SessionError> {
        match parse_session_spec(spec)? {
            SessionSpec::Dir(d) => Self::open(&d),
            SessionSpec::ThreeDc { dir, split } => load_3dc(&dir, split),
        }
    }
}
