//! One whole daemon tick (DESIGN.md section 8: median <= 20 us, p99 <= 50 us, zero
//! allocations): 50 ms of bus traffic (about 150 EMG frames plus finger status) decoded,
//! E2E-checked and reassembled, 12 x 50 samples through the filters, the 96 features, ResDD
//! H=96 L=2, conditioning, and the setpoint, diagnostic and heartbeat frames encoded.
//! Measured in wall time and in the thread's CPU time (the machine is shared).

#![allow(
    missing_docs,
    reason = "criterion's macros generate undocumented items"
)]

use std::hint::black_box;
use std::time::Duration;

use cpu_time::ThreadTime;
use criterion::{criterion_group, criterion_main, Criterion};
use decoder::dsp::ChainConfig;
use decoder::model::{AnyModel, ModelKind, ModelSpec, Normalizer, TrainedModel, TrainingSummary};
use driver::engine::{Engine, EngineSettings};
use hand_dbc::CanFrame;
use hand_model::patient::{Intent, Script};
use hand_model::record::run_on_mem_bus;
use hand_model::world::{PatientMode, WorldConfig};

fn engine() -> Engine {
    let chain = ChainConfig::default();
    let n_in = 8 * chain.channels;
    let spec = ModelSpec::default();
    let model = AnyModel::random(ModelKind::ResDd, &spec, n_in, 5, 1).expect("model");
    let summary = TrainingSummary::untrained(ModelKind::ResDd);
    let norm = Normalizer::from_scales(vec![100.0; n_in]).expect("scales");
    let predictor = TrainedModel::new(model, spec, norm, chain.clone(), summary)
        .expect("model")
        .predictor();
    let mut e = Engine::new(
        &chain.validate().expect("chain"),
        predictor,
        EngineSettings::default(),
        0,
    );
    e.validated(0);
    e
}

/// 20 s of traffic from a patient flexing and extending the whole hand.
fn traffic() -> Vec<(u64, CanFrame)> {
    let mut s = Script::new();
    s.rest(1_000_000)
        .ramp_to(Intent::all(1.0), 5_000_000)
        .ramp_to(Intent::all(-1.0), 10_000_000)
        .rest(4_000_000);
    let mut frames = Vec::new();
    run_on_mem_bus(
        WorldConfig::default(),
        PatientMode::Script(s),
        20_000_000,
        |t, f| {
            frames.push((t, *f));
            Ok::<_, ()>(())
        },
    )
    .expect("world")
    .expect("recording");
    frames
}

/// Runs ticks over the traffic in a loop (the engine's clock moves on across laps).
struct Replay {
    engine: Engine,
    frames: Vec<(u64, CanFrame)>,
    next: usize,
    lap: u64,
    deadline: u64,
}

impl Replay {
    fn tick(&mut self) -> usize {
        let span = 20_000_000;
        if self.deadline > span * (self.lap + 1) {
            self.lap += 1;
            self.next = 0;
        }
        while self.next < self.frames.len()
            && self.frames[self.next].0 + span * self.lap <= self.deadline
        {
            let (t, f) = self.frames[self.next];
            self.engine.on_frame(&f, t + span * self.lap);
            self.next += 1;
        }
        let n = self.engine.tick(self.deadline, self.deadline).len();
        self.engine.written(self.deadline, 0);
        self.deadline += 50_000;
        n
    }
}

fn cpu_time_of(iters: u64, mut f: impl FnMut() -> usize) -> Duration {
    let start = ThreadTime::now();
    for _ in 0..iters {
        black_box(f());
    }
    start.elapsed()
}

fn bench(c: &mut Criterion) {
    let frames = traffic();
    let mut group = c.benchmark_group("daemon");
    let mut r = Replay {
        engine: engine(),
        frames: frames.clone(),
        next: 0,
        lap: 0,
        deadline: 50_000,
    };
    group.bench_function("tick", |b| b.iter(|| r.tick()));
    let mut r = Replay {
        engine: engine(),
        frames,
        next: 0,
        lap: 0,
        deadline: 50_000,
    };
    group.bench_function("tick_cpu", |b| {
        b.iter_custom(|iters| cpu_time_of(iters, || r.tick()))
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
