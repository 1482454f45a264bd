//! Chain settings for a recording from another front end (4 to 16 channels, 200 Hz to a few
//! kHz): what the technician gave is used as given, what was left out takes a default that
//! fits the sample rate, and every such choice is said in words.
//!
//! * Band-pass upper edge: `min(450 Hz, 0.9 × Nyquist)`, i.e. 450 Hz from 1 kHz up and 90 Hz
//!   for an armband at 200 Hz (an edge at or above Nyquist cannot be designed).
//! * Window and step: 200 ms and 50 ms when those are whole numbers of samples at the rate,
//!   otherwise the nearest whole number of samples (12.5 samples rounds half away from zero: a 52 ms step at 250 Hz).
//! * Everything else ([`ChainConfig::default`]): 10 Hz lower edge, 4th order, notch at the mains.
//!
//! A configuration that cannot work is refused by [`ChainConfig::validate`]'s clear errors;
//! when a default took part, the error says which defaults were chosen.

use super::config::{ChainConfig, ChainSettings, ConfigError};

/// The default upper edge sits at this fraction of the Nyquist frequency when 450 Hz does not
/// fit below it.
pub const NYQUIST_FRACTION: f64 = 0.9;

/// What an importer knows of the front end, and the technician's choices (`None` = default).
#[derive(Debug, Clone, PartialEq)]
pub struct FrontEnd {
    /// EMG channels in the recording.
    pub channels: usize,
    /// Sample rate in Hz.
    pub sample_rate_hz: f64,
    /// Mains frequency to notch, 50 or 60 Hz.
    pub mains_hz: u32,
    /// Lower band-pass edge in Hz.
    pub band_low_hz: Option<f64>,
    /// Upper band-pass edge in Hz.
    pub band_high_hz: Option<f64>,
    /// Window length in ms.
    pub window_ms: Option<f64>,
    /// Step between feature vectors in ms.
    pub step_ms: Option<f64>,
}

/// A validated chain for a front end, and the defaults that were chosen for it.
#[derive(Debug, Clone, PartialEq)]
pub struct FrontEndChain {
    /// The configuration (as written into a session).
    pub config: ChainConfig,
    /// Its validated, designed form.
    pub settings: ChainSettings,
    /// One sentence per default that differs from [`ChainConfig::default`] because of the rate.
    pub choices: Vec<String>,
}

/// The band-pass upper edge used when none is given: `min(450, 0.9 × fs / 2)`.
pub fn default_band_high_hz(sample_rate_hz: f64) -> f64 {
    ChainConfig::default()
        .band_high_hz
        .min(NYQUIST_FRACTION * sample_rate_hz / 2.0)
}

/// `ms` rounded to a whole number of samples (at least `min`), back in ms.
fn whole_ms(ms: f64, fs: f64, min: f64) -> f64 {
    let samples = (ms * fs / 1000.0).round().max(min);
    samples * 1000.0 / fs
}

impl FrontEnd {
    /// The chain for this front end: given values as given, defaults fitted to the rate.
    pub fn chain(&self) -> Result<FrontEndChain, ConfigError> {
        let base = ChainConfig::default();
        let fs = self.sample_rate_hz;
        let mut choices = Vec::new();
        let band_high_hz = self.band_high_hz.unwrap_or_else(|| {
            let high = default_band_high_hz(fs);
            if high != base.band_high_hz {
                choices.push(format!(
                    "band-pass upper edge {high} Hz ({NYQUIST_FRACTION} x the Nyquist frequency \
                     {} Hz; the usual {} Hz needs a rate of {} Hz or more; --band-high sets it)",
                    fs / 2.0,
                    base.band_high_hz,
                    base.band_high_hz * 2.0 / NYQUIST_FRACTION
                ));
            }
            high
        });
        let mut timing = |given: Option<f64>, default: f64, min: f64, what: &str, flag: &str| {
            given.unwrap_or_else(|| {
                let ms = if fs.is_finite() && fs > 0.0 {
                    whole_ms(default, fs, min)
                } else {
                    default
                };
                if ms != default {
                    choices.push(format!(
                        "{what} {ms} ms ({} samples; {default} ms is not a whole number of \
                         samples at {fs} Hz; {flag} sets it)",
                        (ms * fs / 1000.0).round()
                    ));
                }
                ms
            })
        };
        let window_ms = timing(self.window_ms, base.window_ms, 2.0, "window", "--window-ms");
        let step_ms = timing(self.step_ms, base.step_ms, 1.0, "step", "--step-ms");
        let config = ChainConfig {
            channels: self.channels,
            sample_rate_hz: fs,
            mains_hz: self.mains_hz,
            band_low_hz: self.band_low_hz.unwrap_or(base.band_low_hz),
            band_high_hz,
            window_ms,
            step_ms,
            ..base
        };
        match config.validate() {
            Ok(settings) => Ok(FrontEndChain {
                config,
                settings,
                choices,
            }),
            Err(e) if choices.is_empty() => Err(e),
            Err(e) => Err(ConfigError::WithDefaults {
                chosen: choices.join("; "),
                source: Box::new(e),
            }),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn front_end(channels: usize, fs: f64) -> FrontEnd {
        FrontEnd {
            channels,
            sample_rate_hz: fs,
            mains_hz: 50,
            band_low_hz: None,
            band_high_hz: None,
            window_ms: None,
            step_ms: None,
        }
    }

    #[test]
    fn the_daemons_front_end_keeps_every_default_silently() {
        let c = front_end(12, 1000.0).chain().unwrap();
        assert_eq!(c.config, ChainConfig::default());
        assert!(c.choices.is_empty(), "{:?}", c.choices);
    }

    #[test]
    fn an_armband_at_200_hz_gets_an_edge_below_nyquist_and_says_so() {
        let c = front_end(8, 200.0).chain().unwrap();
        assert_eq!(c.config.band_high_hz, 90.0);
        assert_eq!((c.settings.window_len(), c.settings.step_len()), (40, 10));
        assert_eq!(c.choices.len(), 1, "{:?}", c.choices);
        assert!(c.choices[0].contains("90 Hz") && c.choices[0].contains("--band-high"));
    }

    #[test]
    fn at_250_hz_the_step_is_rounded_to_whole_samples() {
        let c = front_end(16, 250.0).chain().unwrap();
        assert_eq!((c.settings.window_len(), c.settings.step_len()), (50, 13));
        assert_eq!(c.config.step_ms, 52.0);
        assert_eq!(c.choices.len(), 2, "{:?}", c.choices);
    }

    #[test]
    fn impossible_configurations_are_clear_errors() {
        let mut f = front_end(8, 200.0);
        f.band_high_hz = Some(100.0);
        let e = f.chain().unwrap_err();
        assert!(matches!(e, ConfigError::AboveNyquist { .. }), "{e}");
        assert!(e.to_string().contains("Nyquist"), "{e}");
        // A lower edge above the chosen upper edge: the error names the chosen default.
        let mut f = front_end(8, 200.0);
        f.band_low_hz = Some(95.0);
        let e = f.chain().unwrap_err();
        assert!(matches!(e, ConfigError::WithDefaults { .. }), "{e}");
        let text = e.to_string();
        assert!(
            text.contains("band_low_hz = 95") && text.contains("90 Hz"),
            "{text}"
        );
        let e = front_end(0, 200.0).chain().unwrap_err();
        assert!(e.to_string().contains("channels = 0"), "{e}");
    }
}
