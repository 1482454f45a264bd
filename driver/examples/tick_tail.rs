//! The daemon tick's tail (issue 15): median, p99 and max of the whole tick over at least
//! 100,000 ticks of recorded traffic, from a histogram of the thread's CPU time per tick, and
//! where the time goes (front end, filters, features, model, the rest) as a table.
//!
//! `cargo run --release -p driver --features sim --example tick_tail -- [--ticks N] [--json]
//! [--drives cia402]`
//!
//! The traffic is 20 s of a patient flexing and extending the whole hand, recorded from the
//! simulated amplifier and fingers on the in-memory bus (the same as `benches/tick.rs`), then
//! replayed lap after lap into one [`Engine`] with its clock moving on. One tick is everything
//! the daemon does for 50 ms: the frames' `on_frame` (E2E, decode, reassembly, filters) plus
//! `tick` (faults, features, model, conditioning, encoding) plus `written`. Each tick is timed
//! with `CLOCK_THREAD_CPUTIME_ID` (`cpu-time`), whose own cost (two reads, measured and
//! reported) is in every figure. The breakdown times each stage alone over the same ticks.
//!
//! `--drives cia402`: every finger on a simulated CiA 402 drive (node 5 + finger, torque mode),
//! as `handctl demo --drives cia402` runs them. The native controllers' FINGER_STATUS frames
//! leave the traffic; each tick the engine's frames (its RPDO1s, SYNC, heartbeat, and any
//! start-up SDO) reach the drives, and the drives' answers (TPDO1, TPDO2, heartbeats) reach the
//! engine in the next tick, before its deadline. Only the engine's calls are timed (`on_frame`
//! with `take_immediate`, `tick`, `written`), from a lap after every drive follows its target;
//! the simulated drives run outside the clock. No stage table in this mode.

use std::hint::black_box;
use std::time::Duration;

use cpu_time::ThreadTime;
use decoder::dsp::{Chain, ChainConfig, ChainSettings};
use decoder::model::{AnyModel, ModelKind, ModelSpec, Predictor, Trainable, TrainedModel};
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

/// How many f64 weights the model holds (the default spec, as the trained model's).
fn n_weights(chain: &ChainConfig) -> usize {
    model(chain).params().len()
}

/// The model handd would run: the demo's simulated calibration (seed 1), trained with the
/// defaults, so the tick pays for everything a calibrated model does (the envelope's
/// projection, the plausibility tests with the calibration's channel patterns, the rest
/// stage). Trained once per run, on the same chain as the traffic.
fn predictor(chain: &ChainConfig) -> Predictor {
    use driver::demo::{calibrated_model, DemoOptions};
    use std::sync::OnceLock;
    static MODEL: OnceLock<TrainedModel> = OnceLock::new();
    let m = MODEL.get_or_init(|| {
        let seed = DemoOptions::default().seed;
        let m = calibrated_model(seed).expect("the demo's calibration, trained");
        let e = m.envelope().expect("a trained model has an envelope");
        eprintln!(
            "model: the demo's calibration (seed {seed}), trained: envelope, alone test {}, {} \
             channel patterns",
            if e.alone().is_some() { "on" } else { "off" },
            e.cone().map_or(0, |c| c.patterns().count())
        );
        m
    });
    assert_eq!(m.chain(), chain, "the model's chain is the traffic's");
    m.predictor()
}

fn engine(chain: &ChainConfig, settings: EngineSettings) -> Engine {
    let chain_settings = chain.validate().expect("chain");
    let mut e = Engine::new(&chain_settings, predictor(chain), settings, 0);
    e.validated(0);
    e
}

/// Every finger on a simulated CiA 402 drive, as `handctl demo --drives cia402` configures them.
fn cia402_settings() -> EngineSettings {
    use driver::drive_config::{Drive, Drives};
    use hand_model::nodes::DriveFingerConfig;
    let fingers = std::array::from_fn(|f| {
        let d = DriveFingerConfig::simulated(f).expect("a simulated drive");
        Drive::Cia402 {
            node: d.node,
            mode: hand_canopen::Mode::CyclicSyncTorque,
            scaling: d.scaling,
        }
    });
    let canopen = driver::drive_config::CanopenConfig::default();
    EngineSettings {
        drives: Drives {
            fingers,
            master: Some((
                hand_canopen::NodeId::try_new(canopen.master_node_id).expect("node id"),
                hand_canopen::CobId::try_new(canopen.sync_cob_id).expect("COB-ID"),
            )),
        },
        ..EngineSettings::default()
    }
}

/// The simulated drives beside the engine, outside the timed part.
struct DriveSims {
    drives: Vec<hand_canopen::sim::SimDrive>,
    /// What the drives sent, for the engine's next tick.
    to_engine: Vec<CanFrame>,
    /// The engine's frames of this tick (its tick's output and its immediate answers).
    from_engine: Vec<CanFrame>,
    scratch: Vec<hand_canopen::CanFrame>,
}

impl DriveSims {
    fn new(settings: &EngineSettings) -> Self {
        let mut scratch = Vec::new();
        let drives = settings
            .drives
            .fingers
            .iter()
            .filter_map(|d| match d {
                driver::drive_config::Drive::Cia402 { node, .. } => {
                    let mut sim = hand_canopen::sim::SimDrive::new(*node);
                    sim.power_on(0, &mut scratch);
                    Some(sim)
                }
                driver::drive_config::Drive::Native => None,
            })
            .collect();
        let mut s = Self {
            drives,
            to_engine: Vec::with_capacity(64),
            from_engine: Vec::with_capacity(64),
            scratch: Vec::with_capacity(64),
        };
        s.to_engine.extend(scratch.drain(..).map(to_dbc));
        s
    }

    /// The engine's frames reach every drive at `now`; what the drives send goes to the engine
    /// next.
    fn exchange(&mut self, now: u64) {
        for f in self.from_engine.drain(..) {
            if let Some(c) = hand_canopen::CanFrame::new(f.raw_id() as u16, f.data()) {
                for d in &mut self.drives {
                    d.on_frame(&c, now, &mut self.scratch);
                }
            }
        }
        for d in &mut self.drives {
            d.poll(now, &mut self.scratch);
        }
        self.to_engine.extend(self.scratch.drain(..).map(to_dbc));
    }
}

fn to_dbc(f: hand_canopen::CanFrame) -> CanFrame {
    CanFrame::new_standard(f.cob_id(), f.payload()).expect("an 11-bit CANopen frame")
}

/// Whether every drive of `engine` follows its target.
fn drives_enabled(engine: &Engine) -> bool {
    (0..5).all(|f| {
        engine
            .drive_status(f)
            .is_none_or(|s| matches!(s, hand_canopen::DriveStatus::Running { enabled: true, .. }))
    })
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

/// One replayed tick: the frames of tick `i` of lap `lap` (and with drives, what they sent
/// since the last tick, received half a tick before the deadline), then `tick` and `written`.
fn run_tick(
    engine: &mut Engine,
    frames: &[(u64, CanFrame)],
    lap: u64,
    deadline: u64,
    sims: Option<&mut DriveSims>,
) -> usize {
    for (t, f) in frames {
        engine.on_frame(f, t + SPAN_US * lap);
    }
    let Some(sims) = sims else {
        let n = engine.tick(deadline, deadline).len();
        engine.written(deadline, 0);
        return n;
    };
    for f in &sims.to_engine {
        engine.on_frame(f, deadline - TICK_US / 2);
        sims.from_engine.extend_from_slice(engine.take_immediate());
    }
    sims.to_engine.clear();
    let out = engine.tick(deadline, deadline);
    let n = out.len();
    sims.from_engine.extend_from_slice(out);
    engine.written(deadline, 0);
    n
}

/// The whole tick over `n_ticks` ticks (with `drives`, every finger on a simulated CiA 402
/// drive): the histogram and the cost of one timer pair, ns.
fn whole_ticks(
    chain: &ChainConfig,
    ticks: &[Vec<(u64, CanFrame)>],
    n_ticks: u64,
    drives: bool,
) -> (Hist, u64) {
    let settings = if drives {
        cia402_settings()
    } else {
        EngineSettings::default()
    };
    let mut sims = drives.then(|| DriveSims::new(&settings));
    let mut engine = engine(chain, settings);
    let mut hist = Hist::new();
    // Warm up one lap, untimed (and with drives, until every drive follows its target).
    let mut warm_laps = 0;
    loop {
        for (i, frames) in ticks.iter().enumerate() {
            let deadline = SPAN_US * warm_laps + (i as u64 + 1) * TICK_US;
            run_tick(&mut engine, frames, warm_laps, deadline, sims.as_mut());
            if let Some(s) = sims.as_mut() {
                s.exchange(deadline);
            }
        }
        warm_laps += 1;
        if drives_enabled(&engine) {
            break;
        }
        assert!(
            warm_laps < 3,
            "the drives did not all start in {warm_laps} laps"
        );
    }
    for k in 0..n_ticks {
        let lap = warm_laps + k / ticks.len() as u64;
        let i = (k % ticks.len() as u64) as usize;
        let deadline = SPAN_US * lap + (i as u64 + 1) * TICK_US;
        let start = ThreadTime::now();
        black_box(run_tick(
            &mut engine,
            &ticks[i],
            lap,
            deadline,
            sims.as_mut(),
        ));
        hist.record(start.elapsed().as_nanos() as u64);
        if let Some(s) = sims.as_mut() {
            s.exchange(deadline);
        }
    }
    assert!(
        drives_enabled(&engine),
        "a drive stopped following its target during the run"
    );
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

/// `--drives cia402`: the tick with five drives, no stage table.
fn main_cia402(chain: &ChainConfig, json: bool, n_ticks: u64) {
    // A drive's finger sends no FINGER_STATUS.
    let ticks: Vec<Vec<(u64, CanFrame)>> = traffic()
        .into_iter()
        .map(|t| {
            t.into_iter()
                .filter(|(_, f)| {
                    hand_dbc::messages::FingerStatus::instance_of(f.raw_id()).is_none()
                })
                .collect()
        })
        .collect();
    let (hist, timer_ns) = whole_ticks(chain, &ticks, n_ticks, true);
    let (p50, p99, max, mean) = (
        hist.quantile_us(0.5),
        hist.quantile_us(0.99),
        hist.max_ns as f64 / 1000.0,
        hist.mean_us(),
    );
    if json {
        println!(
            "{{\"what\":\"daemon_tick_cia402\",\"impl\":\"handstack\",\"ticks\":{},\"us_cpu_median\":{p50:.2},\"us_cpu_p99\":{p99:.2},\"us_cpu_max\":{max:.2},\"us_cpu_mean\":{mean:.2},\"timer_ns\":{timer_ns}}}",
            hist.n
        );
        return;
    }
    println!(
        "{} ticks with five CiA 402 drives (torque mode), CPU time per tick from a {BIN_NS} ns \
         histogram:",
        hist.n
    );
    println!("  median {p50:.2} us, p99 {p99:.2} us, max {max:.2} us, mean {mean:.2} us");
    println!("  (one timer pair costs {timer_ns} ns and is in every tick's figure)");
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
    match args
        .iter()
        .position(|a| a == "--drives")
        .map(|i| args.get(i + 1).map(String::as_str))
    {
        None | Some(Some("native")) => {}
        Some(Some("cia402")) => return main_cia402(&chain, json, n_ticks),
        Some(other) => panic!("--drives {other:?}: native or cia402"),
    }
    let ticks = traffic();
    let frames: usize = ticks.iter().map(Vec::len).sum();
    let (hist, timer_ns) = whole_ticks(&chain, &ticks, n_ticks, false);
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
        (
            "model (normalize, envelope and plausibility, ResDD H=96 L=2, output stage)",
            s.model,
        ),
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
