//! A bare recording as a session without trials, read with a given chain (a model's): what
//! `handctl decode RECORDING` runs on. A candump log (`.log`, the daemon's front end) or a
//! sample file (`.npy`, `.csv`: every column a channel, sampled at the chain's rate). It has
//! no labels, so only [`Session::stream_windows`] makes sense on it.

use std::path::{Path, PathBuf};

use super::columns::SampleTable;
use super::error::SessionError;
use super::meta::{RecordingFormat, RecordingSpec, SessionMeta};
use super::recording::Recording;
use super::Session;
use crate::dsp::ChainConfig;

impl Session {
    /// Reads the recording `path` (by its extension: `.log`, `.npy` or `.csv`) with `chain`.
    pub fn open_recording(path: &Path, chain: &ChainConfig) -> Result<Self, SessionError> {
        let settings = chain.validate()?;
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        let format = match ext.as_deref() {
            Some("log") => RecordingFormat::Candump,
            Some("npy") => RecordingFormat::Npy,
            Some("csv") => {
                let table = SampleTable::read_csv(path)?;
                let split = table.split(None, &[], settings.n_channels())?;
                let recording =
                    Recording::from_samples(settings.n_channels(), split.emg, settings.sample_rate_hz())
                        .map_err(|m| SessionError::recording(path, m))?;
                return Ok(Self::unlabelled(path, chain, RecordingFormat::Npy, recording));
            }
            _ => {
                return Err(SessionError::Spec(format!(
                    "{}: a recording is a candump log (.log) or samples (.npy, .csv); a session is a directory",
                    path.display()
                )))
            }
        };
        let meta = Self::unlabelled_meta(path, chain, format);
        let recording = Recording::load(&meta, Path::new("."))?;
        Ok(Self::unlabelled(path, chain, format, recording))
    }

    fn unlabelled_meta(path: &Path, chain: &ChainConfig, format: RecordingFormat) -> SessionMeta {
        SessionMeta {
            chain: chain.clone(),
            onset_skip_ms: 0.0,
            recording: RecordingSpec {
                format,
                file: PathBuf::from(path),
                full_scale: None,
            },
            segments: Vec::new(),
            trials: Vec::new(),
            reference: None,
            recorded_utc: None,
        }
    }

    fn unlabelled(
        path: &Path,
        chain: &ChainConfig,
        format: RecordingFormat,
        recording: Recording,
    ) -> Self {
        Session {
            name: path.to_path_buf(),
            meta: Self::unlabelled_meta(path, chain, format),
            recording,
            reference: None,
        }
    }
}
