//! The training loop: masked MSE, mini-batches, Adam or SGD, early stopping on held-out data.
//!
//! Deterministic: one ChaCha8 stream seeded from [`TrainConfig::seed`] makes the split, the
//! initial weights and the per-epoch shuffles, in that order; every sum runs in a fixed order on
//! one thread. The same seed and the same data therefore give bit-identical weights.

use std::time::Instant;

use super::any::AnyModel;
use super::config::TrainConfig;
use super::dataset::{Dataset, N_FINGERS};
use super::error::TrainError;
use super::init::SeededRng;
use super::kind::ModelKind;
use super::normalizer::Normalizer;
use super::optim::OptimState;
use super::spec::ModelSpec;
use super::split::make_split;
use super::summary::TrainingSummary;
use super::trained::TrainedModel;
use super::traits::{Model, Scratch, Trainable};

/// Progress after one epoch, passed to the caller's callback (which decides how to show it).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EpochReport {
    /// Epoch number, from 1.
    pub epoch: usize,
    /// The configured upper bound on epochs.
    pub max_epochs: usize,
    /// Mean masked squared error over the training windows during this epoch (running mean
    /// over its mini-batches, as the weights moved).
    pub train_loss: f64,
    /// Masked MSE on the held-out windows after this epoch (None without a split).
    pub val_loss: Option<f64>,
    /// Epoch with the best validation loss so far (the current one without a split).
    pub best_epoch: usize,
}

/// Masked MSE of `model` over windows `idx` (normalized features in `xn`).
fn masked_mse(
    model: &AnyModel,
    data: &Dataset,
    xn: &[f64],
    idx: &[usize],
    scratch: &mut Scratch,
) -> f64 {
    let nf = data.n_features();
    let mut y = [0.0; N_FINGERS];
    let (mut sum, mut count) = (0.0, 0usize);
    for &i in idx {
        model.predict_with(&xn[i * nf..(i + 1) * nf], &mut y, scratch);
        let (t, m) = (data.target(i), data.mask(i));
        for f in 0..N_FINGERS {
            if m[f] {
                let e = y[f] - t[f];
                sum += e * e;
                count += 1;
            }
        }
    }
    if count == 0 {
        0.0
    } else {
        sum / count as f64
    }
}

fn distinct_trials(data: &Dataset, idx: &[usize]) -> usize {
    let mut t: Vec<usize> = idx.iter().map(|&i| data.trial(i)).collect();
    t.sort_unstable();
    t.dedup();
    t.len()
}

/// Trains a model of `kind` (using `spec`'s block for it) on `data`.
///
/// The normalizer is fitted on the training part of the split only. With a split, the weights
/// of the epoch with the lowest validation loss are kept; `progress` is called after every
/// epoch. Errors on an empty or fully masked dataset, invalid settings, an impossible split, or
/// a diverging loss.
pub fn train(
    kind: ModelKind,
    spec: &ModelSpec,
    data: &Dataset,
    cfg: &TrainConfig,
    progress: &mut dyn FnMut(EpochReport),
) -> Result<TrainedModel, TrainError> {
    let started = Instant::now();
    cfg.validate()?;
    if data.is_empty() {
        return Err(TrainError::EmptyDataset);
    }
    if data.n_targets() == 0 {
        return Err(TrainError::AllMasked);
    }
    let mut rng = SeededRng::new(cfg.seed);
    let split = make_split(data, cfg.split, &mut rng)?;
    if split
        .train
        .iter()
        .all(|&i| !data.mask(i).iter().any(|&m| m))
    {
        return Err(TrainError::AllMasked);
    }
    let nf = data.n_features();
    let normalizer = Normalizer::fit(nf, split.train.iter().map(|&i| data.row(i)))?;
    let mut xn = vec![0.0; data.len() * nf];
    for (i, out) in xn.chunks_exact_mut(nf).enumerate() {
        normalizer.apply(data.row(i), out);
    }

    let mut model = AnyModel::init(kind, spec, nf, N_FINGERS, &mut rng)?;
    let n_params = model.params().len();
    let mut opt = OptimState::new(cfg.optimizer, n_params);
    let mut grad = vec![0.0; n_params];
    let mut scratch = model.new_scratch();
    let mut order = split.train.clone();
    let mut y = [0.0; N_FINGERS];
    let mut dy = [0.0; N_FINGERS];

    let has_val = !split.val.is_empty();
    let mut best_params = model.params().to_vec();
    let mut best_val = f64::INFINITY;
    let mut best_epoch = 0;
    let mut since_best = 0;
    let mut epochs_run = 0;
    let mut final_train_loss = f64::NAN;
    let mut stopped_early = false;

    for epoch in 1..=cfg.max_epochs {
        rng.shuffle(&mut order);
        let (mut loss_sum, mut loss_count) = (0.0, 0usize);
        for batch in order.chunks(cfg.batch_size) {
            let count: usize = batch
                .iter()
                .map(|&i| data.mask(i).iter().filter(|&&m| m).count())
                .sum();
            if count == 0 {
                continue;
            }
            let inv = 1.0 / count as f64;
            grad.fill(0.0);
            for &i in batch {
                let x = &xn[i * nf..(i + 1) * nf];
                model.predict_with(x, &mut y, &mut scratch);
                let (t, m) = (data.target(i), data.mask(i));
                for f in 0..N_FINGERS {
                    if m[f] {
                        let e = y[f] - t[f];
                        loss_sum += e * e;
                        dy[f] = 2.0 * e * inv;
                    } else {
                        dy[f] = 0.0;
                    }
                }
                model.backward(x, &dy, &mut scratch, &mut grad);
            }
            loss_count += count;
            opt.step(model.params_mut(), &grad);
        }
        let train_loss = loss_sum / loss_count.max(1) as f64;
        epochs_run = epoch;
        final_train_loss = train_loss;
        if !train_loss.is_finite() || model.params().iter().any(|p| !p.is_finite()) {
            return Err(TrainError::Diverged { epoch });
        }
        let val_loss = if has_val {
            let v = masked_mse(&model, data, &xn, &split.val, &mut scratch);
            if !v.is_finite() {
                return Err(TrainError::Diverged { epoch });
            }
            if v < best_val - cfg.min_delta {
                best_val = v;
                best_epoch = epoch;
                since_best = 0;
                best_params.copy_from_slice(model.params());
            } else {
                since_best += 1;
            }
            Some(v)
        } else {
            best_epoch = epoch;
            None
        };
        progress(EpochReport {
            epoch,
            max_epochs: cfg.max_epochs,
            train_loss,
            val_loss,
            best_epoch,
        });
        if has_val && since_best >= cfg.patience {
            stopped_early = epoch < cfg.max_epochs;
            break;
        }
    }
    if has_val {
        model.params_mut().copy_from_slice(&best_params);
    }
    let summary = TrainingSummary {
        kind,
        config: *cfg,
        epochs_run,
        best_epoch,
        stopped_early,
        final_train_loss,
        best_val_loss: has_val.then_some(best_val),
        n_train_windows: split.train.len(),
        n_val_windows: split.val.len(),
        n_train_trials: distinct_trials(data, &split.train),
        n_val_trials: distinct_trials(data, &split.val),
        duration_ms: u64::try_from(started.elapsed().as_millis()).unwrap_or(u64::MAX),
    };
    Ok(TrainedModel::new(
        model,
        *spec,
        normalizer,
        data.chain().clone(),
        summary,
    )?)
}
