//! Per-feature scaling fitted on the training windows.
//!
//! Scale only, no centring: a feature of exactly zero (no muscle activity) stays zero, and a
//! bias-free model (ResDD, LN) then outputs exactly zero force. The scale of feature `j` is
//! `1 / RMS_j` over the training windows, so every feature reaches the model with unit RMS
//! regardless of its unit (µV, µV², ...). RMS rather than max: one artefact spike cannot shrink
//! a whole feature.

use serde::{Deserialize, Serialize};

use super::error::ModelError;

/// Multiplies each feature by a fixed, fitted factor.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Normalizer {
    scale: Vec<f64>,
}

impl Normalizer {
    /// Fits `scale_j = 1 / sqrt(mean_i x_ij²)` over `rows` (each of length `n_features`).
    ///
    /// A feature that is exactly zero in every row gets scale 0: the model learns nothing about
    /// it, so if it comes alive later (a recovered lead, say) it must not drive untrained weights.
    /// Errors on no rows, a wrong row length or a non-finite value.
    pub fn fit<'a>(
        n_features: usize,
        rows: impl IntoIterator<Item = &'a [f64]>,
    ) -> Result<Self, ModelError> {
        let mut sum_sq = vec![0.0f64; n_features];
        let mut n = 0usize;
        for (i, row) in rows.into_iter().enumerate() {
            if row.len() != n_features {
                return Err(ModelError::Shape {
                    what: format!("normalizer row {i}"),
                    expected: n_features,
                    found: row.len(),
                });
            }
            for (j, (s, &x)) in sum_sq.iter_mut().zip(row).enumerate() {
                if !x.is_finite() {
                    return Err(ModelError::NonFinite {
                        what: format!("normalizer row {i}"),
                        index: j,
                    });
                }
                *s += x * x;
            }
            n += 1;
        }
        if n == 0 {
            return Err(ModelError::EmptyFit);
        }
        let scale = sum_sq
            .into_iter()
            .map(|s| {
                let rms = (s / n as f64).sqrt();
                // Subnormal or zero RMS: no usable signal (and 1/rms would overflow).
                if rms > f64::MIN_POSITIVE.sqrt() {
                    1.0 / rms
                } else {
                    0.0
                }
            })
            .collect();
        Ok(Normalizer { scale })
    }

    /// A normalizer with given scales (finite and non-negative).
    pub fn from_scales(scale: Vec<f64>) -> Result<Self, ModelError> {
        if let Some(index) = scale.iter().position(|s| !s.is_finite() || *s < 0.0) {
            return Err(ModelError::NonFinite {
                what: "normalizer scales (must be finite and >= 0)".into(),
                index,
            });
        }
        Ok(Normalizer { scale })
    }

    /// The identity on `n` features.
    pub fn identity(n: usize) -> Self {
        Normalizer {
            scale: vec![1.0; n],
        }
    }

    /// Number of features.
    pub fn len(&self) -> usize {
        self.scale.len()
    }

    /// Whether it has no features.
    pub fn is_empty(&self) -> bool {
        self.scale.is_empty()
    }

    /// The per-feature factors.
    pub fn scales(&self) -> &[f64] {
        &self.scale
    }

    /// `out_j = x_j · scale_j`; no allocation. Panics if lengths differ (a wiring error).
    #[inline]
    pub fn apply(&self, x: &[f64], out: &mut [f64]) {
        assert_eq!(x.len(), self.scale.len(), "normalizer input length");
        assert_eq!(out.len(), self.scale.len(), "normalizer output length");
        for ((o, xi), s) in out.iter_mut().zip(x).zip(&self.scale) {
            *o = xi * s;
        }
    }
}
