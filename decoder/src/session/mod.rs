//! Calibration sessions: the raw recording of a calibration (a candump log of the bus, or an
//! imported sample file) with a small `session.toml` saying which trial ran when; loading cuts it
//! into labelled feature windows for training and evaluation, quality gates check it first.
//!
//! Targets per window: the trial's finger +1 (flexion) or -1 (extension), all five 0 for rest;
//! fingers a trial does not involve are masked out. Whole-hand trials (`finger = "all"`) set all
//! five. Importers turn external recordings (NPY or CSV plus a label table, and the 3DC armband
//! recordings as a proxy) into the same form; an imported session may carry a reference signal
//! (a force or angle column, [`Reference`]). [`Session::stream_windows`] gives every window of
//! the recording, labelled or not, for decoding.

mod candump;
mod columns;
mod error;
mod gates;
mod import;
mod load;
mod meta;
mod npy;
mod patterns;
mod recording;
mod reference;
mod rest_level;
mod stream;
mod table_import;
mod trial;
mod unlabelled;
mod windows;

use std::path::{Path, PathBuf};

pub use columns::{SampleTable, SplitColumns};
pub use error::SessionError;
pub use gates::{
    check_gates, noisy_against_others, GateConfig, GateIssue, GateKind, GateReport,
    MAX_FLEX_EXT_SIMILARITY, MIN_PATTERN_SIMILARITY, MIN_WINDOWS_PER_TRIAL,
};
pub use import::{import_3dc, load_3dc, parse_session_spec, SessionSpec, Split};
pub use meta::{
    RecordingFormat, RecordingSpec, Segment, SessionMeta, FORMAT_VERSION, MAX_TIME_US, META_FILE,
};
pub use npy::{npy_f64_bytes, write_npy_f64};
pub use patterns::{
    pearson, PatternFigures, MIN_PATTERN_CHANNELS, MIN_REFERENCE_MOVEMENTS, SWAP_MARGIN,
};
pub use recording::Recording;
pub use reference::{Reference, ReferenceSpec, REFERENCE_FILE};
pub use stream::StreamWindows;
pub use table_import::{import_table, load_label_table, SamplesSource, TableImport};
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
    /// The force or angle recorded beside it, if the session has one (one value per sample).
    pub reference: Option<Reference>,
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
        let reference = Reference::load(&meta, dir, recording.len())?;
        let mut session = Self::from_parts(dir.to_path_buf(), meta, recording)?;
        session.reference = reference;
        Ok(session)
    }

    /// Builds a session from parts, checking that they agree (no reference signal).
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
            reference: None,
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
