//! Proof that inference never touches the heap once set up: a counting global allocator
//! (`stats_alloc`, which holds the unsafe code) around many predictions of every architecture
//! at the daemon's shapes (96 features, 5 fingers), through `Predictor::run` and through
//! `Model::predict_with`. Runs without the test harness so no other thread allocates while the
//! region is measured.

use decoder::dsp::ChainConfig;
use decoder::model::{
    AnyModel, Model, ModelKind, ModelSpec, Normalizer, TrainedModel, TrainingSummary, N_FINGERS,
};
use stats_alloc::{Region, StatsAlloc, INSTRUMENTED_SYSTEM};
use std::alloc::System;

#[global_allocator]
static GLOBAL: &StatsAlloc<System> = &INSTRUMENTED_SYSTEM;

fn summary(kind: ModelKind) -> TrainingSummary {
    TrainingSummary::untrained(kind)
}

fn main() {
    let chain = ChainConfig::default();
    let n_in = 8 * chain.channels;
    let inputs: Vec<Vec<f64>> = (0..50)
        .map(|k| {
            (0..n_in)
                .map(|i| (((i * 31 + k * 17) % 97) as f64 - 20.0) * 0.37)
                .collect()
        })
        .collect();
    let mut checksum = 0.0;
    let mut calls = 0usize;
    for kind in ModelKind::ALL {
        let spec = ModelSpec::default();
        let model = AnyModel::random(kind, &spec, n_in, N_FINGERS, 1).expect("model");
        let normalizer = Normalizer::from_scales(vec![0.01; n_in]).expect("scales");
        let trained = TrainedModel::new(
            model.clone(),
            spec,
            normalizer,
            chain.clone(),
            summary(kind),
        )
        .expect("bundle");
        let mut predictor = trained.predictor();
        let mut scratch = model.new_scratch();
        let mut y = [0.0; N_FINGERS];

        let region = Region::new(GLOBAL);
        for round in 0..20 {
            for x in &inputs {
                let out = predictor.run(x);
                model.predict_with(x, &mut y, &mut scratch);
                checksum += out[round % N_FINGERS] + y[0];
                calls += 2;
            }
        }
        let stats = region.change();
        assert_eq!(
            stats.allocations, 0,
            "{kind}: inference allocated: {stats:?}"
        );
        assert_eq!(
            stats.reallocations, 0,
            "{kind}: inference reallocated: {stats:?}"
        );
        assert_eq!(stats.deallocations, 0, "{kind}: inference freed: {stats:?}");
    }
    assert!(checksum.is_finite());
    println!("model_alloc: {calls} predictions over 4 architectures, 0 heap allocations");
    println!("1 passed, 0 failed");
}
