//! Criterion benchmarks of the models (decoder::model):
//! - `model/predict_<kind>`: one prediction (normalize + model) at the daemon's shapes, 96
//!   features -> 5 fingers, default hyper-parameters (ResDD H=96, L=2);
//! - `model/tick_chain_resdd`: one daemon tick's decoder work: 12 channels x 50 new samples
//!   through the signal chain, the 96 features, then ResDD;
//! - `model/train_resdd_calibration`: training ResDD with default settings on a synthetic
//!   calibration session of the default size (11 trials x 100 windows x 96 features: flexion and
//!   extension per finger plus rest), trial-tail split, early stopping.
//!
//! Run: `cargo bench -p decoder --bench model -- --warm-up-time 1 --measurement-time 3`

// criterion_group! generates an undocumented `pub fn`.
#![allow(missing_docs)]

use cpu_time::ThreadTime;
use criterion::{black_box, criterion_group, criterion_main, Criterion};
use decoder::dsp::{Chain, ChainConfig};
use decoder::model::{
    train, AnyModel, Dataset, ModelKind, ModelSpec, Normalizer, TrainConfig, TrainedModel,
    TrainingSummary, ValidationSplit, N_FINGERS,
};
use std::time::Duration;

/// SplitMix64 in [0, 1).
struct Gen(u64);
impl Gen {
    fn unit(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// CPU time of this thread for `iters` calls of `f` (the 2-core machine is shared, so wall time
/// includes time the thread spent preempted).
fn cpu_time_of<R>(iters: u64, mut f: impl FnMut() -> R) -> Duration {
    let start = ThreadTime::now();
    for _ in 0..iters {
        black_box(f());
    }
    start.elapsed()
}

fn summary(kind: ModelKind) -> TrainingSummary {
    TrainingSummary::untrained(kind)
}

fn trained_random(kind: ModelKind) -> TrainedModel {
    let chain = ChainConfig::default();
    let n_in = 8 * chain.channels;
    let model = AnyModel::random(kind, &ModelSpec::default(), n_in, N_FINGERS, 1).expect("model");
    let norm = Normalizer::from_scales(vec![0.02; n_in]).expect("scales");
    TrainedModel::new(model, ModelSpec::default(), norm, chain, summary(kind)).expect("bundle")
}

/// 11 trials (flexion and extension per finger, rest) x `windows` windows of 96 features from
/// a random non-negative mixing of 10 muscle sources, with noise.
fn calibration(windows: usize) -> Dataset {
    let mut g = Gen(7);
    let chain = ChainConfig::default();
    let nf = 8 * chain.channels;
    let mix: Vec<Vec<f64>> = (0..10)
        .map(|_| (0..nf).map(|_| g.unit().powi(2)).collect())
        .collect();
    let mut d = Dataset::new(chain).expect("chain");
    for trial in 0..11 {
        let (finger, dir) = (trial / 2, if trial % 2 == 0 { 1.0 } else { -1.0 });
        for _ in 0..windows {
            let mut x: Vec<f64> = (0..nf).map(|_| 0.05 * g.unit()).collect();
            let (mut t, mut m) = ([0.0; N_FINGERS], [true; N_FINGERS]);
            if trial < 10 {
                let a = 0.8 + 0.2 * g.unit();
                let src = &mix[2 * finger + usize::from(dir < 0.0)];
                for (xi, s) in x.iter_mut().zip(src) {
                    *xi += a * s;
                }
                m = [false; N_FINGERS];
                m[finger] = true;
                t[finger] = dir;
            }
            let x: Vec<f64> = x.iter().map(|v| v * 50.0).collect();
            d.push(&x, t, m, trial).expect("window");
        }
    }
    d
}

fn bench_models(c: &mut Criterion) {
    let mut group = c.benchmark_group("model");
    let x: Vec<f64> = (0..96).map(|i| ((i * 37 % 101) as f64) * 0.8).collect();
    for kind in ModelKind::ALL {
        let mut p = trained_random(kind).predictor();
        group.bench_function(format!("predict_{kind}"), |b| {
            b.iter(|| p.run(black_box(&x)))
        });
        group.bench_function(format!("predict_{kind}_cpu"), |b| {
            b.iter_custom(|iters| cpu_time_of(iters, || p.run(black_box(&x))))
        });
    }

    let settings = ChainConfig::default().validate().expect("defaults");
    let ch = settings.n_channels();
    let mut g = Gen(3);
    let signal: Vec<f64> = (0..10_000 * ch).map(|_| (g.unit() - 0.5) * 400.0).collect();
    let mut chain = Chain::new(&settings);
    for s in signal[..settings.window_len() * ch].chunks_exact(ch) {
        chain.push(s);
    }
    let ticks: Vec<&[f64]> = signal.chunks_exact(settings.step_len() * ch).collect();
    let mut p = trained_random(ModelKind::ResDd).predictor();
    let mut i = 0;
    let mut tick = move || {
        let t = ticks[i % ticks.len()];
        i += 1;
        let mut ready = false;
        for s in t.chunks_exact(ch) {
            ready |= chain.push(black_box(s));
        }
        assert!(ready);
        p.run(chain.features())
    };
    group.bench_function("tick_chain_resdd", |b| b.iter(&mut tick));
    group.bench_function("tick_chain_resdd_cpu", |b| {
        b.iter_custom(|iters| cpu_time_of(iters, &mut tick))
    });

    let data = calibration(100);
    let cfg = TrainConfig {
        split: ValidationSplit::TrialTail { fraction: 0.2 },
        ..TrainConfig::default()
    };
    let mut epochs = 0;
    group.sample_size(10);
    group.measurement_time(Duration::from_secs(5));
    let spec = ModelSpec::default();
    let mut run = || {
        let m = train(ModelKind::ResDd, &spec, &data, &cfg, &mut |_| {}).expect("trains");
        epochs = m.summary().epochs_run;
        m
    };
    group.bench_function("train_resdd_calibration", |b| b.iter(&mut run));
    group.bench_function("train_resdd_calibration_cpu", |b| {
        b.iter_custom(|iters| cpu_time_of(iters, &mut run))
    });
    println!(
        "train_resdd_calibration: {} windows, {epochs} epochs per run",
        data.len()
    );
    group.finish();
}

criterion_group!(benches, bench_models);
criterion_main!(benches);
