//! decoder::dsp against independent references: scipy's filter design and `sosfilt`, and a plain
//! numpy implementation of the paper's features, on the real 10-channel 3DC recordings.
//!
//! The references come from `decoder/ref/chain_reference.py`, run here (via HANDSTACK_PYTHON)
//! into a temporary directory. Relative error is `max|rust - ref| / max|ref|`, per channel for
//! the filtered signal and per feature column for the features.

mod dsp_common;

use decoder::dsp::npy::read_npy;
use decoder::dsp::{
    batch_features, batch_filtered, multichannel_features_into, multichannel_features_with, Chain,
    ChainConfig, FeatureSignal, Simd, Sos,
};
use dsp_common::{data_path, rel_err, run_reference, temp_dir};
use serde_json::Value;
use std::path::Path;

const TOL: f64 = 1e-9;
/// Coefficients are designed by the same algorithm in the same precision: only rounding differs.
const DESIGN_TOL: f64 = 1e-12;

fn f(v: &Value) -> f64 {
    v.as_f64().expect("number in manifest")
}

fn sections(v: &Value) -> Vec<[f64; 6]> {
    v.as_array()
        .expect("array of sections")
        .iter()
        .map(|row| {
            let r: Vec<f64> = row.as_array().expect("section row").iter().map(f).collect();
            r.try_into().expect("6 coefficients per section")
        })
        .collect()
}

/// Asserts every coefficient agrees and returns the worst error (relative, floored at 1e-3).
fn assert_sections_equal(what: &str, ours: &[Sos], theirs: &[[f64; 6]]) -> f64 {
    let mut worst = 0.0f64;
    assert_eq!(ours.len(), theirs.len(), "{what}: number of sections");
    for (i, (o, t)) in ours.iter().zip(theirs).enumerate() {
        let o = o.to_array();
        for j in 0..6 {
            let err = (o[j] - t[j]).abs() / t[j].abs().max(1e-3);
            worst = worst.max(err);
            assert!(
                err <= DESIGN_TOL,
                "{what}: section {i} coefficient {j}: ours {} scipy {} (err {err:e})",
                o[j],
                t[j]
            );
        }
    }
    worst
}

fn config_from(v: &Value) -> ChainConfig {
    ChainConfig {
        sample_rate_hz: f(&v["sample_rate_hz"]),
        band_low_hz: f(&v["band_low_hz"]),
        band_high_hz: f(&v["band_high_hz"]),
        bandpass_order: v["bandpass_order"].as_u64().expect("order") as usize,
        mains_hz: v["mains_hz"].as_u64().expect("mains") as u32,
        notch_q: f(&v["notch_q"]),
        mains_harmonics: v["mains_harmonics"].as_u64().expect("harmonics") as u32,
        dc_cutoff_hz: f(&v["dc_cutoff_hz"]),
        ..ChainConfig::default()
    }
}

fn load(dir: &Path, name: &str) -> (Vec<usize>, Vec<f64>) {
    let a = read_npy(dir.join(name)).expect("reference npy");
    (a.shape, a.data)
}

fn column(data: &[f64], n_cols: usize, c: usize) -> Vec<f64> {
    data.iter().skip(c).step_by(n_cols).copied().collect()
}

#[test]
fn chain_matches_scipy_and_numpy_on_real_recordings() {
    let data_dir = data_path("3dc-armband-p4");
    let out = temp_dir("dsp-scipy");
    run_reference(
        "chain_reference.py",
        &[
            out.to_str().expect("utf-8 temp path"),
            data_dir.to_str().expect("utf-8 data path"),
        ],
    );
    let manifest: Value = serde_json::from_str(
        &std::fs::read_to_string(out.join("manifest.json")).expect("manifest.json"),
    )
    .expect("manifest is JSON");

    // 1. Designed sections against scipy for every configuration the script lists.
    let designs = manifest["designs"].as_array().expect("designs");
    assert!(
        designs.len() >= 3,
        "need at least three design configurations"
    );
    let mut worst_design = 0.0f64;
    for d in designs {
        let cfg = config_from(&d["config"]);
        let settings = cfg.validate().expect("reference configuration is valid");
        let what = format!(
            "{} Hz {}-{} Hz order {}",
            cfg.sample_rate_hz, cfg.band_low_hz, cfg.band_high_hz, cfg.bandpass_order
        );
        let e1 = assert_sections_equal(
            &format!("band-pass {what}"),
            settings.bandpass_sections(),
            &sections(&d["bandpass"]),
        );
        let e2 = assert_sections_equal(
            &format!("DC high-pass {what}"),
            std::slice::from_ref(settings.dc_section()),
            &sections(&d["dc"]),
        );
        let e3 = assert_sections_equal(
            &format!(
                "notch {} Hz x{} {what}",
                cfg.mains_hz,
                cfg.mains_harmonics + 1
            ),
            settings.notch_sections(),
            &sections(&d["notch"]),
        );
        worst_design = worst_design.max(e1).max(e2).max(e3);
    }
    eprintln!(
        "dsp design vs scipy on {} configurations: worst coefficient error {worst_design:e}",
        designs.len()
    );

    // 2. The real recordings, each filtered on its own from reset state.
    let chain_v = &manifest["chain"];
    let mut cfg = config_from(chain_v);
    cfg.channels = chain_v["channels"].as_u64().expect("channels") as usize;
    cfg.window_ms = f(&chain_v["window_ms"]);
    cfg.step_ms = f(&chain_v["step_ms"]);
    let settings = cfg.validate().expect("10-channel chain config");
    let unrect_settings = ChainConfig {
        feature_signal: FeatureSignal::Filtered,
        ..cfg.clone()
    }
    .validate()
    .expect("unrectified config");
    let ch = settings.n_channels();
    assert_eq!(ch, 10);

    let recordings = manifest["recordings"].as_array().expect("recordings");
    assert!(recordings.len() >= 6, "need several recordings");
    let mut gestures = std::collections::BTreeSet::new();
    let mut worst_filter = 0.0f64;
    let mut worst_feature = 0.0f64;
    let mut emg_cache: Vec<(String, decoder::dsp::npy::NpyArray)> = Vec::new();
    for r in recordings {
        let split = r["split"].as_str().expect("split").to_string();
        if !emg_cache.iter().any(|(s, _)| *s == split) {
            let a = read_npy(data_dir.join(format!("P4_{split}_emg.npy"))).expect("recording");
            assert_eq!(a.shape.len(), 2);
            assert_eq!(a.shape[1], ch, "3DC recordings have 10 channels");
            emg_cache.push((split.clone(), a));
        }
        let emg = &emg_cache
            .iter()
            .find(|(s, _)| *s == split)
            .expect("cached")
            .1;
        let (start, end) = (
            r["start"].as_u64().expect("start") as usize,
            r["end"].as_u64().expect("end") as usize,
        );
        gestures.insert(r["gesture"].as_u64().expect("gesture"));
        let k = r["k"].as_u64().expect("k");
        let x = &emg.data[start * ch..end * ch];

        let ours = batch_filtered(&settings, x).expect("whole samples");
        let (shape, theirs) = load(&out, &format!("filtered_{k}.npy"));
        assert_eq!(shape, vec![end - start, ch]);
        for c in 0..ch {
            let e = rel_err(&column(&ours, ch, c), &column(&theirs, ch, c));
            worst_filter = worst_filter.max(e);
            assert!(
                e <= TOL,
                "recording {k} channel {c}: filtered rel. error {e:e}"
            );
        }

        for (settings, file) in [
            (&settings, format!("features_{k}.npy")),
            (&unrect_settings, format!("features_unrect_{k}.npy")),
        ] {
            let ours = batch_features(settings, x);
            let (shape, theirs) = load(&out, &file);
            assert_eq!(shape, vec![ours.n_rows, ours.n_cols], "{file}: shape");
            assert_eq!(ours.n_cols, 80);
            assert!(ours.n_rows > 50, "a 5 s recording gives ~97 windows");
            for c in 0..ours.n_cols {
                let e = rel_err(
                    &column(&ours.data, ours.n_cols, c),
                    &column(&theirs, ours.n_cols, c),
                );
                worst_feature = worst_feature.max(e);
                assert!(e <= TOL, "{file} column {c}: rel. error {e:e}");
            }
        }
    }
    for g in [0, 7, 8] {
        assert!(
            gestures.contains(&g),
            "gesture {g} must be among the recordings"
        );
    }
    eprintln!(
        "dsp vs scipy/numpy on {} recordings: worst filtered rel. error {worst_filter:e}, worst feature rel. error {worst_feature:e}",
        recordings.len()
    );
    let _ = std::fs::remove_dir_all(&out);
}

/// The features-only path against LibEMG's definitions (issue 15), reproduced in numpy by
/// `decoder/ref/libemg_features.py` (LibEMG itself only in `scripts/bench`): RMS, MAV, VAR,
/// IAV (our INT), WL and DASDV over 200-sample windows of the real 3DC recording, centred and
/// rectified. LibEMG's VAR is `np.var` (divides by N), ours divides by N - 1: compared as
/// `ours * (N - 1) / N`.
#[test]
fn features_only_path_matches_libemg_definitions() {
    let out = temp_dir("dsp-libemg");
    let data_dir = data_path("3dc-armband-p4");
    run_reference(
        "libemg_features.py",
        &[
            "reference",
            out.to_str().expect("utf-8 temp path"),
            data_dir.to_str().expect("utf-8 data path"),
        ],
    );
    let (wshape, windows) = load(&out, "windows.npy");
    let (fshape, theirs) = load(&out, "libemg_features.npy");
    let [n, ch, len] = wshape[..] else {
        panic!("windows.npy shape {wshape:?}")
    };
    assert_eq!(fshape, vec![n, 6, ch], "libemg_features.npy shape");
    assert!(n >= 40 && ch == 10 && len == 200, "windows {wshape:?}");
    let nf = len as f64;
    // LibEMG feature k is our feature OURS[k] times SCALE[k].
    const OURS: [usize; 6] = [0, 1, 2, 4, 5, 6];
    let scale = [1.0, 1.0, (nf - 1.0) / nf, 1.0, 1.0, 1.0];
    let (mut feats, mut portable) = (vec![0.0; 8 * ch], vec![0.0; 8 * ch]);
    let mut worst = 0.0f64;
    for (i, w) in windows.chunks_exact(ch * len).enumerate() {
        multichannel_features_into(w, ch, &mut feats);
        // The build for this CPU's instruction set and the portable one: the same bits.
        multichannel_features_with(Simd::portable(), w, ch, &mut portable);
        assert!(
            feats
                .iter()
                .zip(&portable)
                .all(|(a, b)| a.to_bits() == b.to_bits()),
            "window {i}: dispatched {feats:?} vs portable {portable:?}"
        );
        for (k, (&o, s)) in OURS.iter().zip(scale).enumerate() {
            for c in 0..ch {
                let want = theirs[(i * 6 + k) * ch + c];
                let got = feats[c * 8 + o] * s;
                let e = (got - want).abs() / want.abs().max(f64::MIN_POSITIVE);
                worst = worst.max(e);
                assert!(
                    e <= TOL,
                    "window {i} channel {c} feature {k}: ours {got} LibEMG-numpy {want} (rel. {e:e})"
                );
            }
        }
    }
    eprintln!(
        "features-only path vs LibEMG definitions on {n} windows: worst rel. error {worst:e}"
    );
    let _ = std::fs::remove_dir_all(&out);
}

/// The chain built for this CPU's instruction set (AVX2 or AVX-512 where there is one) and the
/// portable build, fed the same real 3DC samples (with one NaN and one huge value to reset a
/// channel): the same filtered values and features bit for bit. At 4, 8, 12 and 16 channels
/// (the recording's 10 repeated or cut) the AVX2 build runs its explicit cascade kernel, at 5
/// and 10 the compiled loop; with AVX-512 the features go two channels at a time, at 5 with
/// the last channel alone.
#[test]
fn dispatched_and_portable_chains_agree_bit_for_bit_on_a_real_recording() {
    let a = read_npy(data_path("3dc-armband-p4").join("P4_test_emg.npy")).expect("recording");
    let rec_ch = a.shape[1];
    for ch in [4, 5, 8, 10, 12, 16] {
        let settings = ChainConfig {
            channels: ch,
            ..ChainConfig::default()
        }
        .validate()
        .expect("chain");
        let mut chains = [
            Chain::with_simd(&settings, Simd::detect()),
            Chain::with_simd(&settings, Simd::portable()),
        ];
        let same = |a: &[f64], b: &[f64]| a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits());
        let mut windows = 0;
        for (i, rec) in a.data.chunks_exact(rec_ch).take(3000).enumerate() {
            let mut s: Vec<f64> = (0..ch).map(|c| rec[c % rec_ch]).collect();
            if i == 700 {
                s[3] = f64::NAN;
                s[ch - 1] = 1e300;
            }
            let ends: Vec<bool> = chains.iter_mut().map(|c| c.push(&s)).collect();
            let [d, p] = &mut chains;
            assert!(
                same(d.last_filtered(), p.last_filtered()),
                "{ch} channels, sample {i}: filtered"
            );
            if ends[0] {
                windows += 1;
                assert!(
                    same(d.features(), p.features()),
                    "{ch} channels, sample {i}: features"
                );
            }
        }
        assert!(windows >= 10, "{windows} windows");
    }
}
