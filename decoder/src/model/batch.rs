//! Work memory of the batched passes ([`super::Trainable::forward_batch`] and
//! [`super::Trainable::backward_batch`]): one buffer per mini-batch, sized once for the largest
//! batch, so the training steps do not allocate.

use super::traits::Scratch;

/// Activations and backward buffers for up to a given number of samples at once.
///
/// Each architecture lays out its per-layer matrices (`rows x width`, row-major) in `buf`;
/// `scratch` serves the per-sample fallback and the parts that stay per sample (the CNN's
/// convolutions).
#[derive(Debug, Clone, Default)]
pub struct BatchWork {
    pub(crate) buf: Vec<f64>,
    pub(crate) idx: Vec<usize>,
    pub(crate) scratch: Scratch,
}

impl BatchWork {
    /// Work memory of `n_f64` floats and `n_idx` indices plus a per-sample `scratch` (normally
    /// via [`super::Trainable::new_batch_work`]).
    pub fn with_capacity(n_f64: usize, n_idx: usize, scratch: Scratch) -> Self {
        BatchWork {
            buf: vec![0.0; n_f64],
            idx: vec![0; n_idx],
            scratch,
        }
    }

    /// Grows the buffers if a batch needs more than they hold (no-op when big enough).
    pub(crate) fn ensure(&mut self, n_f64: usize, n_idx: usize) {
        if self.buf.len() < n_f64 {
            self.buf.resize(n_f64, 0.0);
        }
        if self.idx.len() < n_idx {
            self.idx.resize(n_idx, 0);
        }
    }
}
