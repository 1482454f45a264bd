//! Labelled feature windows for training: per window the features, five finger targets, a mask
//! of the fingers the trial says something about, and the trial the window came from (the
//! held-out split is made by trial, because overlapping windows of one trial are near copies).

use std::collections::BTreeSet;

use crate::dsp::{ChainConfig, FEATURES_PER_CHANNEL};

use super::error::TrainError;

/// Number of fingers (outputs): 0 thumb, 1 index, 2 middle, 3 ring, 4 pinky (from hand.dbc).
pub use hand_dbc::hand::N_FINGERS;

/// Training windows produced by one signal chain configuration.
#[derive(Debug, Clone, PartialEq)]
pub struct Dataset {
    chain: ChainConfig,
    n_features: usize,
    x: Vec<f64>,
    y: Vec<[f64; N_FINGERS]>,
    mask: Vec<[bool; N_FINGERS]>,
    trial: Vec<usize>,
}

impl Dataset {
    /// An empty dataset for features made by `chain` (`8 × channels` features per window).
    /// Errors if the chain configuration is invalid.
    pub fn new(chain: ChainConfig) -> Result<Self, TrainError> {
        chain
            .validate()
            .map_err(|e| TrainError::Config(format!("signal chain: {e}")))?;
        Ok(Dataset {
            n_features: FEATURES_PER_CHANNEL * chain.channels,
            chain,
            x: Vec::new(),
            y: Vec::new(),
            mask: Vec::new(),
            trial: Vec::new(),
        })
    }

    /// Adds one window; a trial's windows must be added in time order (the trial-tail split
    /// relies on it). `target[f]` is the label of finger `f` (+1 maximal flexion, -1 maximal
    /// extension, 0 rest); `mask[f]` is true when that label enters the loss. Errors on a wrong
    /// feature count, a non-finite feature, or a non-finite unmasked target.
    pub fn push(
        &mut self,
        features: &[f64],
        target: [f64; N_FINGERS],
        mask: [bool; N_FINGERS],
        trial: usize,
    ) -> Result<(), TrainError> {
        let row = self.len();
        if features.len() != self.n_features {
            return Err(TrainError::FeatureCount {
                expected: self.n_features,
                found: features.len(),
            });
        }
        if let Some(col) = features.iter().position(|v| !v.is_finite()) {
            return Err(TrainError::NonFiniteFeature { row, col });
        }
        if let Some(finger) = (0..N_FINGERS).find(|&f| mask[f] && !target[f].is_finite()) {
            return Err(TrainError::NonFiniteTarget { row, finger });
        }
        self.x.extend_from_slice(features);
        // Masked targets never reach the loss; store 0 so a NaN placeholder cannot leak anywhere.
        let mut t = target;
        for f in 0..N_FINGERS {
            if !mask[f] {
                t[f] = 0.0;
            }
        }
        self.y.push(t);
        self.mask.push(mask);
        self.trial.push(trial);
        Ok(())
    }

    /// The signal chain configuration the features came from.
    pub fn chain(&self) -> &ChainConfig {
        &self.chain
    }
    /// Features per window.
    pub fn n_features(&self) -> usize {
        self.n_features
    }
    /// Number of windows.
    pub fn len(&self) -> usize {
        self.trial.len()
    }
    /// Whether there are no windows.
    pub fn is_empty(&self) -> bool {
        self.trial.is_empty()
    }
    /// Features of window `i`.
    pub fn row(&self, i: usize) -> &[f64] {
        &self.x[i * self.n_features..(i + 1) * self.n_features]
    }
    /// Targets of window `i` (masked entries are 0).
    pub fn target(&self, i: usize) -> &[f64; N_FINGERS] {
        &self.y[i]
    }
    /// Loss mask of window `i`.
    pub fn mask(&self, i: usize) -> &[bool; N_FINGERS] {
        &self.mask[i]
    }
    /// Trial id of window `i`.
    pub fn trial(&self, i: usize) -> usize {
        self.trial[i]
    }
    /// The distinct trial ids, ascending.
    pub fn trial_ids(&self) -> Vec<usize> {
        self.trial
            .iter()
            .copied()
            .collect::<BTreeSet<_>>()
            .into_iter()
            .collect()
    }
    /// Number of unmasked targets over all windows.
    pub fn n_targets(&self) -> usize {
        self.mask
            .iter()
            .map(|m| m.iter().filter(|&&b| b).count())
            .sum()
    }
}
