//! The streaming chain's behaviour around bad input: non-finite and absurd samples are counted,
//! reset only the affected channel, never make a feature non-finite, and leave the window.

use decoder::dsp::{batch_features, Chain, ChainConfig, ChainSettings};

fn settings(channels: usize) -> ChainSettings {
    ChainConfig {
        channels,
        ..ChainConfig::default()
    }
    .validate()
    .expect("valid configuration")
}

fn sample(n: usize, channels: usize) -> Vec<f64> {
    (0..channels)
        .map(|c| {
            let t = n as f64 / 1000.0;
            200.0 * (2.0 * std::f64::consts::PI * (37.0 + 11.0 * c as f64) * t).sin()
                + 80.0 * (2.0 * std::f64::consts::PI * 91.0 * t + c as f64).cos()
                + 15.0
        })
        .collect()
}

#[test]
fn a_bad_sample_resets_only_its_channel_and_leaves_the_window() {
    let ch = 10;
    let bad_ch = 3;
    let s = settings(ch);
    let w = s.window_len();
    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY, 1e300, -2e12] {
        let mut clean = Chain::new(&s);
        let mut hit = Chain::new(&s);
        // A chain started fresh right after the bad sample: channel bad_ch must follow it exactly.
        let mut restarted = Chain::new(&s);
        let t_bad = 1234;
        let mut saw_in_window = 0;
        for n in 0..3000 {
            let x = sample(n, ch);
            let mut y = x.clone();
            if n == t_bad {
                y[bad_ch] = bad;
            }
            let ready_clean = clean.push(&x);
            let ready_hit = hit.push(&y);
            assert_eq!(ready_clean, ready_hit);
            if n > t_bad {
                restarted.push(&x);
                assert_eq!(
                    hit.last_filtered()[bad_ch].to_bits(),
                    restarted.last_filtered()[bad_ch].to_bits(),
                    "filter state of channel {bad_ch} was reset at the bad sample"
                );
            }
            assert!(
                hit.features().iter().all(|f| f.is_finite()),
                "features stay finite ({bad})"
            );
            // Channels other than the bad one are untouched, bit for bit.
            for c in (0..ch).filter(|&c| c != bad_ch) {
                assert_eq!(
                    hit.features()[c * 8..c * 8 + 8],
                    clean.features()[c * 8..c * 8 + 8]
                );
            }
            let in_window = n >= t_bad && n < t_bad + w;
            assert_eq!(hit.faults().in_window(bad_ch), in_window, "sample {n}");
            assert_eq!(hit.faults().any_in_window(), in_window);
            saw_in_window += usize::from(in_window);
        }
        assert_eq!(saw_in_window, w);
        let f = hit.faults();
        if bad.is_finite() {
            assert_eq!(
                (f.non_finite(bad_ch), f.out_of_range(bad_ch)),
                (0, 1),
                "{bad}"
            );
        } else {
            assert_eq!(
                (f.non_finite(bad_ch), f.out_of_range(bad_ch)),
                (1, 0),
                "{bad}"
            );
        }
        assert_eq!(f.bad_samples(bad_ch), 1);
        assert_eq!(f.total(), 1);
        assert!((0..ch)
            .filter(|&c| c != bad_ch)
            .all(|c| f.bad_samples(c) == 0));
        assert_eq!(clean.faults().total(), 0);
    }
}

#[test]
fn a_run_of_nans_is_counted_and_recovers() {
    let s = settings(2);
    let mut chain = Chain::new(&s);
    for n in 0..2000 {
        let mut x = sample(n, 2);
        if (500..800).contains(&n) {
            x[1] = f64::NAN;
        }
        chain.push(&x);
        assert!(chain.features().iter().all(|f| f.is_finite()));
        if (500..999).contains(&n) {
            assert!(chain.faults().in_window(1));
        }
    }
    assert_eq!(chain.faults().non_finite(1), 300);
    assert_eq!(chain.faults().non_finite_counts(), &[0, 300]);
    assert!(!chain.faults().in_window(1));
    // Long after the gap the channel carries signal again.
    assert!(chain.features()[8] > 50.0, "RMS {}", chain.features()[8]);
}

#[test]
fn wrong_length_pushes_are_counted_not_fatal() {
    let s = settings(4);
    let mut chain = Chain::new(&s);
    for n in 0..400 {
        let x = sample(n, 4);
        match n {
            100 => chain.push(&x[..2]),
            101 => chain.push(&[x.as_slice(), &[1.0, 2.0]].concat()),
            _ => chain.push(&x),
        };
    }
    let f = chain.faults();
    assert_eq!(f.wrong_length(), 2);
    // The short push left channels 2 and 3 without a value: counted as non-finite there.
    assert_eq!(f.non_finite_counts(), &[0, 0, 1, 1]);
    assert_eq!(f.total(), 4);
    assert!(chain.features().iter().all(|v| v.is_finite()));
}

#[test]
fn reset_clears_state_features_and_faults() {
    let s = settings(3);
    let mut chain = Chain::new(&s);
    let mut x: Vec<f64> = Vec::new();
    for n in 0..450 {
        let mut v = sample(n, 3);
        if n == 10 {
            v[0] = f64::NAN;
        }
        chain.push(&v);
        x.extend(sample(n, 3));
    }
    assert!(chain.faults().total() > 0 && chain.samples_seen() == 450);
    chain.reset();
    assert_eq!(chain.faults().total(), 0);
    assert_eq!(chain.samples_seen(), 0);
    assert_eq!(chain.vectors_emitted(), 0);
    assert!(chain.features().iter().all(|&f| f == 0.0));
    let mut rows = Vec::new();
    for v in x.chunks_exact(3) {
        if chain.push(v) {
            rows.extend_from_slice(chain.features());
        }
    }
    assert_eq!(rows, batch_features(&s, &x).data);
}

#[test]
fn features_are_ready_once_the_window_is_full_then_every_step() {
    let s = settings(1);
    let mut chain = Chain::new(&s);
    let ready: Vec<usize> = (1..=400).filter(|&n| chain.push(&sample(n, 1))).collect();
    assert_eq!(ready, vec![200, 250, 300, 350, 400]);
    assert_eq!(chain.vectors_emitted(), 5);
}

#[test]
fn batch_refuses_a_ragged_buffer() {
    let s = settings(3);
    let e = decoder::dsp::try_batch_features(&s, &[0.0; 7]).expect_err("7 values, 3 channels");
    assert!(e.to_string().contains("7 values"), "{e}");
    assert!(decoder::dsp::batch_filtered(&s, &[0.0; 4]).is_err());
    let empty = batch_features(&s, &[]);
    assert_eq!((empty.n_rows, empty.n_cols, empty.data.len()), (0, 24, 0));
}

#[test]
fn a_silent_channel_settles_to_exact_zero_not_subnormals() {
    // After an impulse, zero input makes IIR state decay into subnormals and cycle there
    // forever unless it is flushed; the chain flushes state below FLUSH_BELOW.
    let s = settings(2);
    let mut chain = Chain::new(&s);
    chain.push(&[1000.0, -3.0e4]);
    let mut smallest_nonzero = f64::MAX;
    for _ in 0..200_000 {
        chain.push(&[0.0, 0.0]);
        chain.features();
        for &v in chain.last_filtered().iter().chain(chain.last_features()) {
            if v != 0.0 {
                smallest_nonzero = smallest_nonzero.min(v.abs());
            }
        }
    }
    assert!(
        smallest_nonzero >= f64::MIN_POSITIVE,
        "a subnormal value appeared: {smallest_nonzero:e}"
    );
    assert!(chain.last_filtered().iter().all(|&v| v == 0.0));
    assert!(chain.features().iter().all(|&v| v == 0.0));
}

#[test]
fn features_equal_the_formulas_over_the_processed_window() {
    // Both feature paths: window a whole number of steps (per-block statistics merged) and not
    // (the whole window revisited). Each must equal window_features of the last window of
    // |filtered| to rounding.
    for (step_ms, rectified) in [(50.0, true), (30.0, true), (50.0, false), (7.0, false)] {
        let s = ChainConfig {
            channels: 3,
            step_ms,
            feature_signal: if rectified {
                decoder::dsp::FeatureSignal::Rectified
            } else {
                decoder::dsp::FeatureSignal::Filtered
            },
            ..ChainConfig::default()
        }
        .validate()
        .expect("valid configuration");
        let x: Vec<f64> = (0..1500).flat_map(|n| sample(n, 3)).collect();
        let filtered = decoder::dsp::batch_filtered(&s, &x).expect("whole samples");
        let mut chain = Chain::new(&s);
        let mut checked = 0;
        for (n, v) in x.chunks_exact(3).enumerate() {
            if !chain.push(v) {
                continue;
            }
            for c in 0..3 {
                let window: Vec<f64> = (n + 1 - s.window_len()..=n)
                    .map(|i| filtered[i * 3 + c])
                    .map(|y| if rectified { y.abs() } else { y })
                    .collect();
                let want = decoder::dsp::window_features(&window);
                for (k, (a, b)) in chain.features()[c * 8..c * 8 + 8]
                    .iter()
                    .zip(want)
                    .enumerate()
                {
                    assert!(
                        (a - b).abs() <= 1e-12 * b.abs().max(1e-300),
                        "step {step_ms} ms, sample {n}, channel {c}, feature {k}: {a} vs {b}"
                    );
                }
            }
            checked += 1;
        }
        assert_eq!(checked, s.n_windows(1500));
    }
}

#[test]
fn features_on_request_equal_the_window_end_rows_bit_for_bit_and_follow_every_sample() {
    let ch = 12;
    let s = settings(ch);
    let w = s.window_len();
    let mut chain = Chain::new(&s);
    // A chain whose step is one sample has a window end at every sample: the features asked
    // for at any sample (as the daemon does at its tick) must be its rows, bit for bit.
    let one = ChainConfig {
        channels: ch,
        step_ms: 1.0,
        ..ChainConfig::default()
    }
    .validate()
    .expect("valid configuration");
    let mut every = Chain::new(&one);
    let (mut at_steps, mut between) = (0, 0);
    for n in 0..1500 {
        let x = sample(n, ch);
        let ready = chain.push(&x);
        every.push(&x);
        if chain.samples_seen() < w as u64 {
            continue;
        }
        let now = chain.features().to_vec();
        for (i, (a, b)) in every.features().iter().zip(&now).enumerate() {
            assert_eq!(
                a.to_bits(),
                b.to_bits(),
                "sample {n} feature {i}: {a} vs {b}"
            );
        }
        if ready {
            at_steps += 1;
        } else {
            between += 1;
        }
    }
    assert!(at_steps >= 20 && between >= 1000, "{at_steps} {between}");
    // The window slides with every sample.
    let before = chain.features().to_vec();
    chain.push(&sample(1500, ch));
    assert_ne!(
        before,
        chain.features(),
        "features must follow every sample"
    );
    let now = chain.features().to_vec();
    assert_eq!(now, chain.last_features());
}
