//! Criterion benchmarks of the signal chain (decoder::dsp):
//! - `chain/tick_12ch_50_samples`: one daemon tick, 12 channels x 50 new samples through the
//!   filters, then the 96 features;
//! - `chain/batch_1s_12ch`: the offline path over one second (1000 samples) of 12-channel
//!   signal, including the chain's construction;
//! - `chain/filter_60s_12ch`: only the filters (DC, band-pass, notch) over 60 s of 12-channel
//!   signal, to compare with `scipy.signal.sosfilt` on the same shape
//!   (`decoder/ref/sosfilt_timing.py`).
//!
//!
//! Each is measured twice: wall time (criterion's default) and the benchmark thread's CPU time
//! (`*_cpu`, via `cpu-time`), because the 2-core development machine is shared and wall time
//! there includes time the thread spent preempted.
//!
//! Run: `cargo bench -p decoder --bench chain -- --warm-up-time 1 --measurement-time 3`

// criterion_group! generates an undocumented `pub fn`.
#![allow(missing_docs)]

use cpu_time::ThreadTime;
use criterion::{black_box, criterion_group, criterion_main, Criterion, Throughput};
use decoder::dsp::{batch_features, batch_filtered, Chain, ChainConfig};
use std::time::Duration;

/// Deterministic EMG-like noise (xorshift), `n` samples of `channels` channels, row-major.
fn signal(n: usize, channels: usize) -> Vec<f64> {
    let mut s: u64 = 0x9E37_79B9_7F4A_7C15;
    (0..n * channels)
        .map(|_| {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            ((s >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 400.0
        })
        .collect()
}

/// CPU time of this thread for `iters` calls of `f`.
fn cpu_time_of<R>(iters: u64, mut f: impl FnMut() -> R) -> Duration {
    let start = ThreadTime::now();
    for _ in 0..iters {
        black_box(f());
    }
    start.elapsed()
}

fn bench_chain(c: &mut Criterion) {
    let settings = ChainConfig::default().validate().expect("defaults");
    let ch = settings.n_channels();
    let step = settings.step_len();
    let data = signal(10_000, ch);
    assert!(settings.cascade().len() == 6);
    let mut group = c.benchmark_group("chain");

    let mut chain = Chain::new(&settings);
    // Fill the first window so every timed tick ends with a feature vector.
    for s in data[..settings.window_len() * ch].chunks_exact(ch) {
        chain.push(s);
    }
    let ticks: Vec<&[f64]> = data.chunks_exact(step * ch).collect();
    let mut i = 0;
    let mut tick = move || {
        let t = ticks[i % ticks.len()];
        i += 1;
        let mut ready = false;
        for s in t.chunks_exact(ch) {
            ready |= chain.push(black_box(s));
        }
        assert!(ready);
        black_box(chain.features()[0])
    };
    group.bench_function("tick_12ch_50_samples", |b| b.iter(&mut tick));
    group.bench_function("tick_12ch_50_samples_cpu", |b| {
        b.iter_custom(|iters| cpu_time_of(iters, &mut tick))
    });

    let one_second = &data[..1000 * ch];
    group.throughput(Throughput::Elements(1000));
    group.bench_function("batch_1s_12ch", |b| {
        b.iter(|| black_box(batch_features(&settings, black_box(one_second))))
    });
    group.bench_function("batch_1s_12ch_cpu", |b| {
        b.iter_custom(|iters| {
            cpu_time_of(iters, || {
                black_box(batch_features(&settings, black_box(one_second)));
            })
        })
    });

    let minute = signal(60_000, ch);
    group.throughput(Throughput::Elements(60_000));
    group.sample_size(20);
    group.bench_function("filter_60s_12ch_cpu", |b| {
        b.iter_custom(|iters| {
            cpu_time_of(iters, || {
                black_box(batch_filtered(&settings, black_box(&minute)).expect("whole samples"));
            })
        })
    });
    group.finish();
}

criterion_group!(benches, bench_chain);
criterion_main!(benches);
