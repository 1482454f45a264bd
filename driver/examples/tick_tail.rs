//! The daemon tick's tail (issue 15): median, p99 and max of the whole tick over at least
//! 100,000 ticks of recorded traffic, from a histogram of the thread's CPU time per tick, and
//! where the time goes (front end, filters, features, model, the rest) as a table.
//!
//! `cargo run --release -p driver --features sim --example tick_tail -- [--ticks N] [--json]`
//!
//! The traffic is 20 s of a patient flexing and extending the whole hand, recorded from the
//! simulated amplifier and fingers on the in-memory bus (the same as `benches/tick.rs`), then
//! replayed lap after lap into one [`Engine`] with its clock moving on. One tick is everything
//! the daemon does for 50 ms: the frames' `on_frame` (E2E, decode, reassembly, filters) plus
//! `tick` (faults, features, model, conditioning, encoding) plus `written`. Each tick is timed
//! with `CLOCK_THREAD_CPUTIME_ID` (`cpu-time`), whose own cost (two reads, measured and
//! reported) is in every figure. The breakdown times each stage alone over the same ticks.

use std::hint::black_box;
use std::time::Duration;

use cpu_time::ThreadTime;
use decoder::dsp::{Chain, ChainConfig, ChainSettings};
use decoder::model::{
    AnyModel, ModelKind, ModelSpec, Normalizer, Predictor, Trainable, TrainedModel, TrainingSummary,
};
use driver::engine::{Engine, EngineSettings};
use hand_dbc::emg_front::{EmgFront, EmgFrontConfig, EmgFrontSettings};
use hand_dbc::CanFrame;
use hand_model::patient::{Intent, Script};
use hand_model::record::run_on_mem_bus;
use hand_model::world::{PatientMode, WorldConfig};

/// Length of the recorded traffic, µs.
const SPAN_US: u64 = 20_000_000;
/// Tick period, µs.
const TICK_US: u64 = 50_000;
/// Histogram bin width, ns, and number of bins (the last one holds everything longer).
const BIN_NS: u64 = 10;
const BINS: usize = 20_000;

fn model(chain: &ChainConfig) -> AnyModel {
    let spec = ModelSpec::default();
    AnyModel::random(ModelKind::ResDd, &spec, 8 * chain.channels, 5, 1).expect("model")
}

/// How many f64 weights the model holds.
fn n_weights(chain: &ChainConfig) -> usize {
    model(chain).params().len()
}

fn predictor(chain: &ChainConfig) -> Predictor {
    let n_in = 8 * chain.channels;
    let spec = ModelSpec::default();
    let model = model(chain);
    let summary = TrainingSummary::untrained(ModelKind::ResDd);
    let norm = Normalizer::from_scales(vec![100.0; n_in]).expect("scales");
    TrainedModel::new(model, spec, norm, chain.clone(), summary)
        .expect("model")
        .predictor()
}

fn engine(chain: &ChainConfig) -> Engine {
    let settings = chain.validate().expect("chain");
    let mut e = Engine::new(&settings, predictor(chain), EngineSettings::default(), 0);
    e.validated(0);
    e
}

/// 20 s of traffic from a patient flexing and extending the whole hand, cut into ticks: the
/// frames (with receive times) each tick consumes.
fn traffic() -> Vec<Vec<(u64, CanFrame)>> {
    let mut s = Script::new();
    s.rest(1_000_000)
        .ramp_to(Intent::all(1.0), 5_000_000)
        .ramp_to(Intent::all(-1.0), 10_000_000)
        .rest(4_000_000);
    let mut frames = Vec::new();
    run_on_mem_bus(
        WorldConfig::default(),
        PatientMode::Script(s),
        SPAN_US,
        |t, f| {
            frames.push((t, *f));
            Ok::<_, ()>(())
        },
    )
    .expect("world")
    .expect("recording");
    let mut ticks = vec![Vec::new(); (SPAN_US / TICK_US) as usize];
    for (t, f) in frames {
        // A frame received in (deadline - 50 ms, deadline] belongs to that deadline's tick.
        let i = (t.saturating_sub(1) / TICK_US) as usize;
        if let Some(tick) = ticks.get_mut(i) {
            tick.push((t, f));
        }
    }
    ticks
}

/// CPU time per tick, in `BIN_NS` bins, with the exact maximum.
struct Hist {
    bins: Vec<u64>,
    n: u64,
    max_ns: u64,
    sum_ns: u128,
}

impl Hist {
    fn new() -> Self {
        Self {
            bins: vec![0; BINS],
            n: 0,
            max_ns: 0,
            sum_ns: 0,
        }
    }

    fn record(&mut self, ns: u64) {
        self.bins[((ns / BIN_NS) as usize).min(BINS - 1)] += 1;
        self.n += 1;
        self.max_ns = self.max_ns.max(ns);
        self.sum_ns += u128::from(ns);
    }

    /// Upper edge of the bin holding quantile `q`, µs.
    fn quantile_us(&self, q: f64) -> f64 {
        let want = ((q * self.n as f64).ceil() as u64).max(1);
        let mut seen = 0;
        for (i, &c) in self.bins.iter().enumerate() {
            seen += c;
            if seen >= want {
                return ((i as u64 + 1) * BIN_NS).min(self.max_ns) as f64 / 1000.0;
            }
        }
        self.max_ns as f64 / 1000.0
    }

    fn mean_us(&self) -> f64 {
        self.sum_ns as f64 / self.n.max(1) as f64 / 1000.0
    }
}

/// One replayed tick: the frames of tick `i` of lap `lap`, then `tick` and `written`.
fn run_tick(engine: &mut Engine, frames: &[(u64, CanFrame)], lap: u64, deadline: u64) -> usize {
    for (t, f) in frames {
        engine.on_frame(f, t + SPAN_US * lap);
    }
    let n = engine.tick(deadline, deadline).len();
    engine.written(deadline, 0);
    n
}

/// The whole tick over `n_ticks` ticks: the histogram and the cost of one timer pair, ns.
fn whole_ticks(chain: &ChainConfig, ticks: &[Vec<(u64, CanFrame)>], n_ticks: u64) -> (Hist, u64) {
    let mut engine = engine(chain);
    let mut hist = Hist::new();
    // Warm up one lap, untimed.
    for (i, frames) in ticks.iter().enumerate() {
        run_tick(&mut engine, frames, 0, (i as u64 + 1) * TICK_US);
    }
    for k in 0..n_ticks {
        let lap = 1 + k / ticks.len() as u64;
        let i = (k % ticks.len() as u64) as usize;
        let deadline = SPAN_US * lap + (i as u64 + 1) * TICK_US;
        let start = ThreadTime::now();
        black_box(run_tick(&mut engine, &ticks[i], lap, deadline));
        hist.record(start.elapsed().as_nanos() as u64);
    }
    let c = engine.counters();
    eprintln!(
        "engine after {} ticks: {} deadline misses, state {:?}, faults {:?}",
        c.ticks,
        c.deadline_misses,
        engine.state(),
        engine.faults()
    );
    let start = ThreadTime::now();
    for _ in 0..10_000 {
        black_box(ThreadTime::now().elapsed());
    }
    let timer_ns = start.elapsed().as_nanos() as u64 / 10_000;
    (hist, timer_ns)
}

/// The tick's stages, each alone over the same ticks: mean CPU µs per tick.
struct Stages {
    front: f64,
    filters: f64,
    features: f64,
    model: f64,
    /// Not a stage: one plain read of as many f64 as the model has weights, per tick (the
    /// memory floor of the model stage, whose weights do not fit in L1).
    weights_read: f64,
}

/// Sum of `w` with eight independent accumulators: a read of every value, nothing else.
#[inline(never)]
fn read_all(w: &[f64]) -> f64 {
    let mut acc = [0.0f64; 8];
    for c in w.chunks_exact(8) {
        for k in 0..8 {
            acc[k] += c[k];
        }
    }
    acc.iter().sum()
}

/// Median over `rounds` of the mean CPU time per tick of `pass` (one pass = every tick once).
fn per_tick_us(rounds: usize, n_ticks: usize, mut pass: impl FnMut() -> Duration) -> f64 {
    let mut v: Vec<f64> = (0..rounds)
        .map(|_| pass().as_secs_f64() * 1e6 / n_ticks as f64)
        .collect();
    v.sort_by(f64::total_cmp);
    v[rounds / 2]
}

/// The samples (µV, one row per sample) the front end makes of each tick's frames.
fn front_samples(settings: &EmgFrontSettings, ticks: &[Vec<(u64, CanFrame)>]) -> Vec<Vec<f64>> {
    let mut front = EmgFront::new(settings);
    ticks
        .iter()
        .map(|frames| {
            let mut out = Vec::new();
            for (t, f) in frames {
                front.on_frame(f, *t, &mut |s| out.extend_from_slice(s.uv()));
            }
            out
        })
        .collect()
}

/// One pass of the filters over every tick's samples, with the features at each tick if
/// `features`; returns the CPU time and the feature vectors.
fn chain_pass(
    settings: &ChainSettings,
    samples: &[Vec<f64>],
    features: bool,
) -> (Duration, Vec<Vec<f64>>) {
    let ch = settings.n_channels();
    let mut chain = Chain::new(settings);
    let mut rows = Vec::with_capacity(samples.len());
    let start = ThreadTime::now();
    for tick in samples {
        for s in tick.chunks_exact(ch) {
            chain.push(black_box(s));
        }
        if features {
            black_box(chain.features());
        }
    }
    let t = start.elapsed();
    if features {
        // Again, untimed, to keep the vectors for the model's pass.
        chain.reset();
        for tick in samples {
            for s in tick.chunks_exact(ch) {
                chain.push(s);
            }
            rows.push(chain.features().to_vec());
        }
    }
    (t, rows)
}

fn stages(chain_cfg: &ChainConfig, ticks: &[Vec<(u64, CanFrame)>], rounds: usize) -> Stages {
    let settings = chain_cfg.validate().expect("chain");
    let front_settings = EmgFrontSettings::try_new(EmgFrontConfig {
        max_gap_us: EngineSettings::default().max_gap_us,
        channels: settings.n_channels(),
        ..EmgFrontConfig::at_rate(settings.sample_rate_hz())
    })
    .expect("front end");
    let n = ticks.len();
    let front = per_tick_us(rounds, n, || {
        let mut f = EmgFront::new(&front_settings);
        let mut count = 0usize;
        let start = ThreadTime::now();
        for frames in ticks {
            for (t, fr) in frames {
                f.on_frame(fr, *t, &mut |s| count += s.uv().len());
            }
        }
        black_box(count);
        start.elapsed()
    });
    let samples = front_samples(&front_settings, ticks);
    // Filters alone and filters with features back to back in each round, so a burst of
    // noise on this shared machine lands in both halves of a difference, not in one.
    let per_tick = |d: Duration| d.as_secs_f64() * 1e6 / n as f64;
    let (mut filters, mut features): (Vec<f64>, Vec<f64>) = (0..rounds)
        .map(|_| {
            let alone = per_tick(chain_pass(&settings, &samples, false).0);
            let both = per_tick(chain_pass(&settings, &samples, true).0);
            (alone, both - alone)
        })
        .unzip();
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let rows = chain_pass(&settings, &samples, true).1;
    let mut p = predictor(chain_cfg);
    let model = per_tick_us(rounds, n, || {
        let start = ThreadTime::now();
        for r in &rows {
            black_box(p.run(black_box(r)));
        }
        start.elapsed()
    });
    let weights = vec![1e-3; n_weights(chain_cfg)];
    let weights_read = per_tick_us(rounds, n, || {
        let start = ThreadTime::now();
        for _ in 0..n {
            black_box(read_all(black_box(&weights)));
        }
        start.elapsed()
    });
    Stages {
        front,
        filters: median(&mut filters),
        features: median(&mut features),
        model,
        weights_read,
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let json = args.iter().any(|a| a == "--json");
    let n_ticks: u64 = args
        .iter()
        .position(|a| a == "--ticks")
        .and_then(|i| args.get(i + 1))
        .map(|v| v.parse().expect("--ticks N"))
        .unwrap_or(100_000);
    let chain = ChainConfig::default();
    let ticks = traffic();
    let frames: usize = ticks.iter().map(Vec::len).sum();
    let (hist, timer_ns) = whole_ticks(&chain, &ticks, n_ticks);
    let s = stages(&chain, &ticks, 25);
    let (p50, p99, max, mean) = (
        hist.quantile_us(0.5),
        hist.quantile_us(0.99),
        hist.max_ns as f64 / 1000.0,
        hist.mean_us(),
    );
    let rest = mean - s.front - s.filters - s.features - s.model;
    if json {
        println!(
            "{{\"what\":\"daemon_tick\",\"impl\":\"handstack\",\"ticks\":{},\"us_cpu_median\":{p50:.2},\"us_cpu_p99\":{p99:.2},\"us_cpu_max\":{max:.2},\"us_cpu_mean\":{mean:.2},\"timer_ns\":{timer_ns},\"us_front\":{:.2},\"us_filters\":{:.2},\"us_features\":{:.2},\"us_model\":{:.2},\"us_rest\":{rest:.2},\"us_weights_read\":{:.2},\"weights\":{}}}",
            hist.n, s.front, s.filters, s.features, s.model, s.weights_read, n_weights(&chain)
        );
        return;
    }
    println!(
        "{} ticks ({} frames per 20 s lap), CPU time per tick from a {BIN_NS} ns histogram:",
        hist.n, frames
    );
    println!("  median {p50:.2} us, p99 {p99:.2} us, max {max:.2} us, mean {mean:.2} us");
    println!("  (one timer pair costs {timer_ns} ns and is in every tick's figure)");
    println!("| stage (alone, same ticks) | CPU us per tick | share of the mean |");
    println!("|---|---|---|");
    for (what, us) in [
        ("front end: E2E, decode, reassembly, rails, uV", s.front),
        ("filters (DC, band-pass, notch) + window", s.filters),
        ("features (96, whole window)", s.features),
        ("model (normalize + ResDD H=96 L=2)", s.model),
        ("the rest: dispatch, faults, conditioning, encode", rest),
    ] {
        println!("| {what} | {us:.2} | {:.0} % |", 100.0 * us / mean);
    }
    println!(
        "the model's floor: one plain read of its {} f64 weights takes {:.2} us",
        n_weights(&chain),
        s.weights_read
    );
}
