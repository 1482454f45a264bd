//! Reading the recording a session's metadata points to, in its format.

use std::path::Path;

use super::error::SessionError;
use super::meta::{RecordingFormat, SessionMeta};
use super::recording::Recording;

impl Recording {
    /// Reads the recording a session's metadata points to.
    pub fn load(meta: &SessionMeta, dir: &Path) -> Result<Self, SessionError> {
        let path = meta.recording_path(dir);
        match meta.recording.format {
            RecordingFormat::Npy => load_npy(meta, &path),
            RecordingFormat::Candump => super::candump::load_candump(meta, &path),
        }
    }
}

fn load_npy(meta: &SessionMeta, path: &Path) -> Result<Recording, SessionError> {
    let arr = crate::dsp::npy::read_npy(path).map_err(|e| match e {
        crate::dsp::npy::NpyError::Io { source, .. } => SessionError::io(path, source),
        other => SessionError::recording(path, other.to_string()),
    })?;
    let channels = meta.chain.channels;
    if arr.shape.len() != 2 || arr.shape[1] != channels {
        return Err(SessionError::recording(
            path,
            format!(
                "shape {:?} is not (n_samples, {channels}) as [chain] channels says",
                arr.shape
            ),
        ));
    }
    Recording::from_samples(channels, arr.data, meta.chain.sample_rate_hz)
        .map_err(|m| SessionError::recording(path, m))
}
