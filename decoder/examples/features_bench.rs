//! The features-only path against LibEMG (issue 15): the per-window CPU time of
//! [`decoder::dsp::multichannel_features_into`] over the windows that
//! `decoder/ref/features_libemg_bench.py` times LibEMG's FeatureExtractor on.
//!
//! `cargo run --release -p decoder --example features_bench -- WINDOWS.npy [--json] [--portable]`
//!
//! WINDOWS.npy is float64 `(n_windows, channels, samples)` (LibEMG's layout, channel-major per
//! window, as ours). Prints the median over rounds of the thread's CPU time per window, one
//! window per call as online, twice: `streamed` (every window in turn, each read from memory
//! first) and `hot` (the first 8 windows cycled, so the window is in cache, as the daemon's
//! window is when its tick computes the features); with `--json` one line each,
//! `{"what":"features_window","impl":"handstack","mode":"hot","us_cpu_per_window":X,...}`.
//! The loops run in the build for the CPU's widest instruction set ([`Simd::detect`]); `--portable` times the
//! portable build instead (the same bits). Windows that are all rectified (every value
//! `>= 0`, checked once before timing, as the bench's are and as the chain's are by default)
//! go through [`decoder::dsp::multichannel_rectified_features_with`], the chain's own path for
//! them; others through the general one.

use std::hint::black_box;
use std::time::Duration;

use cpu_time::ThreadTime;
use decoder::dsp::npy::read_npy;
use decoder::dsp::{multichannel_features_with, multichannel_rectified_features_with, Simd};

/// Rounds timed; the median is reported.
const ROUNDS: usize = 15;
/// Passes over all windows per round.
const PASSES: usize = 20;
/// Distinct windows of the hot measurement: 8 x 19.2 kB, well inside L2.
const HOT_WINDOWS: usize = 8;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let json = args.iter().any(|a| a == "--json");
    let portable = args.iter().any(|a| a == "--portable");
    let (simd, name) = if portable {
        (Simd::portable(), "handstack-portable")
    } else {
        (Simd::detect(), "handstack")
    };
    let Some(path) = args.iter().find(|a| !a.starts_with("--")) else {
        eprintln!("usage: features_bench WINDOWS.npy [--json] [--portable]");
        std::process::exit(2);
    };
    let a = read_npy(path).unwrap_or_else(|e| {
        eprintln!("features_bench: {path}: {e}");
        std::process::exit(1);
    });
    let [n_windows, channels, samples] = a.shape[..] else {
        eprintln!("features_bench: {path}: shape {:?}, want 3 axes", a.shape);
        std::process::exit(1);
    };
    let per_window = channels * samples;
    let mut out = vec![0.0; 8 * channels];
    let rectified = !a.data.iter().any(|&v| v < 0.0);
    let isa = simd.name();
    let features = if rectified {
        multichannel_rectified_features_with
    } else {
        multichannel_features_with
    };
    // Streamed: every window once per pass, 1000 of them (19.2 MB, more than the caches), so
    // each call first reads its window from memory. Hot: the first HOT_WINDOWS cycled, so the
    // window is in cache, as the daemon's is (the chain has just written it).
    let all: Vec<&[f64]> = a.data.chunks_exact(per_window).collect();
    let hot: Vec<&[f64]> = (0..all.len())
        .map(|i| all[i % HOT_WINDOWS.min(all.len())])
        .collect();
    for (mode, windows) in [("streamed", &all), ("hot", &hot)] {
        let (median, best) = time_calls(windows, |w| {
            features(simd, w, channels, &mut out);
            black_box(&out);
        });
        let distinct = if mode == "hot" {
            HOT_WINDOWS.min(n_windows)
        } else {
            n_windows
        };
        if json {
            println!(
                "{{\"what\":\"features_window\",\"impl\":\"{name}\",\"mode\":\"{mode}\",\"us_cpu_per_window\":{median:.4},\"us_cpu_best\":{best:.4},\"isa\":\"{isa}\",\"rectified\":{rectified},\"windows\":{distinct},\"channels\":{channels},\"samples\":{samples}}}"
            );
        } else {
            println!(
                "{name} features of one {channels} x {samples} window ({} path, {mode}: {distinct} distinct windows): median {median:.3} us CPU (best {best:.3}) over {ROUNDS} rounds of {} calls",
                if rectified { "rectified" } else { "general" },
                PASSES * windows.len()
            );
        }
    }
}

/// Median and best over [`ROUNDS`] of the thread's CPU time per call, in µs, of `call` on every
/// window of `windows`, [`PASSES`] times.
fn time_calls(windows: &[&[f64]], mut call: impl FnMut(&[f64])) -> (f64, f64) {
    let mut rounds: Vec<Duration> = (0..ROUNDS)
        .map(|_| {
            let start = ThreadTime::now();
            for _ in 0..PASSES {
                for &w in windows {
                    call(black_box(w));
                }
            }
            start.elapsed()
        })
        .collect();
    rounds.sort();
    let calls = (PASSES * windows.len()) as f64;
    let us = |d: Duration| d.as_secs_f64() * 1e6 / calls;
    (us(rounds[ROUNDS / 2]), us(rounds[0]))
}
