//! The chain's configuration ([`ChainConfig`], plain data, serde) and its validated, designed
//! form ([`ChainSettings`], immutable, shared by every channel and every [`super::Chain`]).

use super::design::{butter_bandpass, dc_highpass, iirnotch};
use super::features::FEATURES_PER_CHANNEL;
use super::sos::Sos;
use serde::{Deserialize, Serialize};
use std::sync::Arc;

/// Largest channel count accepted (the amplifier has 12; this is a sanity bound).
pub const MAX_CHANNELS: usize = 256;
/// Largest Butterworth order accepted: beyond it the band-pass sections near DC become
/// numerically fragile in f64 and nothing in sEMG needs them.
pub const MAX_ORDER: usize = 10;
/// Accepted notch quality factors.
pub const Q_RANGE: (f64, f64) = (0.5, 1000.0);
/// Most mains harmonics accepted besides the fundamental: each is a filter section, so the
/// field is bounded before anything is sized by it.
pub const MAX_HARMONICS: u32 = 20;
/// Longest window accepted, samples: the chain keeps two windows per channel, so this bounds
/// its memory (about 268 MB at [`MAX_CHANNELS`], 12.6 MB at 12 channels) whatever a file says.
pub const MAX_WINDOW_SAMPLES: usize = 65_536;

/// Which signal the features are computed on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum FeatureSignal {
    /// The full-wave rectified signal `|y|`, as the paper's pipeline does (default).
    #[default]
    Rectified,
    /// The filtered, unrectified signal `y`.
    Filtered,
}

/// The chain's configuration as a user writes it (TOML/JSON via serde). Missing fields take
/// the defaults below; unknown fields are refused. [`ChainConfig::validate`] checks it and
/// designs the filters.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ChainConfig {
    /// Number of EMG channels (default 12; the 3DC recordings have 10).
    pub channels: usize,
    /// Sample rate in Hz (default 1000).
    pub sample_rate_hz: f64,
    /// Lower band-pass edge in Hz (default 10).
    pub band_low_hz: f64,
    /// Upper band-pass edge in Hz (default 450); must be below Nyquist.
    pub band_high_hz: f64,
    /// Butterworth order of the band-pass (default 4, giving 4 second-order sections).
    pub bandpass_order: usize,
    /// Mains frequency to notch, 50 or 60 Hz (default 50).
    pub mains_hz: u32,
    /// Quality factor of each notch (default 30: 50 Hz notch about 1.7 Hz wide at -3 dB).
    pub notch_q: f64,
    /// Extra harmonics of the mains to notch: 0 = fundamental only (default), 2 = also 2f and 3f.
    pub mains_harmonics: u32,
    /// Cut-off of the first-order DC-removal high-pass in Hz (default 1); must be below
    /// `band_low_hz`.
    pub dc_cutoff_hz: f64,
    /// Window length in ms (default 200); must be a whole number of samples, at least 2.
    pub window_ms: f64,
    /// Step between feature vectors in ms (default 50); a whole number of samples, at most the
    /// window.
    pub step_ms: f64,
    /// Signal the features are computed on (default rectified).
    pub feature_signal: FeatureSignal,
}

impl Default for ChainConfig {
    fn default() -> Self {
        ChainConfig {
            channels: 12,
            sample_rate_hz: 1000.0,
            band_low_hz: 10.0,
            band_high_hz: 450.0,
            bandpass_order: 4,
            mains_hz: 50,
            notch_q: 30.0,
            mains_harmonics: 0,
            dc_cutoff_hz: 1.0,
            window_ms: 200.0,
            step_ms: 50.0,
            feature_signal: FeatureSignal::Rectified,
        }
    }
}

/// Why a [`ChainConfig`] was refused. Each message names the field and the allowed range.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ConfigError {
    /// `channels` outside 1..=MAX_CHANNELS.
    #[error("channels = {0}: must be between 1 and {MAX_CHANNELS}")]
    Channels(usize),
    /// `sample_rate_hz` not finite or not positive.
    #[error("sample_rate_hz = {0}: must be a finite number > 0")]
    SampleRate(f64),
    /// Band edges not finite or not `0 < low < high`.
    #[error("band_low_hz = {low}, band_high_hz = {high}: need 0 < band_low_hz < band_high_hz")]
    Band {
        /// Lower edge given.
        low: f64,
        /// Upper edge given.
        high: f64,
    },
    /// Upper band edge at or above Nyquist.
    #[error(
        "band_high_hz = {high} Hz: must be below the Nyquist frequency, {nyquist} Hz at sample_rate_hz = {fs}"
    )]
    AboveNyquist {
        /// Upper edge given.
        high: f64,
        /// fs / 2.
        nyquist: f64,
        /// Sample rate.
        fs: f64,
    },
    /// Butterworth order outside 1..=MAX_ORDER.
    #[error("bandpass_order = {0}: must be between 1 and {MAX_ORDER}")]
    Order(usize),
    /// Mains frequency not 50 or 60.
    #[error("mains_hz = {0}: must be 50 or 60")]
    Mains(u32),
    /// Notch Q outside its range.
    #[error("notch_q = {0}: must be between {lo} and {hi}", lo = Q_RANGE.0, hi = Q_RANGE.1)]
    NotchQ(f64),
    /// More harmonics than [`MAX_HARMONICS`].
    #[error("mains_harmonics = {0}: must be at most {MAX_HARMONICS}")]
    Harmonics(u32),
    /// A notch (fundamental or harmonic) at or above Nyquist.
    #[error(
        "mains_harmonics = {harmonics}: the notch at {freq} Hz is not below the Nyquist frequency, {nyquist} Hz at sample_rate_hz = {fs}"
    )]
    NotchAboveNyquist {
        /// Harmonics asked for.
        harmonics: u32,
        /// The offending notch frequency.
        freq: f64,
        /// fs / 2.
        nyquist: f64,
        /// Sample rate.
        fs: f64,
    },
    /// DC cut-off not finite, not positive or not below the band.
    #[error("dc_cutoff_hz = {cutoff}: must be > 0 and below band_low_hz = {low}")]
    DcCutoff {
        /// Cut-off given.
        cutoff: f64,
        /// Lower band edge.
        low: f64,
    },
    /// Window or step not a whole number of samples, or out of range.
    #[error("{field} = {ms} ms is {samples} samples at {fs} Hz: {why}")]
    Timing {
        /// `window_ms` or `step_ms`.
        field: &'static str,
        /// Value given.
        ms: f64,
        /// `ms * fs / 1000`.
        samples: f64,
        /// Sample rate.
        fs: f64,
        /// What is wrong.
        why: &'static str,
    },
    /// The configuration failed with defaults chosen for the front end's rate
    /// ([`super::FrontEnd`]); the message names them.
    #[error("{source} (defaults chosen for this front end: {chosen})")]
    WithDefaults {
        /// The defaults chosen, in words.
        chosen: String,
        /// Why the configuration was refused.
        source: Box<ConfigError>,
    },
}

/// Converts a duration in ms to a whole number of samples, or says why it is not one.
fn whole_samples(field: &'static str, ms: f64, fs: f64, min: usize) -> Result<usize, ConfigError> {
    let samples = ms * fs / 1000.0;
    let err = |why| ConfigError::Timing {
        field,
        ms,
        samples,
        fs,
        why,
    };
    if !samples.is_finite() || samples > MAX_WINDOW_SAMPLES as f64 {
        return Err(err("must be finite and at most 65536 samples"));
    }
    let rounded = samples.round();
    if (samples - rounded).abs() > 1e-9 * rounded.max(1.0) {
        return Err(err("must be a whole number of samples"));
    }
    if rounded < min as f64 {
        return Err(err(if min == 2 {
            "the window needs at least 2 samples"
        } else {
            "must be at least 1 sample"
        }));
    }
    Ok(rounded as usize)
}

impl ChainConfig {
    /// Checks every field and designs the filters. After this nothing in the chain can fail.
    pub fn validate(&self) -> Result<ChainSettings, ConfigError> {
        if self.channels == 0 || self.channels > MAX_CHANNELS {
            return Err(ConfigError::Channels(self.channels));
        }
        let fs = self.sample_rate_hz;
        if !fs.is_finite() || fs <= 0.0 {
            return Err(ConfigError::SampleRate(fs));
        }
        self.check_bandpass(fs)?;
        let notch_freqs = self.notch_freqs(fs)?;
        let (dc, low) = (self.dc_cutoff_hz, self.band_low_hz);
        if !(dc.is_finite() && dc > 0.0 && dc < low) {
            return Err(ConfigError::DcCutoff { cutoff: dc, low });
        }
        let (window_len, step_len) = self.window_and_step(fs)?;
        let (cascade, n_bandpass) = self.design(&notch_freqs);
        Ok(ChainSettings {
            inner: Arc::new(Inner {
                config: self.clone(),
                cascade,
                n_bandpass,
                notch_freqs,
                window_len,
                step_len,
            }),
        })
    }

    /// The band edges (positive, ordered, below Nyquist) and the Butterworth order.
    fn check_bandpass(&self, fs: f64) -> Result<(), ConfigError> {
        let nyquist = fs / 2.0;
        let (low, high) = (self.band_low_hz, self.band_high_hz);
        if !low.is_finite() || !high.is_finite() || low <= 0.0 || high <= low {
            return Err(ConfigError::Band { low, high });
        }
        if high >= nyquist {
            return Err(ConfigError::AboveNyquist { high, nyquist, fs });
        }
        if self.bandpass_order == 0 || self.bandpass_order > MAX_ORDER {
            return Err(ConfigError::Order(self.bandpass_order));
        }
        Ok(())
    }

    /// The notch centre frequencies, fundamental first, after checking the mains frequency,
    /// the quality factor and that every harmonic is below Nyquist.
    fn notch_freqs(&self, fs: f64) -> Result<Vec<f64>, ConfigError> {
        if self.mains_hz != 50 && self.mains_hz != 60 {
            return Err(ConfigError::Mains(self.mains_hz));
        }
        let q = self.notch_q;
        if !(q.is_finite() && q >= Q_RANGE.0 && q <= Q_RANGE.1) {
            return Err(ConfigError::NotchQ(q));
        }
        if self.mains_harmonics > MAX_HARMONICS {
            return Err(ConfigError::Harmonics(self.mains_harmonics));
        }
        let nyquist = fs / 2.0;
        let n_notches = self.mains_harmonics as usize + 1;
        let mut notch_freqs = Vec::with_capacity(n_notches);
        for h in 1..=n_notches {
            let freq = self.mains_hz as f64 * h as f64;
            if freq >= nyquist {
                return Err(ConfigError::NotchAboveNyquist {
                    harmonics: self.mains_harmonics,
                    freq,
                    nyquist,
                    fs,
                });
            }
            notch_freqs.push(freq);
        }
        Ok(notch_freqs)
    }

    /// Window and step lengths in samples (whole numbers, the step no longer than the window).
    fn window_and_step(&self, fs: f64) -> Result<(usize, usize), ConfigError> {
        let window_len = whole_samples("window_ms", self.window_ms, fs, 2)?;
        let step_len = whole_samples("step_ms", self.step_ms, fs, 1)?;
        if step_len > window_len {
            return Err(ConfigError::Timing {
                field: "step_ms",
                ms: self.step_ms,
                samples: step_len as f64,
                fs,
                why: "must not be longer than window_ms (samples would be skipped)",
            });
        }
        Ok((window_len, step_len))
    }

    /// The filter cascade in running order (DC section, band-pass sections, notches) and the
    /// number of band-pass sections in it. Only for a checked configuration.
    fn design(&self, notch_freqs: &[f64]) -> (Vec<Sos>, usize) {
        let fs = self.sample_rate_hz;
        let dc_section = dc_highpass(self.dc_cutoff_hz, fs);
        let bandpass =
            butter_bandpass(self.bandpass_order, self.band_low_hz, self.band_high_hz, fs);
        let notches: Vec<Sos> = notch_freqs
            .iter()
            .map(|&f| iirnotch(f, self.notch_q, fs))
            .collect();
        let mut cascade = Vec::with_capacity(1 + bandpass.len() + notches.len());
        cascade.push(dc_section);
        cascade.extend_from_slice(&bandpass);
        cascade.extend_from_slice(&notches);
        (cascade, bandpass.len())
    }
}

#[derive(Debug, PartialEq)]
struct Inner {
    config: ChainConfig,
    /// DC section, band-pass sections, notch sections, in the order they run.
    cascade: Vec<Sos>,
    n_bandpass: usize,
    notch_freqs: Vec<f64>,
    window_len: usize,
    step_len: usize,
}

/// A validated [`ChainConfig`] with its designed filter coefficients. Immutable; cloning is
/// cheap (shared), so every channel and every chain reads the same coefficients.
#[derive(Debug, Clone, PartialEq)]
pub struct ChainSettings {
    inner: Arc<Inner>,
}

impl ChainSettings {
    /// Same as [`ChainConfig::validate`]: checks `config` and designs the filters.
    pub fn try_new(config: &ChainConfig) -> Result<ChainSettings, ConfigError> {
        config.validate()
    }

    /// The configuration these settings were validated from.
    pub fn config(&self) -> &ChainConfig {
        &self.inner.config
    }
    /// Number of channels.
    pub fn n_channels(&self) -> usize {
        self.inner.config.channels
    }
    /// Window length in samples.
    pub fn window_len(&self) -> usize {
        self.inner.window_len
    }
    /// Samples between feature vectors.
    pub fn step_len(&self) -> usize {
        self.inner.step_len
    }
    /// Length of the feature vector: 8 per channel.
    pub fn n_features(&self) -> usize {
        FEATURES_PER_CHANNEL * self.n_channels()
    }
    /// Sample rate in Hz.
    pub fn sample_rate_hz(&self) -> f64 {
        self.inner.config.sample_rate_hz
    }
    /// Every section in the order a sample runs through them: DC, band-pass, notch(es).
    pub fn cascade(&self) -> &[Sos] {
        &self.inner.cascade
    }
    /// The DC-removal section.
    pub fn dc_section(&self) -> &Sos {
        &self.inner.cascade[0]
    }
    /// The band-pass sections (scipy's `butter(..., output='sos')` rows).
    pub fn bandpass_sections(&self) -> &[Sos] {
        &self.inner.cascade[1..1 + self.inner.n_bandpass]
    }
    /// The notch sections, fundamental first.
    pub fn notch_sections(&self) -> &[Sos] {
        &self.inner.cascade[1 + self.inner.n_bandpass..]
    }
    /// Centre frequencies of the notches in Hz, fundamental first.
    pub fn notch_freqs_hz(&self) -> &[f64] {
        &self.inner.notch_freqs
    }
    /// Number of feature rows a recording of `n_samples` samples yields (first row once the
    /// window is full, then one per step).
    pub fn n_windows(&self, n_samples: usize) -> usize {
        if n_samples < self.window_len() {
            0
        } else {
            (n_samples - self.window_len()) / self.step_len() + 1
        }
    }
    /// End (exclusive sample index, from the last reset) of the window of feature row `row`.
    pub fn window_end(&self, row: usize) -> usize {
        self.window_len() + row * self.step_len()
    }
}
