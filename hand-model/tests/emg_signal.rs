//! The simulated sEMG looks like sEMG: spectrum, amplitude vs force, rest noise floor, seeding.

mod common;

use common::{median_frequency, rms_ac};
use hand_model::emg::{AmplifierConfig, ChannelFaults, EmgSynth, N_CHANNELS};
use hand_model::patient::{Intent, MuscleDrive};

/// `n` samples of channel `ch` (µV, as quantised) for a constant intent.
fn record(cfg: &AmplifierConfig, intent: Intent, n: usize) -> Vec<[f64; N_CHANNELS]> {
    let mut synth = EmgSynth::try_new(cfg.clone()).expect("default config is valid");
    let act = MuscleDrive::default().activation(&intent);
    (0..n)
        .map(|_| {
            let s = synth.next_sample(&act, ChannelFaults::default());
            s.counts.map(|c| f64::from(c) * cfg.lsb_uv)
        })
        .collect()
}

fn channel(rec: &[[f64; N_CHANNELS]], ch: usize) -> Vec<f64> {
    rec.iter().map(|s| s[ch]).collect()
}

#[test]
fn median_frequency_during_contraction_is_60_to_150_hz() {
    let cfg = AmplifierConfig::default();
    for finger in 0..5 {
        for (level, ch) in [(0.7, finger + 1), (-0.7, 6 + finger + 1)] {
            let rec = record(&cfg, Intent::finger(finger, level), 4096);
            let mf = median_frequency(&channel(&rec, ch), cfg.sample_rate_hz);
            assert!(
                (60.0..=150.0).contains(&mf),
                "finger {finger} level {level} channel {ch}: median frequency {mf} Hz"
            );
        }
    }
}

#[test]
fn window_rms_rises_monotonically_with_force() {
    let cfg = AmplifierConfig::default();
    let levels = [0.0, 0.1, 0.2, 0.4, 0.6, 0.8, 1.0];
    for ch in [2usize, 8] {
        let finger = 1;
        let sign = if ch < 6 { 1.0 } else { -1.0 };
        let rms: Vec<f64> = levels
            .iter()
            .map(|l| {
                rms_ac(&channel(
                    &record(&cfg, Intent::finger(finger, sign * l), 2000),
                    ch,
                ))
            })
            .collect();
        for w in rms.windows(2) {
            assert!(
                w[1] > w[0],
                "channel {ch}: RMS not rising with force: {rms:?}"
            );
        }
        // Near-linear: with curvature 1.2, half force gives 2^-1.2 = 0.44 of full-force RMS
        // (plus the floor); a grossly non-linear model would fall far outside this band.
        let ratio = rms[3] / rms[6];
        assert!(
            (0.3..0.6).contains(&ratio),
            "channel {ch}: RMS(0.4)/RMS(1) = {ratio}"
        );
    }
}

#[test]
fn rest_rms_is_within_the_stated_noise_floor() {
    let cfg = AmplifierConfig::default();
    let drive = MuscleDrive::default();
    let bound = cfg.rest_rms_bound_uv(drive.tonic);
    // The figure the README states for the default amplifier: about 10 µV (4 LSB).
    assert!(bound < 12.5, "the default rest bound grew to {bound} µV");
    let rec = record(&cfg, Intent::REST, 5000);
    for ch in 0..N_CHANNELS {
        // 1 s windows, as a rest detector would see them.
        for w in channel(&rec, ch).chunks(1000) {
            let r = rms_ac(w);
            assert!(
                r <= bound,
                "channel {ch}: rest RMS {r} µV above the stated {bound} µV"
            );
            assert!(
                r >= cfg.noise_floor_uv * 0.8,
                "channel {ch}: rest RMS {r} µV below the electrode noise"
            );
        }
    }
}

#[test]
fn same_seed_same_samples_different_seed_different_samples() {
    let a = AmplifierConfig::default();
    let b = AmplifierConfig {
        seed: 2,
        ..a.clone()
    };
    let intent = Intent::finger(3, 0.5);
    assert_eq!(record(&a, intent, 500), record(&a, intent, 500));
    assert_ne!(record(&a, intent, 500), record(&b, intent, 500));
}

#[test]
fn no_saturation_at_maximal_whole_hand_contraction() {
    let cfg = AmplifierConfig::default();
    let mut synth = EmgSynth::try_new(cfg).expect("valid");
    let act = MuscleDrive::default().activation(&Intent::all(1.0));
    let mut clipped = 0u32;
    for _ in 0..5000 {
        clipped += synth
            .next_sample(&act, ChannelFaults::default())
            .saturated
            .count_ones();
    }
    // 5000 samples x 12 channels: the defaults leave > 4 sigma of headroom.
    assert!(
        clipped <= 6,
        "{clipped} clipped channel-samples at default gain"
    );
}

#[test]
fn bad_configs_are_rejected() {
    let ok = AmplifierConfig::default();
    let bad = [
        AmplifierConfig {
            band_high_hz: 600.0,
            ..ok.clone()
        },
        AmplifierConfig {
            band_low_hz: 0.0,
            ..ok.clone()
        },
        AmplifierConfig {
            curvature: 10.0,
            ..ok.clone()
        },
        AmplifierConfig {
            lsb_uv: f64::NAN,
            ..ok.clone()
        },
        AmplifierConfig {
            noise_floor_uv: -1.0,
            ..ok.clone()
        },
    ];
    for c in bad {
        assert!(EmgSynth::try_new(c.clone()).is_err(), "{c:?} accepted");
    }
}
