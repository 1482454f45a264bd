//! Proof that the chain's per-sample and per-tick path never touches the heap: a counting
//! global allocator (`stats_alloc`, which holds the unsafe code) around 12-channel ticks of 50
//! samples, with features, faults and a reset in between. Runs without the test harness so no
//! other thread allocates while the region is measured.

use decoder::dsp::{Chain, ChainConfig};
use stats_alloc::{Region, StatsAlloc, INSTRUMENTED_SYSTEM};
use std::alloc::System;

#[global_allocator]
static GLOBAL: &StatsAlloc<System> = &INSTRUMENTED_SYSTEM;

fn main() {
    let settings = ChainConfig::default().validate().expect("defaults");
    let channels = settings.n_channels();
    let data: Vec<f64> = (0..2000 * channels)
        .map(|i| (((i * 7919) % 1013) as f64 - 506.0) * 0.9)
        .collect();
    let mut chain = Chain::new(&settings);
    let mut checksum = 0.0;
    let mut ticks = 0;

    let region = Region::new(GLOBAL);
    for round in 0..3 {
        for tick in data.chunks_exact(50 * channels) {
            let mut ready = false;
            for (k, sample) in tick.chunks_exact(channels).enumerate() {
                if round == 1 && k == 7 {
                    // Bad input on the hot path must not allocate either.
                    let mut bad = [0.0; 12];
                    bad.copy_from_slice(sample);
                    bad[5] = f64::NAN;
                    bad[6] = 1e300;
                    ready |= chain.push(&bad);
                    chain.push(&bad[..3]);
                } else {
                    ready |= chain.push(sample);
                }
            }
            if ready {
                checksum += chain.features().iter().sum::<f64>();
                ticks += 1;
            }
            checksum += chain.faults().total() as f64 + chain.faults().in_window(5) as u8 as f64;
        }
        chain.reset();
    }
    let stats = region.change();

    assert!(ticks > 100, "only {ticks} ticks ran");
    assert!(checksum.is_finite());
    assert_eq!(
        stats.allocations, 0,
        "heap allocations in the hot path: {stats:?}"
    );
    assert_eq!(
        stats.reallocations, 0,
        "heap reallocations in the hot path: {stats:?}"
    );
    assert_eq!(
        stats.deallocations, 0,
        "heap frees in the hot path: {stats:?}"
    );
    println!(
        "dsp_alloc: {ticks} ticks of 12 x 50 samples: {} allocations, {} reallocations, {} deallocations",
        stats.allocations, stats.reallocations, stats.deallocations
    );
}
