//! The figures behind the plausibility check's *off the patterns* test
//! (`decoder::model::PatternCone`, issue 25): how far windows' channel powers lie from the
//! cone of their calibration's patterns, on the 3DC recordings and on the simulator, through
//! the same envelope the daemon runs.
//!
//!     cargo run --release -p driver --features sim --example pattern_probe
//!
//! Per set of windows (those whose top channel is above the plausibility floor): how many, the
//! median and largest misfit, and how many pass the bar (the test fires). The 3DC cones are
//! fitted on each participant's train recording (rest, Power Grip as every finger flexed,
//! Open Hand as every finger extended), and the test recording is read at x1, x2 and x3. The
//! simulator's cone is fitted on its calibration (seed 1); then another seed's calibration, the
//! gestures (combinations the calibration never recorded as such), the calibration at 2x and
//! 3x effort, and with the band turned by 0.3 and 0.5 of a spacing.
use decoder::dsp::FEATURES_PER_CHANNEL;
use decoder::model::{Envelope, PLAUSIBLE_FLOOR};
use decoder::session::{load_3dc, LabelledWindows, Session, Split, WindowOptions};
use hand_dbc::candump::LogWriter;
use hand_model::emg::AmplifierConfig;
use hand_model::faults::{Fault, FaultPlan};
use hand_model::nodes::AmplifierNodeConfig;
use hand_model::record::run_on_mem_bus;
use hand_model::world::WorldConfig;
use hand_model::Scenario;
use std::path::Path;

/// The envelope (with its cone) of a calibration's windows, as training fits it.
fn envelope_of(w: &LabelledWindows) -> Envelope {
    Envelope::fit(w.n_features, w.features.chunks_exact(w.n_features))
        .and_then(|e| {
            e.with_patterns(
                w.features
                    .chunks_exact(w.n_features)
                    .zip(w.labels.iter().map(|l| &l.targets)),
            )
        })
        .expect("envelope")
}

/// One line: the windows above the floor, their misfits, how many pass the bar.
fn report(name: &str, env: &Envelope, rows: &[f64], n: usize) {
    let cone = env.cone().expect("the calibration's patterns");
    let mut m: Vec<f64> = rows
        .chunks_exact(n)
        .filter_map(|x| env.pattern_misfit(x))
        .collect();
    m.sort_by(f64::total_cmp);
    let over = m.iter().filter(|v| **v > cone.bar()).count();
    println!(
        "{name}: {} windows above the floor {PLAUSIBLE_FLOOR}; misfit median {:.3}, largest \
         {:.3}; above the bar {:.3}: {over} ({:.1}%)",
        m.len(),
        m.get(m.len() / 2).copied().unwrap_or(0.0),
        m.last().copied().unwrap_or(0.0),
        cone.bar(),
        100.0 * over as f64 / m.len().max(1) as f64
    );
}

/// What the whole plausibility check costs per window of `what`, with the pattern test and
/// without it, in ns: a figure, never a bar (this machine's timing varies by tens of percent).
fn cost(what: &str, env: &Envelope, rows: &[f64], n: usize) {
    let without = env.clone().with_cone(None).expect("envelope");
    let time = |e: &Envelope| {
        let start = std::time::Instant::now();
        let mut hits = 0usize;
        for _ in 0..20 {
            for x in rows.chunks_exact(n) {
                hits += usize::from(e.implausible(std::hint::black_box(x)));
            }
        }
        let per = start.elapsed().as_nanos() as f64 / (20 * rows.len() / n) as f64;
        (per, hits / 20)
    };
    let ((with, hits), (plain, _)) = (time(env), time(&without));
    println!(
        "cost of the plausibility check per window of {what}: {with:.0} ns with the pattern \
         test ({hits} implausible), {plain:.0} ns without"
    );
}

/// `rows` with the signal scaled by `gain` (amplitude features by `gain`, VAR by its square).
fn scaled(rows: &[f64], gain: f64) -> Vec<f64> {
    let var = decoder::dsp::FEATURE_NAMES
        .iter()
        .position(|n| *n == "VAR")
        .expect("VAR");
    rows.iter()
        .enumerate()
        .map(|(j, v)| {
            if j % FEATURES_PER_CHANNEL == var {
                v * gain * gain
            } else {
                v * gain
            }
        })
        .collect()
}

/// Records `scenario` on the simulator with `faults` into `dir` (a session directory).
fn record(dir: &Path, seed: u64, scenario: Scenario, faults: FaultPlan) {
    std::fs::create_dir_all(dir).expect("directory");
    let run = scenario.build(seed).expect("scenario");
    let signal = AmplifierConfig {
        seed,
        ..AmplifierConfig::default()
    };
    let meta = run.session_meta("frames.log", &signal);
    let file = std::fs::File::create(dir.join("frames.log")).expect("frames.log");
    let mut log = LogWriter::new(std::io::BufWriter::new(file));
    let cfg = WorldConfig {
        amplifier: AmplifierNodeConfig {
            signal,
            ..AmplifierNodeConfig::default()
        },
        faults,
        ..WorldConfig::default()
    };
    run_on_mem_bus(cfg, run.patient, run.duration_us, |t, f| {
        log.write_frame(t, "can0", f)
    })
    .expect("simulator")
    .expect("log");
    log.flush().expect("log");
    meta.write(dir).expect("session.toml");
}

fn from(fault: Fault) -> FaultPlan {
    let mut plan = FaultPlan::new();
    plan.add_from(fault, 0).expect("fault");
    plan
}

fn main() {
    let opts = WindowOptions::default();
    for p in [4u32, 6, 7] {
        let d = format!("../shared/data/3dc-armband-p{p}");
        assert!(
            Path::new(&d).exists(),
            "{d} is missing (run from the repo root, with ../shared beside it)"
        );
        let train = load_3dc(Path::new(&d), Split::Train)
            .and_then(|s| s.windows(&opts))
            .expect("train");
        let test = load_3dc(Path::new(&d), Split::Test)
            .and_then(|s| s.windows(&opts))
            .expect("test");
        let env = envelope_of(&train);
        report(
            &format!("P{p} train"),
            &env,
            &train.features,
            train.n_features,
        );
        for gain in [1.0, 2.0, 3.0] {
            let rows = scaled(&test.features, gain);
            report(&format!("P{p} test x{gain}"), &env, &rows, test.n_features);
        }
    }
    let base = std::env::temp_dir().join(format!("pattern-probe-{}", std::process::id()));
    let cal = base.join("calibration");
    record(&cal, 1, Scenario::Calibration, FaultPlan::new());
    let w = Session::open(&cal)
        .and_then(|s| s.windows(&opts))
        .expect("calibration");
    let env = envelope_of(&w);
    println!(
        "simulator: {} patterns",
        env.cone().expect("patterns").patterns().count()
    );
    report("simulator calibration", &env, &w.features, w.n_features);
    let runs = [
        ("another seed's calibration", 2, FaultPlan::new()),
        (
            "calibration at 2x effort",
            1,
            from(Fault::OverEffort { pct: 200 }),
        ),
        (
            "calibration at 3x effort",
            1,
            from(Fault::OverEffort { pct: 300 }),
        ),
        (
            "band turned 0.3 spacing",
            1,
            from(Fault::ElectrodeShift { tenths: 3 }),
        ),
        (
            "band turned 0.5 spacing",
            1,
            from(Fault::ElectrodeShift { tenths: 5 }),
        ),
    ];
    let mut turned = Vec::new();
    for (i, (name, seed, plan)) in runs.into_iter().enumerate() {
        let dir = base.join(format!("run{i}"));
        record(&dir, seed, Scenario::Calibration, plan);
        let w = Session::open(&dir)
            .and_then(|s| s.windows(&opts))
            .expect("session");
        report(name, &env, &w.features, w.n_features);
        turned = w.features;
    }
    cost("the calibration", &env, &w.features, w.n_features);
    cost("the band turned 0.5 spacing", &env, &turned, w.n_features);
    let dir = base.join("gestures");
    record(&dir, 3, Scenario::Gestures, FaultPlan::new());
    let chain = Session::open(&cal).expect("calibration").meta.chain;
    let g = Session::open_recording(&dir.join("frames.log"), &chain)
        .and_then(|s| s.stream_windows())
        .expect("gestures");
    report("gestures", &env, &g.features, g.n_features);
    cost("the gestures", &env, &g.features, g.n_features);
    std::fs::remove_dir_all(&base).expect("clean up");
}
