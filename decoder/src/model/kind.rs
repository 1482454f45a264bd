//! Which model architecture a decoder uses, as named on the command line and in model files.

use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

use super::error::ModelError;

/// The four architectures of the paper: ResDD (the contribution) and its three baselines.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ModelKind {
    /// Residual multiplicative ("dendritic") network: near-linear, bias-free.
    ResDd,
    /// Three bias-free linear layers, no activation (a factored linear map).
    Ln,
    /// Three dense layers with biases, ReLU after the first two.
    Mlp,
    /// Two 1-D convolutions over the electrode axis, one max-pool, two dense layers.
    Cnn,
}

impl ModelKind {
    /// All kinds, in the order the paper's tables list them.
    pub const ALL: [ModelKind; 4] = [
        ModelKind::ResDd,
        ModelKind::Ln,
        ModelKind::Mlp,
        ModelKind::Cnn,
    ];

    /// The lower-case name used on the command line and in files ("resdd", "ln", "mlp", "cnn").
    pub fn name(self) -> &'static str {
        match self {
            ModelKind::ResDd => "resdd",
            ModelKind::Ln => "ln",
            ModelKind::Mlp => "mlp",
            ModelKind::Cnn => "cnn",
        }
    }

    /// Whether the architecture has no bias terms, so that a zero input gives exactly zero output
    /// (the property that makes "no muscle activity" mean "no force").
    pub fn is_bias_free(self) -> bool {
        matches!(self, ModelKind::ResDd | ModelKind::Ln)
    }
}

impl fmt::Display for ModelKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for ModelKind {
    type Err = ModelError;

    /// Parses "resdd", "ln", "mlp" or "cnn" (case-insensitive, surrounding space ignored).
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let t = s.trim().to_ascii_lowercase();
        ModelKind::ALL
            .into_iter()
            .find(|k| k.name() == t)
            .ok_or_else(|| ModelError::UnknownKind(s.to_string()))
    }
}
