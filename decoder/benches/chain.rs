//! Criterion benchmarks of the signal chain (decoder::dsp):
//! - `chain/tick_12ch_50_samples`: one daemon tick, 12 channels x 50 new samples through the
//!   filters, then the 96 features;
//! - `chain/batch_1s_12ch`: the offline path over one second (1000 samples) of 12-channel
//!   signal, including the chain's construction.
//!
//! Run: `cargo bench -p decoder --bench chain -- --warm-up-time 1 --measurement-time 3`

// criterion_group! generates an undocumented `pub fn`.
#![allow(missing_docs)]

use criterion::{black_box, criterion_group, criterion_main, Criterion, Throughput};
use decoder::dsp::{batch_features, Chain, ChainConfig};

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

fn bench_chain(c: &mut Criterion) {
    let settings = ChainConfig::default().validate().expect("defaults");
    let ch = settings.n_channels();
    let step = settings.step_len();
    let data = signal(10_000, ch);
    let mut group = c.benchmark_group("chain");

    let mut chain = Chain::new(&settings);
    // Fill the first window so every timed tick ends with a feature vector.
    for s in data[..settings.window_len() * ch].chunks_exact(ch) {
        chain.push(s);
    }
    let ticks: Vec<&[f64]> = data.chunks_exact(step * ch).collect();
    let mut i = 0;
    group.bench_function("tick_12ch_50_samples", |b| {
        b.iter(|| {
            let tick = ticks[i % ticks.len()];
            i += 1;
            let mut ready = false;
            for s in tick.chunks_exact(ch) {
                ready |= chain.push(black_box(s));
            }
            assert!(ready);
            black_box(chain.features()[0])
        })
    });

    let one_second = &data[..1000 * ch];
    group.throughput(Throughput::Elements(1000));
    group.bench_function("batch_1s_12ch", |b| {
        b.iter(|| black_box(batch_features(&settings, black_box(one_second))))
    });
    group.finish();
}

criterion_group!(benches, bench_chain);
criterion_main!(benches);
