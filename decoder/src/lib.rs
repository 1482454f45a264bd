//! The sEMG decoder: the causal filter bank, windowing and the 96 amplitude features
//! (`dsp`), and the models that map features to per-finger force labels (`model`): ResDD and
//! the paper's baselines, training, calibration sessions and evaluation; [`fsio`] replaces
//! files atomically for every writer of the stack.
//!
//! It knows nothing of sockets, threads or clocks, so the same code runs in the daemon, in
//! offline evaluation, in replay and in the simulator, bit for bit.

pub mod dsp;
pub mod eval;
pub mod fsio;
pub mod model;
pub mod session;
