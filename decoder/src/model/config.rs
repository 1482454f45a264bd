//! Training settings: optimizer, batching, early stopping, validation split, seed.

use std::str::FromStr;

use serde::{Deserialize, Serialize};

use super::effort::EffortPenalty;
use super::error::TrainError;
use super::rest::RestFit;

/// Gradient step rule.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "name", rename_all = "snake_case")]
pub enum Optimizer {
    /// Adam (Kingma & Ba) with bias correction.
    Adam {
        /// Learning rate (default 1e-3).
        lr: f64,
        /// First-moment decay (default 0.9).
        beta1: f64,
        /// Second-moment decay (default 0.999).
        beta2: f64,
        /// Denominator guard (default 1e-8).
        eps: f64,
    },
    /// SGD with (heavy-ball) momentum: `v = μ·v + g`, `θ -= lr·v`.
    Sgd {
        /// Learning rate (default 0.01).
        lr: f64,
        /// Momentum μ (default 0.9).
        momentum: f64,
    },
}

impl Optimizer {
    /// Adam with the usual defaults.
    pub fn adam() -> Self {
        Optimizer::Adam {
            lr: 1e-3,
            beta1: 0.9,
            beta2: 0.999,
            eps: 1e-8,
        }
    }

    /// SGD with momentum 0.9, learning rate 0.01.
    pub fn sgd() -> Self {
        Optimizer::Sgd {
            lr: 0.01,
            momentum: 0.9,
        }
    }

    fn validate(&self) -> Result<(), TrainError> {
        let bad = |m: String| Err(TrainError::Config(m));
        match *self {
            Optimizer::Adam {
                lr,
                beta1,
                beta2,
                eps,
            } => {
                if !(lr > 0.0 && lr.is_finite()) {
                    return bad(format!(
                        "Adam learning rate must be > 0 and finite, got {lr}"
                    ));
                }
                if !(0.0..1.0).contains(&beta1) || !(0.0..1.0).contains(&beta2) {
                    return bad(format!(
                        "Adam betas must be in [0, 1), got {beta1}, {beta2}"
                    ));
                }
                if !(eps > 0.0 && eps.is_finite()) {
                    return bad(format!("Adam eps must be > 0, got {eps}"));
                }
            }
            Optimizer::Sgd { lr, momentum } => {
                if !(lr > 0.0 && lr.is_finite()) {
                    return bad(format!(
                        "SGD learning rate must be > 0 and finite, got {lr}"
                    ));
                }
                if !(0.0..1.0).contains(&momentum) {
                    return bad(format!("SGD momentum must be in [0, 1), got {momentum}"));
                }
            }
        }
        Ok(())
    }
}

impl Default for Optimizer {
    fn default() -> Self {
        Optimizer::adam()
    }
}

impl FromStr for Optimizer {
    type Err = TrainError;

    /// "adam" or "sgd", with their default settings.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.trim().to_ascii_lowercase().as_str() {
            "adam" => Ok(Optimizer::adam()),
            "sgd" => Ok(Optimizer::sgd()),
            _ => Err(TrainError::Config(format!(
                "unknown optimizer {s:?}: expected adam or sgd"
            ))),
        }
    }
}

/// How the windows used for early stopping are held out.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "by", rename_all = "snake_case")]
pub enum ValidationSplit {
    /// Hold out whole trials (default): about `fraction` of the trials, chosen so that every
    /// label (finger × direction, or rest) keeps at least one trial for training. Honest:
    /// held-out windows share no samples with training windows.
    Trial {
        /// Fraction of trials held out, in (0, 1).
        fraction: f64,
    },
    /// Hold out the last `fraction` of every trial's windows (in the order they were pushed,
    /// which must be time order), dropping the windows between the two parts that share samples
    /// with both (`ceil(window / step) - 1` of them, from the dataset's chain configuration).
    /// Not leaky, and works when each label has a single trial (a one-repetition calibration).
    TrialTail {
        /// Fraction of each trial's windows held out, in (0, 1).
        fraction: f64,
    },
    /// Hold out random windows. **Leaky**: windows overlap 75%, so held-out windows are near
    /// copies of training windows and early stopping stops late. Offered only to reproduce the
    /// paper's protocol.
    Window {
        /// Fraction of windows held out, in (0, 1).
        fraction: f64,
    },
    /// No held-out data: train for `max_epochs` and keep the last weights.
    None,
}

impl Default for ValidationSplit {
    fn default() -> Self {
        ValidationSplit::TrialTail { fraction: 0.2 }
    }
}

impl FromStr for ValidationSplit {
    type Err = TrainError;

    /// "trial", "trial-tail" or "window" (each holding out 20%), or "none".
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let fraction = 0.2;
        match s.trim().to_ascii_lowercase().as_str() {
            "trial" => Ok(ValidationSplit::Trial { fraction }),
            "trial-tail" | "trial_tail" => Ok(ValidationSplit::TrialTail { fraction }),
            "window" => Ok(ValidationSplit::Window { fraction }),
            "none" => Ok(ValidationSplit::None),
            _ => Err(TrainError::Config(format!(
                "unknown validation split {s:?}: expected trial, trial-tail, window or none"
            ))),
        }
    }
}

/// All training settings.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TrainConfig {
    /// Step rule (default Adam).
    pub optimizer: Optimizer,
    /// Windows per mini-batch (default 32).
    pub batch_size: usize,
    /// Upper bound on epochs (default 200).
    pub max_epochs: usize,
    /// Epochs without validation improvement before stopping (default 20; at least 1).
    pub patience: usize,
    /// Smallest decrease of the validation loss that counts as an improvement (default 1e-6).
    pub min_delta: f64,
    /// Held-out split for early stopping (default: the last 20% of every trial).
    pub split: ValidationSplit,
    /// Seed for initialisation, split and shuffling (default 0).
    pub seed: u64,
    /// The effort-ray penalty that keeps the decoder monotonic in effort (default on; `None`
    /// is the paper's plain training, and what a model file without the field was trained
    /// with).
    #[serde(default)]
    pub effort: Option<EffortPenalty>,
    /// The rest stage fitted after training from the rest windows (default on; `None` is the
    /// paper's raw output, and what a model file without the field was trained with).
    #[serde(default)]
    pub rest: Option<RestFit>,
}

impl Default for TrainConfig {
    fn default() -> Self {
        TrainConfig {
            optimizer: Optimizer::default(),
            batch_size: 32,
            max_epochs: 200,
            patience: 20,
            min_delta: 1e-6,
            split: ValidationSplit::default(),
            seed: 0,
            effort: Some(EffortPenalty::default()),
            rest: Some(RestFit::default()),
        }
    }
}

impl TrainConfig {
    /// The paper's plain training: the defaults without the effort-ray penalty and without the
    /// rest stage, early stopping on whole held-out trials (the split the issue-12 tables were
    /// first measured with).
    pub fn plain() -> Self {
        TrainConfig {
            effort: None,
            rest: None,
            split: ValidationSplit::Trial { fraction: 0.2 },
            ..TrainConfig::default()
        }
    }

    /// Checks every field; the error names the field and its allowed range.
    pub fn validate(&self) -> Result<(), TrainError> {
        self.optimizer.validate()?;
        if let Some(effort) = &self.effort {
            effort.validate()?;
        }
        if let Some(rest) = &self.rest {
            rest.validate()?;
        }
        let bad = |m: String| Err(TrainError::Config(m));
        if self.batch_size == 0 || self.batch_size > 1 << 20 {
            return bad(format!(
                "batch_size must be in 1..=1048576, got {}",
                self.batch_size
            ));
        }
        if self.max_epochs == 0 || self.max_epochs > 1_000_000 {
            return bad(format!(
                "max_epochs must be in 1..=1000000, got {}",
                self.max_epochs
            ));
        }
        if self.patience == 0 {
            return bad("patience must be at least 1 epoch, got 0".into());
        }
        if !(self.min_delta >= 0.0 && self.min_delta.is_finite()) {
            return bad(format!(
                "min_delta must be >= 0 and finite, got {}",
                self.min_delta
            ));
        }
        match self.split {
            ValidationSplit::Trial { fraction }
            | ValidationSplit::TrialTail { fraction }
            | ValidationSplit::Window { fraction }
                if !(fraction > 0.0 && fraction < 1.0) =>
            {
                bad(format!(
                    "validation fraction must be in (0, 1), got {fraction}"
                ))
            }
            _ => Ok(()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_config_without_the_effort_and_rest_fields_is_the_plain_training() {
        let mut json = serde_json::to_value(TrainConfig::default()).expect("serialise");
        assert!(json["effort"].is_object(), "{json}");
        assert!(json["rest"].is_object(), "{json}");
        json.as_object_mut().expect("object").remove("effort");
        json.as_object_mut().expect("object").remove("rest");
        let old: TrainConfig = serde_json::from_value(json).expect("old files still load");
        // No penalty, no rest stage; the split is what the file says.
        let plain = TrainConfig {
            split: old.split,
            ..TrainConfig::plain()
        };
        assert_eq!(old, plain);
        assert_ne!(old, TrainConfig::default());
    }

    #[test]
    fn bad_effort_settings_are_refused_by_name() {
        for (bad, field) in [
            (
                EffortPenalty {
                    weight: 0.0,
                    ..EffortPenalty::default()
                },
                "weight",
            ),
            (
                EffortPenalty {
                    points: 0,
                    ..EffortPenalty::default()
                },
                "points",
            ),
            (
                EffortPenalty {
                    min_slope: 1.5,
                    ..EffortPenalty::default()
                },
                "min_slope",
            ),
        ] {
            let cfg = TrainConfig {
                effort: Some(bad),
                ..TrainConfig::default()
            };
            let err = cfg.validate().expect_err("refused").to_string();
            assert!(err.contains(field), "{err}");
        }
    }
}
