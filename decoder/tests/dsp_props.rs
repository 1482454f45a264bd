//! Properties of the chain (proptest): linear scaling of the features, decay of a constant
//! input, the notch's attenuation of mains, and streaming = batch bit for bit.

use decoder::dsp::{
    batch_features, batch_filtered, Chain, ChainConfig, ChainSettings, FeatureSignal,
};
use proptest::prelude::*;
use std::f64::consts::PI;

fn settings(channels: usize, mains_hz: u32, signal: FeatureSignal) -> ChainSettings {
    ChainConfig {
        channels,
        mains_hz,
        feature_signal: signal,
        ..ChainConfig::default()
    }
    .validate()
    .expect("valid test configuration")
}

/// A deterministic EMG-like test signal from a seed: noise with bursts and an offset.
fn signal(seed: u64, n: usize, channels: usize) -> Vec<f64> {
    let mut s = seed | 1;
    let mut next = move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    (0..n * channels)
        .map(|i| {
            let t = (i / channels) as f64 / 1000.0;
            let burst = 1.0 + 4.0 * ((2.0 * PI * 0.7 * t).sin().max(0.0));
            300.0 * burst * next() + 40.0
        })
        .collect()
}

fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs()) + 1e-300
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    #[test]
    fn features_scale_with_the_input(seed in any::<u64>(), k in prop_oneof![-50.0f64..-0.01, 0.01f64..50.0],
                                     rectified in any::<bool>()) {
        let sig = if rectified { FeatureSignal::Rectified } else { FeatureSignal::Filtered };
        let s = settings(2, 50, sig);
        let x = signal(seed, 600, 2);
        let kx: Vec<f64> = x.iter().map(|v| k * v).collect();
        let a = batch_features(&s, &x);
        let b = batch_features(&s, &kx);
        prop_assert_eq!(a.n_rows, 9);
        for (ra, rb) in a.rows().zip(b.rows()) {
            for (i, (&fa, &fb)) in ra.iter().zip(rb).enumerate() {
                let factor = if i % 8 == 2 { k * k } else { k.abs() };
                prop_assert!(close(fa * factor, fb, 1e-9),
                    "feature {} : {} * {} != {}", i, fa, factor, fb);
            }
        }
    }

    #[test]
    fn a_constant_input_decays_to_zero(c in -1e4f64..1e4, channels in 1usize..4) {
        let s = settings(channels, 50, FeatureSignal::Rectified);
        let mut chain = Chain::new(&s);
        let sample = vec![c; channels];
        // 10 s: the 1 Hz DC high-pass has a 0.16 s time constant, the band-pass settles faster.
        for _ in 0..10_000 {
            chain.push(&sample);
        }
        prop_assert!(chain.vectors_emitted() > 0);
        for (i, &f) in chain.features().iter().enumerate() {
            prop_assert!(f.is_finite() && f >= 0.0 && f <= 1e-9 * c.abs().max(1.0),
                "feature {} = {} for constant {}", i, f, c);
        }
    }

    #[test]
    fn the_mains_notch_attenuates_a_pure_sine_by_30_db(amp in 1.0f64..1e4, phase in 0.0f64..(2.0 * PI),
                                                      sixty in any::<bool>()) {
        let mains = if sixty { 60 } else { 50 };
        let s = settings(1, mains, FeatureSignal::Filtered);
        let mut chain = Chain::new(&s);
        let f = mains as f64;
        // 3 s: the Q = 30 notch's transient (time constant about 0.2 s) has died out.
        for n in 0..3000 {
            chain.push(&[amp * (2.0 * PI * f * n as f64 / 1000.0 + phase).sin()]);
        }
        let rms_out = chain.features()[0];
        let rms_in = amp / 2f64.sqrt();
        let db = 20.0 * (rms_in / rms_out).log10();
        prop_assert!(db >= 30.0, "{} Hz notch attenuates only {} dB", mains, db);
    }

    #[test]
    fn streaming_equals_batch_bit_for_bit(seed in any::<u64>(), channels in 1usize..13, n in 0usize..900) {
        let s = settings(channels, 50, FeatureSignal::Rectified);
        let x = signal(seed, n, channels);
        let batch = batch_features(&s, &x);
        let mut chain = Chain::new(&s);
        let filtered = batch_filtered(&s, &x).expect("whole samples");
        let mut rows = Vec::new();
        for (sample, want) in x.chunks_exact(channels).zip(filtered.chunks_exact(channels)) {
            if chain.push(sample) {
                rows.extend_from_slice(chain.features());
            }
            for (a, b) in chain.last_filtered().iter().zip(want) {
                prop_assert_eq!(a.to_bits(), b.to_bits());
            }
        }
        prop_assert_eq!(batch.n_rows, s.n_windows(n));
        prop_assert_eq!(batch.n_cols, 8 * channels);
        prop_assert_eq!(rows.len(), batch.data.len());
        for (a, b) in rows.iter().zip(&batch.data) {
            prop_assert_eq!(a.to_bits(), b.to_bits());
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 32, ..ProptestConfig::default() })]

    /// Any f64 at all (NaN, infinities, f64::MAX, subnormals) never makes a feature non-finite,
    /// and every bad value is counted on its channel.
    #[test]
    fn any_input_keeps_features_finite(values in prop::collection::vec(prop::num::f64::ANY, 3 * 420)) {
        let s = settings(3, 50, FeatureSignal::Rectified);
        let mut chain = Chain::new(&s);
        let mut bad = [0u64; 3];
        for sample in values.chunks_exact(3) {
            for (c, v) in sample.iter().enumerate() {
                if v.is_nan() || v.abs() > decoder::dsp::MAX_ABS_SAMPLE {
                    bad[c] += 1;
                }
            }
            chain.push(sample);
            prop_assert!(chain.features().iter().all(|f| f.is_finite()));
            prop_assert!(chain.last_filtered().iter().all(|f| f.is_finite()));
        }
        for (c, &n) in bad.iter().enumerate() {
            prop_assert_eq!(chain.faults().bad_samples(c), n);
        }
        prop_assert_eq!(chain.vectors_emitted(), 5);
    }

    /// Large but accepted values (up to MAX_ABS_SAMPLE) keep everything finite as well.
    #[test]
    fn extreme_finite_input_keeps_features_finite(values in prop::collection::vec(-1e12f64..1e12, 2 * 400)) {
        let s = settings(2, 60, FeatureSignal::Filtered);
        let mut chain = Chain::new(&s);
        for sample in values.chunks_exact(2) {
            chain.push(sample);
        }
        prop_assert!(chain.features().iter().all(|f| f.is_finite()));
        prop_assert_eq!(chain.faults().total(), 0);
    }
}

#[test]
fn the_notch_leaves_other_frequencies_alone() {
    // A narrow notch: 100 Hz and 30 Hz pass within 0.5 dB at Q = 30 (the band-pass is flat there).
    for f in [30.0, 100.0, 200.0] {
        let s = settings(1, 50, FeatureSignal::Filtered);
        let mut chain = Chain::new(&s);
        for n in 0..3000 {
            chain.push(&[100.0 * (2.0 * PI * f * n as f64 / 1000.0).sin()]);
        }
        let db = 20.0 * ((100.0 / 2f64.sqrt()) / chain.features()[0]).log10();
        assert!(db.abs() < 0.5, "{f} Hz attenuated by {db} dB");
    }
}

#[test]
fn reset_makes_joined_recordings_equal_separate_batches() {
    let s = settings(3, 50, FeatureSignal::Rectified);
    let a = signal(1, 700, 3);
    let b = signal(2, 450, 3);
    let mut chain = Chain::new(&s);
    let mut got = Vec::new();
    for rec in [&a, &b] {
        chain.reset();
        for sample in rec.chunks_exact(3) {
            if chain.push(sample) {
                got.extend_from_slice(chain.features());
            }
        }
    }
    let mut want = batch_features(&s, &a).data;
    want.extend(batch_features(&s, &b).data);
    assert_eq!(got, want);
}
