//! What training did, as stored in a model file: [`TrainingSummary`]. Its own file so that the
//! trained model (which holds one) and the training loop (which fills one in) both depend on it
//! rather than on each other.

use serde::{Deserialize, Serialize};

use super::config::TrainConfig;
use super::kind::ModelKind;

/// What training did; stored in the model file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrainingSummary {
    /// Architecture trained.
    pub kind: ModelKind,
    /// Settings used.
    pub config: TrainConfig,
    /// Epochs run.
    pub epochs_run: usize,
    /// Epoch whose weights were kept.
    pub best_epoch: usize,
    /// Whether early stopping ended training before `max_epochs`.
    pub stopped_early: bool,
    /// Training loss of the last epoch run.
    pub final_train_loss: f64,
    /// Validation loss of the kept weights (None without a split).
    pub best_val_loss: Option<f64>,
    /// Training windows.
    pub n_train_windows: usize,
    /// Held-out windows.
    pub n_val_windows: usize,
    /// Distinct trials in the training part.
    pub n_train_trials: usize,
    /// Distinct trials in the held-out part.
    pub n_val_trials: usize,
    /// Wall-clock training time in milliseconds (informative only; never affects results).
    pub duration_ms: u64,
}

impl TrainingSummary {
    /// The summary of a model that was never trained (random weights, for tests, benchmarks
    /// and tools that build a [`TrainedModel`](super::TrainedModel) by hand).
    pub fn untrained(kind: ModelKind) -> Self {
        TrainingSummary {
            kind,
            config: TrainConfig::default(),
            epochs_run: 0,
            best_epoch: 0,
            stopped_early: false,
            final_train_loss: 0.0,
            best_val_loss: None,
            n_train_windows: 0,
            n_val_windows: 0,
            n_train_trials: 0,
            n_val_trials: 0,
            duration_ms: 0,
        }
    }
}
