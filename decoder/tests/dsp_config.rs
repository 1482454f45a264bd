//! Validation of the chain configuration: defaults, the 10-channel and 200 Hz set-ups, and a
//! clear error naming the field and the limit for every bad value.

use decoder::dsp::{
    ChainConfig, ConfigError, FeatureSignal, FEATURE_NAMES, MAX_HARMONICS, MAX_WINDOW_SAMPLES,
};

fn err(cfg: ChainConfig) -> (ConfigError, String) {
    let e = cfg.validate().expect_err("configuration must be refused");
    let msg = e.to_string();
    (e, msg)
}

#[test]
fn defaults_match_the_design() {
    let cfg = ChainConfig::default();
    assert_eq!(cfg.channels, 12);
    assert_eq!(cfg.sample_rate_hz, 1000.0);
    assert_eq!((cfg.band_low_hz, cfg.band_high_hz), (10.0, 450.0));
    assert_eq!(cfg.bandpass_order, 4);
    assert_eq!(cfg.mains_hz, 50);
    assert_eq!(cfg.notch_q, 30.0);
    assert_eq!(cfg.mains_harmonics, 0);
    assert_eq!(cfg.feature_signal, FeatureSignal::Rectified);
    let s = cfg.validate().expect("defaults are valid");
    assert_eq!(s.n_channels(), 12);
    assert_eq!(s.window_len(), 200);
    assert_eq!(s.step_len(), 50);
    assert_eq!(s.n_features(), 96);
    assert_eq!(s.bandpass_sections().len(), 4);
    assert_eq!(s.notch_sections().len(), 1);
    assert_eq!(s.cascade().len(), 6);
    assert_eq!(s.notch_freqs_hz(), &[50.0]);
    assert_eq!(s.config(), &cfg);
    assert_eq!(
        FEATURE_NAMES,
        ["RMS", "MAV", "VAR", "SD", "INT", "WL", "DASDV", "DAMV"]
    );
    assert_eq!(s.n_windows(199), 0);
    assert_eq!(s.n_windows(200), 1);
    assert_eq!(s.n_windows(1000), 17);
    assert_eq!(s.window_end(2), 300);
}

#[test]
fn ten_channels_and_200_hz_work() {
    let s = ChainConfig {
        channels: 10,
        ..ChainConfig::default()
    }
    .validate()
    .expect("10 channels");
    assert_eq!(s.n_features(), 80);

    let s = ChainConfig {
        sample_rate_hz: 200.0,
        band_high_hz: 90.0,
        ..ChainConfig::default()
    }
    .validate()
    .expect("200 Hz with a 10-90 Hz band");
    assert_eq!((s.window_len(), s.step_len()), (40, 10));
}

#[test]
fn band_above_nyquist_is_refused_naming_the_limit() {
    let (e, msg) = err(ChainConfig {
        sample_rate_hz: 200.0,
        ..ChainConfig::default()
    });
    assert!(matches!(e, ConfigError::AboveNyquist { .. }), "{e:?}");
    assert!(msg.contains("band_high_hz = 450"), "{msg}");
    assert!(msg.contains("Nyquist frequency, 100 Hz"), "{msg}");

    let (e, _) = err(ChainConfig {
        band_high_hz: 500.0,
        ..ChainConfig::default()
    });
    assert!(
        matches!(e, ConfigError::AboveNyquist { .. }),
        "exactly Nyquist: {e:?}"
    );

    for (low, high) in [(0.0, 450.0), (100.0, 50.0), (f64::NAN, 450.0), (10.0, 10.0)] {
        let (e, msg) = err(ChainConfig {
            band_low_hz: low,
            band_high_hz: high,
            ..ChainConfig::default()
        });
        assert!(matches!(e, ConfigError::Band { .. }), "{e:?}");
        assert!(msg.contains("band_low_hz"), "{msg}");
    }
}

#[test]
fn other_fields_are_checked() {
    let (e, msg) = err(ChainConfig {
        channels: 0,
        ..ChainConfig::default()
    });
    assert_eq!(e, ConfigError::Channels(0));
    assert!(msg.contains("channels = 0"), "{msg}");

    for fs in [0.0, -1000.0, f64::INFINITY] {
        let (e, _) = err(ChainConfig {
            sample_rate_hz: fs,
            ..ChainConfig::default()
        });
        assert!(matches!(e, ConfigError::SampleRate(_)), "{e:?}");
    }

    for order in [0, 11] {
        let (e, msg) = err(ChainConfig {
            bandpass_order: order,
            ..ChainConfig::default()
        });
        assert_eq!(e, ConfigError::Order(order));
        assert!(msg.contains("between 1 and 10"), "{msg}");
    }

    let (e, msg) = err(ChainConfig {
        mains_hz: 55,
        ..ChainConfig::default()
    });
    assert_eq!(e, ConfigError::Mains(55));
    assert!(msg.contains("50 or 60"), "{msg}");

    for q in [0.0, -3.0, f64::NAN, 1e6] {
        let (e, msg) = err(ChainConfig {
            notch_q: q,
            ..ChainConfig::default()
        });
        assert!(matches!(e, ConfigError::NotchQ(_)), "{e:?}");
        assert!(msg.contains("notch_q"), "{msg}");
    }

    let (e, msg) = err(ChainConfig {
        dc_cutoff_hz: 10.0,
        ..ChainConfig::default()
    });
    assert!(matches!(e, ConfigError::DcCutoff { .. }), "{e:?}");
    assert!(msg.contains("below band_low_hz = 10"), "{msg}");
}

#[test]
fn harmonics_are_notched_and_must_fit_below_nyquist() {
    let s = ChainConfig {
        mains_hz: 60,
        mains_harmonics: 2,
        ..ChainConfig::default()
    }
    .validate()
    .expect("60, 120, 180 Hz");
    assert_eq!(s.notch_freqs_hz(), &[60.0, 120.0, 180.0]);
    assert_eq!(s.notch_sections().len(), 3);

    let (e, msg) = err(ChainConfig {
        sample_rate_hz: 200.0,
        band_high_hz: 90.0,
        mains_harmonics: 1,
        ..ChainConfig::default()
    });
    assert!(matches!(e, ConfigError::NotchAboveNyquist { .. }), "{e:?}");
    assert!(msg.contains("100 Hz"), "{msg}");
}

#[test]
fn window_and_step_must_be_whole_samples() {
    let (e, msg) = err(ChainConfig {
        window_ms: 200.5,
        ..ChainConfig::default()
    });
    assert!(
        matches!(
            e,
            ConfigError::Timing {
                field: "window_ms",
                ..
            }
        ),
        "{e:?}"
    );
    assert!(msg.contains("whole number of samples"), "{msg}");

    let (e, msg) = err(ChainConfig {
        sample_rate_hz: 200.0,
        band_high_hz: 90.0,
        step_ms: 12.0,
        ..ChainConfig::default()
    });
    assert!(
        matches!(
            e,
            ConfigError::Timing {
                field: "step_ms",
                ..
            }
        ),
        "{e:?}"
    );
    assert!(msg.contains("2.4 samples"), "{msg}");

    let (e, _) = err(ChainConfig {
        window_ms: 1.0,
        step_ms: 1.0,
        ..ChainConfig::default()
    });
    assert!(
        matches!(
            e,
            ConfigError::Timing {
                field: "window_ms",
                ..
            }
        ),
        "{e:?}"
    );

    let (e, msg) = err(ChainConfig {
        step_ms: 250.0,
        ..ChainConfig::default()
    });
    assert!(
        matches!(
            e,
            ConfigError::Timing {
                field: "step_ms",
                ..
            }
        ),
        "{e:?}"
    );
    assert!(msg.contains("not be longer than window_ms"), "{msg}");

    let (e, _) = err(ChainConfig {
        step_ms: 0.0,
        ..ChainConfig::default()
    });
    assert!(
        matches!(
            e,
            ConfigError::Timing {
                field: "step_ms",
                ..
            }
        ),
        "{e:?}"
    );
}

#[test]
fn serde_round_trip_defaults_and_unknown_fields() {
    let cfg = ChainConfig {
        channels: 10,
        mains_hz: 60,
        feature_signal: FeatureSignal::Filtered,
        ..ChainConfig::default()
    };
    let text = toml::to_string(&cfg).expect("serialize");
    assert!(text.contains("feature_signal = \"filtered\""), "{text}");
    let back: ChainConfig = toml::from_str(&text).expect("deserialize");
    assert_eq!(back, cfg);

    let partial: ChainConfig = toml::from_str("channels = 10\nmains_hz = 60\n").expect("partial");
    assert_eq!(
        partial,
        ChainConfig {
            channels: 10,
            mains_hz: 60,
            ..ChainConfig::default()
        }
    );

    let e = toml::from_str::<ChainConfig>("chanels = 10\n").expect_err("typo refused");
    assert!(e.to_string().contains("chanels"), "{e}");
}

// Regression: `mains_harmonics = 4294967295` sized a vector of 2^32 notch frequencies before any
// check (an allocation of 32 GiB), and a window of 1e7 samples sized the chain's ring at
// 2 × 1e7 samples per channel. Both fields are now bounded before anything is sized by them.
#[test]
fn fields_that_size_memory_are_bounded_first() {
    let (e, msg) = err(ChainConfig {
        sample_rate_hz: 1e300,
        band_high_hz: 450.0,
        mains_harmonics: u32::MAX,
        ..ChainConfig::default()
    });
    assert_eq!(e, ConfigError::Harmonics(u32::MAX));
    assert!(
        msg.contains("mains_harmonics = 4294967295: must be at most 20"),
        "{msg}"
    );
    ChainConfig {
        sample_rate_hz: 10_000.0,
        mains_harmonics: MAX_HARMONICS,
        ..ChainConfig::default()
    }
    .validate()
    .expect("the largest count of harmonics below Nyquist");

    let longest = ChainConfig {
        window_ms: MAX_WINDOW_SAMPLES as f64,
        ..ChainConfig::default()
    };
    assert_eq!(
        longest.validate().expect("65536 samples").window_len(),
        65_536
    );
    let (e, msg) = err(ChainConfig {
        window_ms: (MAX_WINDOW_SAMPLES + 1) as f64,
        ..ChainConfig::default()
    });
    assert!(
        matches!(
            e,
            ConfigError::Timing {
                field: "window_ms",
                ..
            }
        ),
        "{e:?}"
    );
    assert!(msg.contains("at most 65536 samples"), "{msg}");
}
