//! The streaming chain: per-channel filter state, the window ring buffer and the features.

use super::config::{ChainSettings, FeatureSignal};
use super::faults::{Faults, MAX_ABS_SAMPLE};
use super::features::{features_of_split, FEATURES_PER_CHANNEL};

/// The streaming signal chain for all channels (see the module docs for the stages).
///
/// Built once from [`ChainSettings`] (all memory is allocated then), fed one multi-channel
/// sample at a time with [`Chain::push`]. Every `step_len` samples, once the first window is
/// full, a new feature vector is ready in [`Chain::features`]. Nothing here allocates, returns a
/// `Result` or panics after construction.
#[derive(Debug, Clone)]
pub struct Chain {
    settings: ChainSettings,
    n_channels: usize,
    n_sections: usize,
    window_len: usize,
    step_len: usize,
    rectify: bool,
    /// Delay registers, `n_channels * n_sections`, channel-major.
    state: Vec<[f64; 2]>,
    /// Last `window_len` processed values per channel, channel-major; `head` is the slot the
    /// next sample goes to, which is also the oldest sample once the ring is full.
    ring: Vec<f64>,
    head: usize,
    /// Samples pushed since the last reset.
    count: u64,
    /// Feature vectors produced since the last reset.
    emitted: u64,
    features: Vec<f64>,
    last_filtered: Vec<f64>,
    faults: Faults,
}

impl Chain {
    /// A chain in reset state for `settings` (which it shares, not copies).
    pub fn new(settings: &ChainSettings) -> Chain {
        let n_channels = settings.n_channels();
        let n_sections = settings.cascade().len();
        let window_len = settings.window_len();
        Chain {
            settings: settings.clone(),
            n_channels,
            n_sections,
            window_len,
            step_len: settings.step_len(),
            rectify: settings.config().feature_signal == FeatureSignal::Rectified,
            state: vec![[0.0; 2]; n_channels * n_sections],
            ring: vec![0.0; n_channels * window_len],
            head: 0,
            count: 0,
            emitted: 0,
            features: vec![0.0; settings.n_features()],
            last_filtered: vec![0.0; n_channels],
            faults: Faults::new(n_channels, window_len),
        }
    }

    /// Back to the state right after [`Chain::new`]: filter state, window, features and fault
    /// counts cleared. Needed between recordings joined end to end.
    pub fn reset(&mut self) {
        self.state.fill([0.0; 2]);
        self.ring.fill(0.0);
        self.head = 0;
        self.count = 0;
        self.emitted = 0;
        self.features.fill(0.0);
        self.last_filtered.fill(0.0);
        self.faults.clear();
    }

    /// Feeds one multi-channel sample (one value per channel, in channel order). Returns true
    /// when a new feature vector is ready in [`Chain::features`].
    ///
    /// A NaN, infinite or absurdly large value is counted in [`Chain::faults`], resets that
    /// channel's filter state and is filtered as 0. A slice of the wrong length is counted too;
    /// missing channels are treated as non-finite, extra values are ignored.
    pub fn push(&mut self, sample: &[f64]) -> bool {
        if sample.len() != self.n_channels {
            self.faults.record_wrong_length();
        }
        self.faults.tick();
        let cascade = self.settings.cascade();
        let w = self.window_len;
        for ch in 0..self.n_channels {
            let state = &mut self.state[ch * self.n_sections..(ch + 1) * self.n_sections];
            let raw = sample.get(ch).copied().unwrap_or(f64::NAN);
            let x = if !raw.is_finite() {
                self.faults.record_non_finite(ch);
                state.fill([0.0; 2]);
                0.0
            } else if raw.abs() > MAX_ABS_SAMPLE {
                self.faults.record_out_of_range(ch);
                state.fill([0.0; 2]);
                0.0
            } else {
                raw
            };
            let mut y = x;
            for (section, z) in cascade.iter().zip(state.iter_mut()) {
                y = section.step(z, y);
            }
            self.last_filtered[ch] = y;
            self.ring[ch * w + self.head] = if self.rectify { y.abs() } else { y };
        }
        self.head += 1;
        if self.head == w {
            self.head = 0;
        }
        self.count += 1;
        let w64 = w as u64;
        if self.count >= w64 && (self.count - w64).is_multiple_of(self.step_len as u64) {
            self.compute_features();
            self.emitted += 1;
            true
        } else {
            false
        }
    }

    fn compute_features(&mut self) {
        let w = self.window_len;
        for ch in 0..self.n_channels {
            let ring = &self.ring[ch * w..(ch + 1) * w];
            let (newer, older) = ring.split_at(self.head);
            let out =
                &mut self.features[ch * FEATURES_PER_CHANNEL..(ch + 1) * FEATURES_PER_CHANNEL];
            features_of_split(older, newer, out);
        }
    }

    /// The latest feature vector, channel-major, 8 per channel in [`super::FEATURE_NAMES`]
    /// order. All zeros until the first window is full.
    pub fn features(&self) -> &[f64] {
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

    /// Feature vectors produced since the last reset.
    pub fn vectors_emitted(&self) -> u64 {
        self.emitted
    }

    /// The settings this chain runs with.
    pub fn settings(&self) -> &ChainSettings {
        &self.settings
    }
}
