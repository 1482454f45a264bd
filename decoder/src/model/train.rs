//! The training loop: masked MSE plus the effort-ray penalty (see [`super::effort`]),
//! mini-batches, Adam or SGD, early stopping on held-out data.
//!
//! Deterministic: one ChaCha8 stream seeded from [`TrainConfig::seed`] makes the split, the
//! initial weights, and per epoch the shuffle and then the penalty's jittered efforts, in that
//! order; every sum runs in a fixed order on one thread. The same seed and the same data
//! therefore give bit-identical weights on the same machine. Each mini-batch runs as matrix
//! products ([`super::Trainable::forward_batch`]) whose kernel matrixmultiply picks at run time
//! (AVX-512, AVX2/FMA, SSE2, NEON): another processor may round differently in the last bits. Without the penalty no effort is drawn, so the plain
//! training's stream, and its weights, are those from before the penalty existed.

use std::time::Instant;

use super::any::AnyModel;
use super::batch::BatchWork;
use super::config::TrainConfig;
use super::dataset::{Dataset, N_FINGERS};
use super::effort::{ray_directions, EffortPenalty};
use super::effort_batch::RayBatch;
use super::error::TrainError;
use super::init::SeededRng;
use super::kind::ModelKind;
use super::normalizer::Normalizer;
use super::optim::OptimState;
use super::spec::ModelSpec;
use super::split::{make_split, Split};
use super::summary::TrainingSummary;
use super::trained::TrainedModel;
use super::traits::{Model, Trainable};

/// Progress after one epoch, passed to the caller's callback (which decides how to show it).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EpochReport {
    /// Epoch number, from 1.
    pub epoch: usize,
    /// The configured upper bound on epochs.
    pub max_epochs: usize,
    /// Mean masked squared error over the training windows during this epoch (running mean
    /// over its mini-batches, as the weights moved); the effort penalty is not included.
    pub train_loss: f64,
    /// The effort-ray penalty per unmasked target during this epoch, unweighted (None
    /// without the penalty).
    pub effort_penalty: Option<f64>,
    /// Masked MSE on the held-out windows after this epoch, plus the weighted effort penalty
    /// there when it is on (None without a split).
    pub val_loss: Option<f64>,
    /// Epoch with the best validation loss so far (the current one without a split).
    pub best_epoch: usize,
}

/// The dataset with every window's features normalized once, before the first epoch.
struct Normalized<'d> {
    data: &'d Dataset,
    xn: Vec<f64>,
    /// Per window, its ray's envelope edge (see [`EffortPenalty::beyond`]); empty when the
    /// penalty stops at full effort.
    edge: Vec<f64>,
}

impl<'d> Normalized<'d> {
    fn new(data: &'d Dataset, normalizer: &Normalizer, envelope: Option<&super::Envelope>) -> Self {
        let nf = data.n_features();
        let mut xn = vec![0.0; data.len() * nf];
        for (i, out) in xn.chunks_exact_mut(nf).enumerate() {
            normalizer.apply(data.row(i), out);
        }
        let edge = envelope.map_or_else(Vec::new, |e| {
            let k_max = super::verify::BEYOND_EFFORT;
            let mut scaled = vec![0.0; nf];
            (0..data.len())
                .map(|i| {
                    crate::eval::scale_features(data.row(i), k_max, &mut scaled);
                    k_max * e.scale_of(&scaled)
                })
                .collect()
        });
        Normalized { data, xn, edge }
    }

    /// Window `i`'s envelope edge along its ray (1 without one).
    fn edge(&self, i: usize) -> f64 {
        self.edge.get(i).copied().unwrap_or(1.0)
    }

    /// Normalized features of window `i`.
    fn x(&self, i: usize) -> &[f64] {
        let nf = self.data.n_features();
        &self.xn[i * nf..(i + 1) * nf]
    }

    /// Copies the normalized features of windows `idx` into the first rows of `out`, one
    /// window per row, and returns those rows.
    fn gather<'o>(&self, idx: &[usize], out: &'o mut [f64]) -> &'o [f64] {
        let nf = self.data.n_features();
        let rows = &mut out[..idx.len() * nf];
        for (row, &i) in rows.chunks_exact_mut(nf).zip(idx) {
            row.copy_from_slice(self.x(i));
        }
        rows
    }
}

/// What the mini-batch steps reuse, sized once for the largest batch: optimizer state, the
/// gradient, and the buffers of the batched forward and backward passes.
struct Workspace {
    opt: OptimState,
    grad: Vec<f64>,
    /// Windows per batch (validation runs in chunks of this size too).
    batch: usize,
    work: BatchWork,
    /// A batch's normalized features, one window per row.
    x: Vec<f64>,
    y: Vec<[f64; N_FINGERS]>,
    dy: Vec<[f64; N_FINGERS]>,
    /// The penalty's settings and buffers, when it is on.
    effort: Option<EffortWork>,
}

/// The effort penalty's settings and the batch's rays.
struct EffortWork {
    cfg: EffortPenalty,
    jitter: Vec<f64>,
    ks: Vec<f64>,
    rays: RayBatch,
}

impl Workspace {
    fn new(model: &AnyModel, cfg: &TrainConfig) -> Self {
        let n_params = model.params().len();
        let batch = cfg.batch_size;
        let ray_rows = cfg.effort.map_or(0, |e| batch * e.n_efforts());
        Workspace {
            opt: OptimState::new(cfg.optimizer, n_params),
            grad: vec![0.0; n_params],
            batch,
            work: model.new_batch_work(batch.max(ray_rows)),
            x: vec![0.0; batch * model.n_inputs()],
            y: vec![[0.0; N_FINGERS]; batch],
            dy: vec![[0.0; N_FINGERS]; batch],
            effort: cfg.effort.map(|e| EffortWork {
                cfg: e,
                jitter: vec![0.0; e.n_jitter()],
                ks: vec![0.0; e.n_efforts()],
                rays: RayBatch::new(model.n_inputs(), e.n_efforts(), batch),
            }),
        }
    }
}

/// The weights with the lowest validation loss so far, for early stopping.
struct Best {
    params: Vec<f64>,
    val: f64,
    epoch: usize,
    /// Epochs since the last improvement.
    since: usize,
}

impl Best {
    fn new(params: &[f64]) -> Self {
        Best {
            params: params.to_vec(),
            val: f64::INFINITY,
            epoch: 0,
            since: 0,
        }
    }

    /// Records an epoch's validation loss; keeps its weights if it beats the best by more
    /// than `min_delta`.
    fn observe(&mut self, epoch: usize, val: f64, params: &[f64], min_delta: f64) {
        if val < self.val - min_delta {
            self.val = val;
            self.epoch = epoch;
            self.since = 0;
            self.params.copy_from_slice(params);
        } else {
            self.since += 1;
        }
    }
}

/// How the epochs went, for the [`TrainingSummary`].
struct Outcome {
    epochs_run: usize,
    best_epoch: usize,
    stopped_early: bool,
    final_train_loss: f64,
    best_val_loss: Option<f64>,
}

/// Masked MSE of `model` over windows `idx` (batched forward passes, in chunks of a batch).
fn masked_mse(model: &AnyModel, set: &Normalized<'_>, idx: &[usize], ws: &mut Workspace) -> f64 {
    let (mut sum, mut count) = (0.0, 0usize);
    for chunk in idx.chunks(ws.batch) {
        let x = set.gather(chunk, &mut ws.x);
        let y = &mut ws.y[..chunk.len()];
        model.forward_batch(x, y.as_flattened_mut(), &mut ws.work);
        for (&i, y) in chunk.iter().zip(y.iter()) {
            let (t, m) = (set.data.target(i), set.data.mask(i));
            for f in 0..N_FINGERS {
                if m[f] {
                    let e = y[f] - t[f];
                    sum += e * e;
                    count += 1;
                }
            }
        }
    }
    if count == 0 {
        0.0
    } else {
        sum / count as f64
    }
}

/// The objective on the held-out windows `idx`: masked MSE, plus with the effort penalty its
/// weighted value per unmasked target at the strata's midpoints (fixed efforts, so epochs are
/// compared on the same points).
fn validation_loss(
    model: &AnyModel,
    set: &Normalized<'_>,
    idx: &[usize],
    ws: &mut Workspace,
) -> f64 {
    let mse = masked_mse(model, set, idx, ws);
    let Some(e) = ws.effort.as_mut() else {
        return mse;
    };
    e.jitter.fill(0.5);
    let (mut penalty, mut count) = (0.0, 0usize);
    for chunk in idx.chunks(ws.batch) {
        e.rays.clear();
        for &i in chunk {
            let (t, m) = (set.data.target(i), set.data.mask(i));
            count += m.iter().filter(|&&b| b).count();
            let dirs = ray_directions(t, m);
            if dirs.iter().any(|&d| d != 0.0) {
                e.cfg.efforts_to(&e.jitter, set.edge(i), &mut e.ks);
                e.rays.push(set.x(i), &dirs, &e.ks);
            }
        }
        penalty += e.rays.run(model, e.cfg.min_slope, &mut ws.work, None);
    }
    mse + e.cfg.weight * penalty / count.max(1) as f64
}

fn distinct_trials(data: &Dataset, idx: &[usize]) -> usize {
    let mut t: Vec<usize> = idx.iter().map(|&i| data.trial(i)).collect();
    t.sort_unstable();
    t.dedup();
    t.len()
}

/// Refuses what cannot be trained: invalid settings, no windows, no unmasked target.
fn check_inputs(data: &Dataset, cfg: &TrainConfig) -> Result<(), TrainError> {
    cfg.validate()?;
    if data.is_empty() {
        return Err(TrainError::EmptyDataset);
    }
    if data.n_targets() == 0 {
        return Err(TrainError::AllMasked);
    }
    Ok(())
}

/// Running sums of one epoch.
#[derive(Default)]
struct EpochSums {
    loss: f64,
    penalty: f64,
    count: usize,
}

/// Puts the gradient of the batch's masked MSE, plus the weighted effort penalty, into
/// `ws.grad` (`inv` is one over the batch's unmasked target count, which both are divided by)
/// and adds the batch's squared errors and penalty to `sums`.
fn batch_gradient(
    model: &AnyModel,
    set: &Normalized<'_>,
    batch: &[usize],
    inv: f64,
    ws: &mut Workspace,
    sums: &mut EpochSums,
    rng: &mut SeededRng,
) {
    ws.grad.fill(0.0);
    let x = set.gather(batch, &mut ws.x);
    let (y, dy) = (&mut ws.y[..batch.len()], &mut ws.dy[..batch.len()]);
    model.forward_batch(x, y.as_flattened_mut(), &mut ws.work);
    for ((&i, y), dy) in batch.iter().zip(y.iter()).zip(dy.iter_mut()) {
        let (t, m) = (set.data.target(i), set.data.mask(i));
        for f in 0..N_FINGERS {
            if m[f] {
                let e = y[f] - t[f];
                sums.loss += e * e;
                dy[f] = 2.0 * e * inv;
            } else {
                dy[f] = 0.0;
            }
        }
    }
    model.backward_batch(x, dy.as_flattened(), &mut ws.work, &mut ws.grad);
    if let Some(e) = ws.effort.as_mut() {
        e.rays.clear();
        for &i in batch {
            let dirs = ray_directions(set.data.target(i), set.data.mask(i));
            if dirs.iter().all(|&d| d == 0.0) {
                continue;
            }
            for u in e.jitter.iter_mut() {
                *u = rng.unit();
            }
            e.cfg.efforts_to(&e.jitter, set.edge(i), &mut e.ks);
            e.rays.push(set.x(i), &dirs, &e.ks);
        }
        let grad = Some((&mut ws.grad[..], e.cfg.weight * inv));
        sums.penalty += e.rays.run(model, e.cfg.min_slope, &mut ws.work, grad);
    }
}

/// One pass over the training windows in `order`, one optimizer step per mini-batch. Returns
/// the mean masked squared error seen during the pass and the mean effort penalty.
fn run_epoch(
    model: &mut AnyModel,
    set: &Normalized<'_>,
    order: &[usize],
    batch_size: usize,
    ws: &mut Workspace,
    rng: &mut SeededRng,
) -> (f64, f64) {
    let mut sums = EpochSums::default();
    for batch in order.chunks(batch_size) {
        let count: usize = batch
            .iter()
            .map(|&i| set.data.mask(i).iter().filter(|&&m| m).count())
            .sum();
        if count == 0 {
            continue;
        }
        batch_gradient(model, set, batch, 1.0 / count as f64, ws, &mut sums, rng);
        sums.count += count;
        ws.opt.step(model.params_mut(), &ws.grad);
    }
    let n = sums.count.max(1) as f64;
    (sums.loss / n, sums.penalty / n)
}

/// Runs epochs until `max_epochs` or early stopping, calling `progress` after each, and leaves
/// the kept weights in `model`: the best on the held-out windows, or the last without a split.
fn run_epochs(
    model: &mut AnyModel,
    set: &Normalized<'_>,
    split: &Split,
    cfg: &TrainConfig,
    rng: &mut SeededRng,
    progress: &mut dyn FnMut(EpochReport),
) -> Result<Outcome, TrainError> {
    let mut ws = Workspace::new(model, cfg);
    let mut order = split.train.clone();
    let has_val = !split.val.is_empty();
    let mut best = Best::new(model.params());
    let (mut epochs_run, mut final_train_loss, mut stopped_early) = (0, f64::NAN, false);
    for epoch in 1..=cfg.max_epochs {
        rng.shuffle(&mut order);
        let (train_loss, penalty) = run_epoch(model, set, &order, cfg.batch_size, &mut ws, rng);
        epochs_run = epoch;
        final_train_loss = train_loss;
        if !train_loss.is_finite() || model.params().iter().any(|p| !p.is_finite()) {
            return Err(TrainError::Diverged { epoch });
        }
        let val_loss = if has_val {
            let v = validation_loss(model, set, &split.val, &mut ws);
            if !v.is_finite() {
                return Err(TrainError::Diverged { epoch });
            }
            best.observe(epoch, v, model.params(), cfg.min_delta);
            Some(v)
        } else {
            best.epoch = epoch;
            None
        };
        progress(EpochReport {
            epoch,
            max_epochs: cfg.max_epochs,
            train_loss,
            effort_penalty: cfg.effort.map(|_| penalty),
            val_loss,
            best_epoch: best.epoch,
        });
        if has_val && best.since >= cfg.patience {
            stopped_early = epoch < cfg.max_epochs;
            break;
        }
    }
    if has_val {
        model.params_mut().copy_from_slice(&best.params);
    }
    Ok(Outcome {
        epochs_run,
        best_epoch: best.epoch,
        stopped_early,
        final_train_loss,
        best_val_loss: has_val.then_some(best.val),
    })
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
    check_inputs(data, cfg)?;
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
    // Every window of the calibration (the validation part too: it is the patient's signal all
    // the same) bounds what the model may see.
    let envelope = super::Envelope::fit(nf, (0..data.len()).map(|i| data.row(i)))?
        .with_patterns((0..data.len()).map(|i| (data.row(i), data.target(i))))?;
    let beyond = cfg.effort.is_some_and(|e| e.beyond > 0);
    let set = Normalized::new(data, &normalizer, beyond.then_some(&envelope));
    let mut model = AnyModel::init(kind, spec, nf, N_FINGERS, &mut rng)?;
    let outcome = run_epochs(&mut model, &set, &split, cfg, &mut rng, progress)?;
    let summary = TrainingSummary {
        kind,
        config: *cfg,
        epochs_run: outcome.epochs_run,
        best_epoch: outcome.best_epoch,
        stopped_early: outcome.stopped_early,
        final_train_loss: outcome.final_train_loss,
        best_val_loss: outcome.best_val_loss,
        n_train_windows: split.train.len(),
        n_val_windows: split.val.len(),
        n_train_trials: distinct_trials(data, &split.train),
        n_val_trials: distinct_trials(data, &split.val),
        duration_ms: u64::try_from(started.elapsed().as_millis()).unwrap_or(u64::MAX),
    };
    let trained = TrainedModel::new(model, *spec, normalizer, data.chain().clone(), summary)?
        .with_envelope(Some(envelope))?;
    let trained = super::rest::with_fitted_rest(trained, data, cfg.rest)?;
    // A direction no label taught is held at 0 (issue 25 item 4).
    Ok(trained.with_taught(super::Taught::of_dataset(data)))
}
