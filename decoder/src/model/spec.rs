//! Hyper-parameters of each architecture. `ModelSpec` carries one block per kind so that one
//! value (from a CLI or a config file) describes every model an evaluation trains.

use serde::{Deserialize, Serialize};

use crate::dsp::FEATURES_PER_CHANNEL;

use super::error::ModelError;

/// Which quantity a ResDD module multiplies its gate `G_l` by.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum ResDdVariant {
    /// `A_l = G_l ∘ X + G_l` (the paper's form: every module is gated by the projected input).
    #[default]
    InputGated,
    /// `A_l = G_l ∘ A_{l-1} + G_l` (each module gated by the previous module's output).
    Chained,
}

/// ResDD: `X = W_in·x`, `G_l = W_l·A_{l-1}`, `A_l = G_l∘M_l + G_l`, `y = W_out·A_L`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct ResDdSpec {
    /// Hidden width H (rows of `W_in`).
    pub hidden: usize,
    /// Number of modules L (0 makes ResDD a two-layer linear map).
    pub modules: usize,
    /// Module form.
    pub variant: ResDdVariant,
}

impl Default for ResDdSpec {
    fn default() -> Self {
        ResDdSpec {
            hidden: 96,
            modules: 2,
            variant: ResDdVariant::InputGated,
        }
    }
}

/// LN: three bias-free linear layers `W3·W2·W1·x`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct LnSpec {
    /// Widths of the two hidden layers.
    pub hidden: [usize; 2],
}

impl Default for LnSpec {
    fn default() -> Self {
        LnSpec { hidden: [96, 96] }
    }
}

/// MLP: three dense layers with biases, ReLU after the first two.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct MlpSpec {
    /// Widths of the two hidden layers.
    pub hidden: [usize; 2],
}

impl Default for MlpSpec {
    fn default() -> Self {
        MlpSpec { hidden: [96, 96] }
    }
}

/// CNN over the electrode axis: the input (channel-major, `features_per_channel` values per
/// electrode) is a sequence of electrodes with the features as input channels.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct CnnSpec {
    /// Features per electrode ([`FEATURES_PER_CHANNEL`] for the project's feature set).
    pub features_per_channel: usize,
    /// Filters of the first and second convolution.
    pub filters: [usize; 2],
    /// Kernel width along the electrode axis (odd; "same" zero padding).
    pub kernel: usize,
    /// Width of the hidden dense layer.
    pub dense: usize,
}

impl Default for CnnSpec {
    fn default() -> Self {
        CnnSpec {
            features_per_channel: FEATURES_PER_CHANNEL,
            filters: [16, 16],
            kernel: 3,
            dense: 64,
        }
    }
}

/// Hyper-parameters of every architecture; `train` uses the block of the requested kind.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
pub struct ModelSpec {
    /// ResDD block.
    pub resdd: ResDdSpec,
    /// LN block.
    pub ln: LnSpec,
    /// MLP block.
    pub mlp: MlpSpec,
    /// CNN block.
    pub cnn: CnnSpec,
}

/// Largest width accepted for any layer: far above any useful size, it keeps a corrupt or
/// hostile model file from asking for gigabytes.
pub const MAX_WIDTH: usize = 4096;
/// Largest number of ResDD modules accepted.
pub const MAX_MODULES: usize = 64;

pub(crate) fn check_width(what: &str, w: usize) -> Result<(), ModelError> {
    if w == 0 || w > MAX_WIDTH {
        return Err(ModelError::InvalidSpec(format!(
            "{what} must be in 1..={MAX_WIDTH}, got {w}"
        )));
    }
    Ok(())
}
