//! A session's reference signal: a force or angle recorded beside the EMG (one value per EMG
//! sample), taken from a column of the samples file at import (`handctl import --reference`)
//! and stored as `reference.npy` (`n x 1`, float64) in the session directory, named in
//! `session.toml`'s `[reference]` table.
//!
//! Resampling to the feature windows: the reference of a window is the **mean of the reference
//! over the window's samples** (the same `window_len` samples the features are computed on,
//! ending at the window's newest sample), so a window's output and its reference describe the
//! same stretch of time.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::error::SessionError;
use super::meta::SessionMeta;

/// File name of the reference in a session directory written by the importer.
pub const REFERENCE_FILE: &str = "reference.npy";

/// `session.toml`'s `[reference]` table.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ReferenceSpec {
    /// What the reference is, as its column was named at import (e.g. "force").
    pub name: String,
    /// `n x 1` float64 NPY file, relative to the session directory or absolute.
    pub file: PathBuf,
}

/// The reference signal of a session, one value per EMG sample.
#[derive(Debug, Clone, PartialEq)]
pub struct Reference {
    /// What it is (its column name at import).
    pub name: String,
    /// One value per sample of the recording.
    pub values: Vec<f64>,
}

impl Reference {
    /// Reads the reference `meta` names, if any, checking it has one finite value per sample
    /// of a recording of `n_samples` samples.
    pub fn load(
        meta: &SessionMeta,
        dir: &Path,
        n_samples: usize,
    ) -> Result<Option<Self>, SessionError> {
        let Some(spec) = &meta.reference else {
            return Ok(None);
        };
        let path = if spec.file.is_absolute() {
            spec.file.clone()
        } else {
            dir.join(&spec.file)
        };
        let arr = crate::dsp::npy::read_npy(&path).map_err(|e| match e {
            crate::dsp::npy::NpyError::Io { source, .. } => SessionError::io(&path, source),
            other => SessionError::recording(&path, other.to_string()),
        })?;
        let rows = arr.shape.first().copied().unwrap_or(0);
        if arr.shape.len() > 2 || arr.shape.get(1).is_some_and(|&c| c != 1) || rows != n_samples {
            return Err(SessionError::recording(
                &path,
                format!(
                    "shape {:?}: the reference needs one value per sample ({n_samples}, 1)",
                    arr.shape
                ),
            ));
        }
        if let Some(i) = arr.data.iter().position(|v| !v.is_finite()) {
            return Err(SessionError::recording(
                &path,
                format!("reference value {i} is not finite"),
            ));
        }
        Ok(Some(Reference {
            name: spec.name.clone(),
            values: arr.data,
        }))
    }

    /// The reference per window: the mean over the `window_len` samples ending before each
    /// exclusive end sample in `ends` (see the module docs). Ends must be `>= window_len` and
    /// at most the recording's length, as every window's are.
    pub fn window_means(&self, ends: &[usize], window_len: usize) -> Vec<f64> {
        ends.iter()
            .map(|&end| {
                let span = &self.values[end - window_len..end];
                span.iter().sum::<f64>() / window_len as f64
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_window_gets_the_mean_of_its_own_samples() {
        let r = Reference {
            name: "force".into(),
            values: vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.0],
        };
        assert_eq!(r.window_means(&[2, 4, 6], 2), vec![1.5, 3.5, 5.5]);
        assert_eq!(r.window_means(&[3, 6], 3), vec![2.0, 5.0]);
    }
}
