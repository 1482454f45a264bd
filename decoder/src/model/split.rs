//! The held-out split for early stopping.

use std::collections::BTreeMap;

use super::config::ValidationSplit;
use super::dataset::{Dataset, N_FINGERS};
use super::error::TrainError;
use super::init::SeededRng;

/// Window indices for training and validation.
pub(crate) struct Split {
    pub(crate) train: Vec<usize>,
    pub(crate) val: Vec<usize>,
}

/// The label signature of a window: its targets and mask, bit-exact.
fn label_key(d: &Dataset, i: usize) -> [u64; N_FINGERS] {
    let (t, m) = (d.target(i), d.mask(i));
    std::array::from_fn(|f| if m[f] { t[f].to_bits() } else { u64::MAX })
}

/// Splits the windows of `d` for early stopping as `how` says (see [`ValidationSplit`]).
pub(crate) fn make_split(
    d: &Dataset,
    how: ValidationSplit,
    rng: &mut SeededRng,
) -> Result<Split, TrainError> {
    match how {
        ValidationSplit::None => Ok(Split {
            train: (0..d.len()).collect(),
            val: Vec::new(),
        }),
        ValidationSplit::Window { fraction } => window_split(d.len(), fraction, rng),
        ValidationSplit::TrialTail { fraction } => trial_tail_split(d, fraction),
        ValidationSplit::Trial { fraction } => trial_split(d, fraction, rng),
    }
}

/// Random windows: `fraction` of the `n` windows (at least one, never all) held out.
fn window_split(n: usize, fraction: f64, rng: &mut SeededRng) -> Result<Split, TrainError> {
    if n < 2 {
        return Err(TrainError::Split(format!(
            "need at least 2 windows, have {n}"
        )));
    }
    let mut idx: Vec<usize> = (0..n).collect();
    rng.shuffle(&mut idx);
    let n_val = ((fraction * n as f64).round() as usize).clamp(1, n - 1);
    let mut val = idx[..n_val].to_vec();
    let mut train = idx[n_val..].to_vec();
    val.sort_unstable();
    train.sort_unstable();
    Ok(Split { train, val })
}

/// The last `fraction` of every trial's windows held out, the windows that overlap both parts
/// dropped. A trial too short for that (no window to hold out, or none left to train on) trains
/// whole; an error only when no trial is long enough.
fn trial_tail_split(d: &Dataset, fraction: f64) -> Result<Split, TrainError> {
    let chain = d.chain();
    // Windows whose samples overlap a given window: ceil(window / step) - 1.
    let gap = ((chain.window_ms / chain.step_ms).ceil() as usize).saturating_sub(1);
    let held = |m: usize| {
        let n_val = (fraction * m as f64).round() as usize;
        (n_val > 0 && n_val + gap < m).then_some(n_val)
    };
    let mut by_trial: BTreeMap<usize, Vec<usize>> = BTreeMap::new();
    for i in 0..d.len() {
        by_trial.entry(d.trial(i)).or_default().push(i);
    }
    let (mut train, mut val) = (Vec::new(), Vec::new());
    for idx in by_trial.values() {
        let m = idx.len();
        match held(m) {
            Some(n_val) => {
                train.extend_from_slice(&idx[..m - n_val - gap]);
                val.extend_from_slice(&idx[m - n_val..]);
            }
            None => train.extend_from_slice(idx),
        }
    }
    if val.is_empty() {
        let longest = by_trial.values().map(Vec::len).max().unwrap_or(0);
        let needed = (1..=10_000)
            .find(|&m| held(m).is_some())
            .unwrap_or(usize::MAX);
        return Err(TrainError::Split(format!(
            "no trial is long enough to hold out its last {fraction} plus {gap} overlapping \
             windows: the longest has {longest} windows, {needed} are needed (use the trial \
             split, or none)"
        )));
    }
    train.sort_unstable();
    val.sort_unstable();
    Ok(Split { train, val })
}

/// Whole trials held out: about `fraction` of them, never the last trial of a label.
fn trial_split(d: &Dataset, fraction: f64, rng: &mut SeededRng) -> Result<Split, TrainError> {
    let held = held_out_trials(d, fraction, rng)?;
    let (mut train, mut val) = (Vec::new(), Vec::new());
    for i in 0..d.len() {
        if held.binary_search(&d.trial(i)).is_ok() {
            val.push(i);
        } else {
            train.push(i);
        }
    }
    Ok(Split { train, val })
}

/// The trials [`trial_split`] holds out, sorted: trials in random order, each taken while the
/// label of its first window keeps another trial in training, until `fraction` are taken.
fn held_out_trials(
    d: &Dataset,
    fraction: f64,
    rng: &mut SeededRng,
) -> Result<Vec<usize>, TrainError> {
    // Trial -> label of its first window; label -> number of trials still in training.
    let mut trial_label: BTreeMap<usize, [u64; N_FINGERS]> = BTreeMap::new();
    for i in 0..d.len() {
        trial_label
            .entry(d.trial(i))
            .or_insert_with(|| label_key(d, i));
    }
    let mut left: BTreeMap<[u64; N_FINGERS], usize> = BTreeMap::new();
    for key in trial_label.values() {
        *left.entry(*key).or_insert(0) += 1;
    }
    let mut trials: Vec<usize> = trial_label.keys().copied().collect();
    let n_trials = trials.len();
    let want = ((fraction * n_trials as f64).round() as usize).max(1);
    rng.shuffle(&mut trials);
    let mut held = Vec::new();
    for t in trials {
        if held.len() == want {
            break;
        }
        let c = left
            .get_mut(&trial_label[&t])
            .expect("every label was counted");
        if *c > 1 {
            *c -= 1;
            held.push(t);
        }
    }
    if held.is_empty() {
        return Err(TrainError::Split(format!(
            "no trial can be held out without losing a label ({n_trials} trials, every \
             finger/direction has a single trial): record repetitions, or hold out the \
             end of each trial (trial-tail split)"
        )));
    }
    held.sort_unstable();
    Ok(held)
}
