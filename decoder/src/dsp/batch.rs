//! The offline path: a whole recording through the same streaming [`Chain`].

use super::chain::Chain;
use super::config::ChainSettings;

/// A row-major matrix of feature vectors, one row per window.
#[derive(Debug, Clone, PartialEq)]
pub struct FeatureMatrix {
    /// Number of windows.
    pub n_rows: usize,
    /// Features per window (8 per channel).
    pub n_cols: usize,
    /// `n_rows * n_cols` values, row-major.
    pub data: Vec<f64>,
}

impl FeatureMatrix {
    /// Feature vector of window `i`.
    ///
    /// # Panics
    /// If `i >= n_rows`.
    pub fn row(&self, i: usize) -> &[f64] {
        &self.data[i * self.n_cols..(i + 1) * self.n_cols]
    }

    /// All rows in order.
    pub fn rows(&self) -> impl ExactSizeIterator<Item = &[f64]> + '_ {
        // chunks_exact of an empty matrix with n_cols 0 would panic; n_cols is never 0 here.
        self.data.chunks_exact(self.n_cols.max(1))
    }
}

/// Why a batch could not run.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BatchError {
    /// The sample buffer is not a whole number of multi-channel samples.
    #[error("{len} values is not a whole number of samples of {channels} channels")]
    Shape {
        /// Values given.
        len: usize,
        /// Channels configured.
        channels: usize,
    },
}

fn check_shape(settings: &ChainSettings, samples: &[f64]) -> Result<(), BatchError> {
    let channels = settings.n_channels();
    if !samples.len().is_multiple_of(channels) {
        return Err(BatchError::Shape {
            len: samples.len(),
            channels,
        });
    }
    Ok(())
}

/// Features of one recording (`samples` row-major, `n x channels`), computed by a fresh
/// [`Chain`] (reset state) exactly as the streaming path does: row `i` is
/// [`Chain::features`] after sample `settings.window_end(i)`, bit for bit (the very call the
/// daemon makes at a tick whose window ends there).
pub fn try_batch_features(
    settings: &ChainSettings,
    samples: &[f64],
) -> Result<FeatureMatrix, BatchError> {
    check_shape(settings, samples)?;
    let channels = settings.n_channels();
    let n_rows = settings.n_windows(samples.len() / channels);
    let n_cols = settings.n_features();
    let mut data = Vec::with_capacity(n_rows * n_cols);
    let mut chain = Chain::new(settings);
    for sample in samples.chunks_exact(channels) {
        if chain.push(sample) {
            data.extend_from_slice(chain.features());
        }
    }
    Ok(FeatureMatrix {
        n_rows,
        n_cols,
        data,
    })
}

/// [`try_batch_features`] for callers that know their buffer's shape.
///
/// # Panics
/// If `samples.len()` is not a multiple of the channel count.
pub fn batch_features(settings: &ChainSettings, samples: &[f64]) -> FeatureMatrix {
    match try_batch_features(settings, samples) {
        Ok(m) => m,
        Err(e) => panic!("batch_features: {e}"),
    }
}

/// The filtered signal (after the notch, before rectification) of one recording, row-major
/// `n x channels`, from a fresh [`Chain`]: equal to [`Chain::last_filtered`] after each
/// [`Chain::push`], bit for bit.
pub fn batch_filtered(settings: &ChainSettings, samples: &[f64]) -> Result<Vec<f64>, BatchError> {
    check_shape(settings, samples)?;
    let channels = settings.n_channels();
    let mut out = Vec::with_capacity(samples.len());
    let mut chain = Chain::new(settings);
    for sample in samples.chunks_exact(channels) {
        // The filter half of `push` alone: the same code, without windows and features.
        chain.filter_sample(sample);
        out.extend_from_slice(chain.last_filtered());
    }
    Ok(out)
}
