//! The streaming chain: per-channel filter state, the window ring buffer and the features.

use super::cascade::run_cascade;
use super::config::{ChainSettings, FeatureSignal};
use super::faults::{Faults, MAX_ABS_SAMPLE};
use super::features::strided_features_into;
use super::simd::Simd;

/// Filter state smaller than this is set to exactly 0 (every `FLUSH_EVERY` samples). Without
/// it a silent channel's IIR state decays into subnormal numbers and stays there in a limit
/// cycle, which makes every later operation on it slow (2x on this machine, far worse on some
/// CPUs). 1e-150 keeps squares in the features normal too; the change to the output is below
/// 1e-150 in absolute terms.
pub const FLUSH_BELOW: f64 = 1e-150;
/// How often (in samples) tiny filter state is flushed; a power of two.
const FLUSH_EVERY: u64 = 64;

/// The streaming signal chain for all channels (see the module docs for the stages).
///
/// Built once from [`ChainSettings`] (all memory is allocated then), fed one multi-channel
/// sample at a time with [`Chain::push`], which only filters and windows. Features are computed
/// on request ([`Chain::features`]) over the whole window ending at the newest sample: the one
/// feature computation, which the offline path requests at every window end (every `step_len`
/// samples once the first window is full; `push` says when) and the daemon at its ticks.
/// Nothing here allocates, returns a `Result` or panics after construction.
///
/// Layout: filter state is section-major (`[section][channel]`), so each section runs over all
/// channels at once, lanes being channels (`cascade.rs`); every channel still sees exactly the
/// operations, in the order, of scipy's `sosfilt`.
#[derive(Debug, Clone)]
pub struct Chain {
    settings: ChainSettings,
    n_channels: usize,
    window_len: usize,
    step_len: usize,
    rectify: bool,
    /// First and second delay register of every section, `[section][channel]`.
    z0: Vec<f64>,
    z1: Vec<f64>,
    /// Per channel `2 * window_len` slots, every value written twice (at `head` and
    /// `head + window_len`) so the window `[head, head + window_len)` is always contiguous.
    ring: Vec<f64>,
    /// Slot of the oldest sample of the window (= where the next sample goes).
    head: usize,
    /// Samples pushed since the last reset.
    count: u64,
    /// Window ends reached since the last reset.
    emitted: u64,
    /// Samples still to push before the next window end.
    until_features: usize,
    /// The features last computed ([`Chain::features`]).
    features: Vec<f64>,
    /// The current sample of every channel on its way through the cascade; after it, the
    /// filtered output.
    last_filtered: Vec<f64>,
    faults: Faults,
    /// The build of the filter and feature loops that runs (same bits either way).
    simd: Simd,
}

impl Chain {
    /// A chain in reset state for `settings` (which it shares, not copies), its loops built for
    /// the instruction set detected at run time ([`Simd::detect`]).
    pub fn new(settings: &ChainSettings) -> Chain {
        Chain::with_simd(settings, Simd::detect())
    }

    /// [`Chain::new`] with the build of the inner loops chosen by `simd`; every choice gives
    /// the same bits ([`Simd::portable`] is the reference the tests compare against).
    pub fn with_simd(settings: &ChainSettings, simd: Simd) -> Chain {
        let n_channels = settings.n_channels();
        let n_state = n_channels * settings.cascade().len();
        let window_len = settings.window_len();
        Chain {
            settings: settings.clone(),
            n_channels,
            window_len,
            step_len: settings.step_len(),
            rectify: settings.config().feature_signal == FeatureSignal::Rectified,
            z0: vec![0.0; n_state],
            z1: vec![0.0; n_state],
            ring: vec![0.0; n_channels * 2 * window_len],
            head: 0,
            count: 0,
            emitted: 0,
            until_features: window_len,
            features: vec![0.0; settings.n_features()],
            last_filtered: vec![0.0; n_channels],
            faults: Faults::new(n_channels, window_len),
            simd,
        }
    }

    /// Back to the state right after [`Chain::new`]: filter state, window, features and fault
    /// counts cleared. Needed between recordings joined end to end.
    pub fn reset(&mut self) {
        self.z0.fill(0.0);
        self.z1.fill(0.0);
        self.ring.fill(0.0);
        self.head = 0;
        self.count = 0;
        self.emitted = 0;
        self.until_features = self.window_len;
        self.features.fill(0.0);
        self.last_filtered.fill(0.0);
        self.faults.clear();
    }

    /// Zeroes the filter state of one channel (after a bad sample).
    fn reset_channel_state(&mut self, ch: usize) {
        let n = self.n_channels;
        for s in 0..self.settings.cascade().len() {
            self.z0[s * n + ch] = 0.0;
            self.z1[s * n + ch] = 0.0;
        }
    }

    /// The filter half of [`Chain::push`]: validates the sample, runs the cascade and leaves the
    /// filtered values in `last_filtered`; the window and features are not touched. Used alone
    /// by [`super::batch_filtered`].
    pub(crate) fn filter_sample(&mut self, sample: &[f64]) {
        let n = self.n_channels;
        self.count += 1;
        self.faults.set_now(self.count);
        let clean = sample.len() == n && sample.iter().all(|v| v.abs() <= MAX_ABS_SAMPLE);
        if clean {
            self.last_filtered.copy_from_slice(sample);
        } else {
            self.take_bad_sample(sample);
        }

        let (work, z0, z1) = (&mut self.last_filtered[..n], &mut self.z0, &mut self.z1);
        let cascade = self.settings.cascade();
        run_cascade(self.simd, cascade, work, z0, z1);
        if self.count.is_multiple_of(FLUSH_EVERY) {
            for z in self.z0.iter_mut().chain(self.z1.iter_mut()) {
                if z.abs() < FLUSH_BELOW {
                    *z = 0.0;
                }
            }
        }
    }

    /// A sample of the wrong length or with a bad value: counted, each bad channel's filter
    /// state reset and the value filtered as 0 (see [`Chain::push`]).
    #[cold]
    fn take_bad_sample(&mut self, sample: &[f64]) {
        let n = self.n_channels;
        if sample.len() != n {
            self.faults.record_wrong_length();
        }
        for ch in 0..n {
            let raw = sample.get(ch).copied().unwrap_or(f64::NAN);
            self.last_filtered[ch] = if raw.abs() <= MAX_ABS_SAMPLE {
                raw
            } else {
                // NaN fails the comparison above and lands here too.
                if raw.is_finite() {
                    self.faults.record_out_of_range(ch);
                } else {
                    self.faults.record_non_finite(ch);
                }
                self.reset_channel_state(ch);
                0.0
            };
        }
    }

    /// Feeds one multi-channel sample (one value per channel, in channel order): filters it and
    /// puts it in the window. Returns true when the window ends at a step (every `step_len`
    /// samples once the first window is full): where the offline path takes its feature rows.
    /// No features are computed here.
    ///
    /// A NaN, infinite or absurdly large value is counted in [`Chain::faults`], resets that
    /// channel's filter state and is filtered as 0. A slice of the wrong length is counted too;
    /// missing channels are treated as non-finite, extra values are ignored.
    pub fn push(&mut self, sample: &[f64]) -> bool {
        self.filter_sample(sample);
        let work = &self.last_filtered[..self.n_channels];
        let w = self.window_len;
        let head = self.head;
        for (ch, &y) in work.iter().enumerate() {
            let v = if self.rectify { y.abs() } else { y };
            let base = ch * 2 * w;
            self.ring[base + head] = v;
            self.ring[base + head + w] = v;
        }
        self.head = if head + 1 == w { 0 } else { head + 1 };
        self.until_features -= 1;
        if self.until_features == 0 {
            self.until_features = self.step_len;
            self.emitted += 1;
            true
        } else {
            false
        }
    }

    /// The features of the window that ends at the newest sample, computed now over the whole
    /// window: channel-major, 8 per channel in [`super::FEATURE_NAMES`] order. The one feature
    /// computation of the crate: the offline path ([`super::batch_features`]) calls it at every
    /// window end, the daemon at each tick, so both get the same bits for the same samples.
    /// Meaningful once [`Chain::samples_seen`] reaches the window length (the older part of the
    /// window is zeros before). No allocation.
    pub fn features(&mut self) -> &[f64] {
        let (w, head) = (self.window_len, self.head);
        let (ring, features) = (&self.ring, &mut self.features);
        let signal = if self.rectify {
            FeatureSignal::Rectified
        } else {
            FeatureSignal::Filtered
        };
        strided_features_into(self.simd, ring, 2 * w, head, w, signal, features);
        &self.features
    }

    /// The features the last [`Chain::features`] call computed (zeros before the first), without
    /// computing anything.
    pub fn last_features(&self) -> &[f64] {
        &self.features
    }

    /// Filtered value (after the notch, before rectification) of each channel for the last
    /// pushed sample.
    pub fn last_filtered(&self) -> &[f64] {
        &self.last_filtered
    }

    /// Fault counters since the last reset.
    pub fn faults(&self) -> &Faults {
        &self.faults
    }

    /// Samples pushed since the last reset.
    pub fn samples_seen(&self) -> u64 {
        self.count
    }

    /// Window ends ([`Chain::push`] returned true) since the last reset.
    pub fn vectors_emitted(&self) -> u64 {
        self.emitted
    }

    /// The settings this chain runs with.
    pub fn settings(&self) -> &ChainSettings {
        &self.settings
    }
}
