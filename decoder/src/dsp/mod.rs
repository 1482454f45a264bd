//! The causal sEMG signal chain: raw multi-channel samples in, the feature vector the model
//! reads out.
//!
//! Per channel, every sample passes, in this order:
//!
//! 1. **DC removal**: a first-order Butterworth high-pass (bilinear, prewarped) at
//!    [`ChainConfig::dc_cutoff_hz`] (default 1 Hz), i.e. `scipy.signal.butter(1, fc, 'highpass',
//!    fs=fs, output='sos')`. It is the classic DC blocker `y = g (x[n] - x[n-1]) + R y[n-1]` with
//!    `t = tan(pi fc / fs)`, `R = (1 - t) / (1 + t)`, `g = (1 + R) / 2`. The band-pass has zeros at
//!    DC as well; removing a large electrode offset first keeps it out of the high-Q sections.
//! 2. **Band-pass**: Butterworth of [`ChainConfig::bandpass_order`] between
//!    [`ChainConfig::band_low_hz`] and [`ChainConfig::band_high_hz`], designed here in code as
//!    second-order sections exactly as `scipy.signal.butter(order, [lo, hi], 'bandpass', fs=fs,
//!    output='sos')` does (analog prototype, low-pass to band-pass, bilinear transform with
//!    prewarping, `zpk2sos` with scipy's "nearest" pairing).
//! 3. **Notch** at the mains frequency (and optionally its harmonics), each a biquad equal to
//!    `scipy.signal.iirnotch(f, Q, fs)`.
//! 4. **Full-wave rectification** `|y|` (switchable off with [`FeatureSignal::Filtered`]).
//!
//! Every section runs in transposed direct form II with the same operation order as scipy's
//! `sosfilt`, so the filtered output equals `sosfilt` of the same sections to rounding. One
//! deliberate difference: every 64 samples, filter state below [`FLUSH_BELOW`] (1e-150) is set
//! to 0, so a silent channel never sinks into slow subnormal arithmetic.
//!
//! The last `window_len` processed values of each channel are kept in a ring buffer, contiguous
//! in memory. [`Chain::push`] only filters and windows; the 8 features of the paper's Table 1
//! are computed on request ([`Chain::features`]) per channel over the whole window `x[0..N]`
//! ending at the newest sample, in the order of [`FEATURE_NAMES`]:
//!
//! | name  | formula |
//! |-------|---------|
//! | RMS   | `sqrt(sum x[i]^2 / N)` |
//! | MAV   | `sum |x[i]| / N` |
//! | VAR   | `sum (x[i] - mean)^2 / (N - 1)` |
//! | SD    | `sqrt(VAR)` |
//! | INT   | `sum |x[i]|` |
//! | WL    | `sum_{i>=1} |x[i] - x[i-1]|` |
//! | DASDV | `sqrt(sum_{i>=1} (x[i] - x[i-1])^2 / (N - 1))` |
//! | DAMV  | `sum_{i>=1} |x[i] - x[i-1]| / (N - 1)` |
//!
//! The feature vector is channel-major: `[ch0 RMS, ch0 MAV, .., ch0 DAMV, ch1 RMS, ..]`, 8 values
//! per channel (96 for 12 channels).
//!
//! There is one feature computation: the offline path ([`batch_features`]) asks for the
//! features at every window end (every `step_len` samples once the first window is full), the
//! daemon at each of its ticks, and both run the same function over the same contiguous window,
//! so the same samples give the same features bit for bit. It equals the formulas above to
//! rounding (checked against numpy).
//!
//! Use: validate a [`ChainConfig`] once into [`ChainSettings`] (the only fallible step), build a
//! [`Chain`] from it, then [`Chain::push`] one multi-channel sample at a time; nothing after
//! validation allocates, returns a `Result` or panics on any input. Non-finite (or absurdly
//! large) samples are counted per channel in [`Faults`], reset that channel's filter state and
//! enter the filter as 0, so a channel recovers as soon as the bad samples leave the window.
//! [`batch_features`] runs the very same streaming code over a whole recording.
//!
//! The filter and feature loops are portable Rust compiled twice: for the baseline target and,
//! chosen at run time, for the widest instruction set on x86_64 ([`Simd`]; the `pulp` crate's
//! safe dispatch). At 4, 8, 12 and 16 channels the AVX2 build filters with an explicit
//! four-lane kernel instead (`cascade.rs`: the same operations per channel), and with AVX-512
//! the features take two channels per eight-lane vector (`feature_pairs_x86.rs`: each channel's
//! four lanes as before). Every build gives the same bits (no reassociation, no fused
//! multiply-add; tested), so the daemon, training and replay agree whichever machine runs them.

mod batch;
mod cascade;
mod chain;
mod config;
mod design;
mod faults;
#[cfg(target_arch = "x86_64")]
mod feature_pairs_x86;
mod feature_passes;
mod features;
mod front_end;
pub mod npy;
mod simd;
mod sos;

pub use batch::{batch_features, batch_filtered, try_batch_features, BatchError, FeatureMatrix};
pub use chain::{Chain, FLUSH_BELOW};
pub use config::{
    ChainConfig, ChainSettings, ConfigError, FeatureSignal, MAX_CHANNELS, MAX_HARMONICS, MAX_ORDER,
    MAX_WINDOW_SAMPLES, Q_RANGE,
};
pub use design::{butter_bandpass, dc_highpass, iirnotch};
pub use faults::{Faults, MAX_ABS_SAMPLE};
pub use features::{
    multichannel_features_into, multichannel_features_with, multichannel_rectified_features_with,
    window_features, FEATURES_PER_CHANNEL, FEATURE_NAMES, RMS_FEATURE,
};
pub use front_end::{default_band_high_hz, FrontEnd, FrontEndChain, NYQUIST_FRACTION};
pub use simd::Simd;
pub use sos::Sos;
