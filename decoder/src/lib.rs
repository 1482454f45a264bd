//! The sEMG decoder: the causal filter bank, windowing and the 96 amplitude features
//! (`dsp`), and the models that map features to per-finger force labels (`model`): ResDD and
//! the paper's baselines, training, calibration sessions and evaluation; [`fsio`] replaces
//! files atomically for every writer of the stack.
//!
//! It knows nothing of sockets, threads or clocks, so the same code runs in the daemon, in
//! offline evaluation, in replay and in the simulator, bit for bit.
//!
//! Module order (each module uses only those to its left; nothing points back):
//!
//! ```text
//! dsp  <-  model  <-  session  <-  eval
//! ```
//!
//! - `dsp`: the signal chain and the feature layout (`FEATURES_PER_CHANNEL`, `FEATURE_NAMES`);
//!   uses nothing else of the crate.
//! - `model`: models, training and model files, on feature vectors from `dsp`.
//! - `session`: calibration sessions cut into labelled feature windows (`dsp`), which turn into
//!   a training set (`model::Dataset`).
//! - `eval`: metrics, and `evaluate_model`, which runs a `model` on a `session`'s windows.
//!
//! Inside `model`: `summary` (what training did) <- `trained` (model + normalizer + chain)
//! <- `train` (the loop that makes one) and `file` (reads and writes one).

pub mod dsp;
pub mod eval;
pub mod fsio;
pub mod model;
pub mod session;
pub mod textfile;
