//! The embedded demo (feature `sim`), in one process over the in-memory bus: the simulated patient is
//! calibrated (rest, maximal flexion and extension of each finger and of the whole hand),
//! ResDD is trained on that session, then the real daemon loop drives the simulated hand
//! while the simulated patient tracks a sine with the index finger. Tracking is scored on the
//! force the index finger's controller reports (divided by the patient's full-scale force)
//! against the target, with the paper's RMSE, MAPE and R².
//!
//! The calibration is always simulated faster than real time (it is a recording); the
//! tracking runs on the system clock in real time, or on a virtual clock with `fast`.

use std::path::{Path, PathBuf};
use std::time::Duration;

use decoder::eval::tracking_metrics;
use decoder::model::{train, EpochReport, ModelKind, ModelSpec, TrainConfig, TrainedModel};
use decoder::session::{check_gates, GateConfig, Session, WindowOptions};
use hand_clock::{Clock, SystemClock, VirtualClock};
use hand_dbc::candump::LogWriter;
use hand_dbc::messages::FingerStatus;
use hand_dbc::CanFrame;
use hand_model::emg::AmplifierConfig;
use hand_model::nodes::AmplifierNodeConfig;
use hand_model::patient::TrackingConfig;
use hand_model::record::run_on_mem_bus;
use hand_model::world::{PatientMode, World, WorldConfig};
use hand_model::{MemBus, MemEndpoint, Scenario};

use crate::config::Config;
use crate::daemon::{Runner, Snapshot};
use crate::engine::Engine;
use crate::mem_transport::MemTransport;
use crate::startup::engine_settings;

/// Settings of a demo run.
#[derive(Debug, Clone)]
pub struct DemoOptions {
    /// Seed of the amplifier's noise and the patient's motor noise.
    pub seed: u64,
    /// Virtual clock for the tracking phase (as fast as the machine goes).
    pub fast: bool,
    /// Length of the tracking phase, s (scored after the first `settle_s`).
    pub track_s: f64,
    /// Tracking time left out of the score while the patient finds the target, s.
    pub settle_s: f64,
    /// Where the calibration session and the model are written.
    pub work_dir: PathBuf,
    /// Training epochs at most.
    pub max_epochs: usize,
}

impl Default for DemoOptions {
    fn default() -> Self {
        Self {
            seed: 1,
            fast: false,
            track_s: 24.0,
            settle_s: 4.0,
            work_dir: std::env::temp_dir().join("handstack-demo"),
            max_epochs: 200,
        }
    }
}

/// What the demo measured.
#[derive(Debug, Clone)]
pub struct DemoReport {
    /// The session directory.
    pub session_dir: PathBuf,
    /// The model file.
    pub model_path: PathBuf,
    /// Calibration trials recorded.
    pub trials: usize,
    /// Training epochs run and time, ms.
    pub epochs: usize,
    /// Training time, ms.
    pub train_ms: u64,
    /// Scored samples (FINGER_STATUS of the index finger, 50 Hz).
    pub samples: usize,
    /// Root mean square error of force/full-scale against the target.
    pub rmse: f64,
    /// MAPE over |target| >= 0.1, percent.
    pub mape: Option<f64>,
    /// Coefficient of determination.
    pub r2: f64,
    /// The daemon's snapshot at the end (latency, deadline misses, ...).
    pub end: Snapshot,
}

/// What the demo tells its caller as it goes.
pub enum DemoEvent<'a> {
    /// A phase starts.
    Phase(&'a str),
    /// One training epoch ended.
    Epoch(EpochReport),
    /// About every 250 ms of tracking: the daemon's snapshot, the target and the index force.
    Live {
        /// Seconds into tracking.
        t_s: f64,
        /// The snapshot.
        snapshot: &'a Snapshot,
        /// Target now.
        target: f64,
        /// Index finger force / full scale.
        tracked: f64,
    },
}

/// Why the demo failed.
#[derive(Debug, thiserror::Error)]
pub enum DemoError {
    /// The simulator refused something.
    #[error("simulator: {0}")]
    Sim(#[from] hand_model::SimError),
    /// Writing or reading the session.
    #[error("session: {0}")]
    Session(#[from] decoder::session::SessionError),
    /// The session failed its quality gates.
    #[error("the calibration session failed its quality gates:\n{0}")]
    Gates(String),
    /// Training.
    #[error("training: {0}")]
    Train(#[from] decoder::model::TrainError),
    /// Saving the model.
    #[error("model file: {0}")]
    File(#[from] decoder::model::FileError),
    /// Files.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        #[source]
        source: std::io::Error,
    },
    /// Scoring.
    #[error("scoring: {0}")]
    Eval(#[from] decoder::eval::EvalError),
}

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> DemoError + '_ {
    move |source| DemoError::Io {
        path: path.to_owned(),
        source,
    }
}

/// Record a simulated calibration session (candump `frames.log` + `session.toml`) in `dir`.
pub fn record_calibration(dir: &Path, seed: u64) -> Result<usize, DemoError> {
    std::fs::create_dir_all(dir).map_err(io(dir))?;
    let run = Scenario::Calibration.build(seed)?;
    let signal = AmplifierConfig {
        seed,
        ..AmplifierConfig::default()
    };
    let meta = run.session_meta("frames.log", &signal);
    let log_path = dir.join("frames.log");
    let file = std::fs::File::create(&log_path).map_err(io(&log_path))?;
    let mut log = LogWriter::new(std::io::BufWriter::new(file));
    let cfg = WorldConfig {
        amplifier: AmplifierNodeConfig {
            signal,
            ..AmplifierNodeConfig::default()
        },
        ..WorldConfig::default()
    };
    run_on_mem_bus(cfg, run.patient, run.duration_us, |t, f| {
        log.write_frame(t, "can0", f)
    })?
    .map_err(io(&log_path))?;
    log.flush().map_err(io(&log_path))?;
    meta.write(dir)?;
    Ok(run.trials.len())
}

/// ResDD (default specification) trained on `session`'s labelled windows, seeded.
pub fn train_on_session(
    session: &Session,
    seed: u64,
    max_epochs: usize,
    on_epoch: &mut dyn FnMut(EpochReport),
) -> Result<TrainedModel, DemoError> {
    let data = session
        .windows(&WindowOptions { two_point: false })?
        .to_dataset(&session.meta.chain)?;
    let cfg = TrainConfig {
        max_epochs,
        seed,
        ..TrainConfig::default()
    };
    Ok(train(
        ModelKind::ResDd,
        &ModelSpec::default(),
        &data,
        &cfg,
        on_epoch,
    )?)
}

/// Calibrate, train, track; see the module docs.
pub fn run_demo(
    opts: &DemoOptions,
    mut on: impl FnMut(DemoEvent<'_>),
) -> Result<DemoReport, DemoError> {
    on(DemoEvent::Phase(
        "calibration: recording rest, flexion and extension of each finger",
    ));
    let session_dir = opts.work_dir.join("session");
    let trials = record_calibration(&session_dir, opts.seed)?;
    let session = Session::open(&session_dir)?;
    let gates = check_gates(&session, &GateConfig::default())?;
    if !gates.passed() {
        return Err(DemoError::Gates(gates.to_string()));
    }

    on(DemoEvent::Phase(
        "training ResDD on the calibration session",
    ));
    let model = train_on_session(&session, opts.seed, opts.max_epochs, &mut |r| {
        on(DemoEvent::Epoch(r))
    })?;
    let model_path = opts.work_dir.join("model.hsm");
    model.save(&model_path)?;

    on(DemoEvent::Phase(
        "tracking: the daemon drives the hand, the patient follows a sine with the index finger",
    ));
    let (samples, end) = if opts.fast {
        track(&model, opts, VirtualClock::new(), true, &mut on)?
    } else {
        track(&model, opts, SystemClock::new(), false, &mut on)?
    };
    let skip = (opts.settle_s * 50.0) as usize;
    let scored = samples.get(skip..).unwrap_or(&[]);
    let target: Vec<f64> = scored.iter().map(|s| s.0).collect();
    let tracked: Vec<f64> = scored.iter().map(|s| s.1).collect();
    let m = tracking_metrics(&target, &tracked)?;
    let s = model.summary();
    Ok(DemoReport {
        session_dir,
        model_path,
        trials,
        epochs: s.epochs_run,
        train_ms: s.duration_ms,
        samples: scored.len(),
        rmse: m.rmse,
        mape: m.mape,
        r2: m.r2,
        end,
    })
}

/// A clock the demo can also move by hand (virtual) or only read (system).
trait DemoClock: Clock + Clone + Send + Sync + 'static {
    fn set(&self, _t_us: u64) {}
}
impl DemoClock for VirtualClock {
    fn set(&self, t_us: u64) {
        self.set_us(t_us);
    }
}
impl DemoClock for SystemClock {}

/// The tracking phase's closed loop, ready to run: the simulated world (amplifier, the five
/// finger controllers, the patient following a sine with one finger) and the daemon's loop
/// with the default configuration, on one in-memory bus that reads `clock`.
pub struct ClosedLoop<K: Clock> {
    /// The simulated hand, amplifier and patient.
    pub world: World<MemEndpoint<CanFrame>>,
    /// The daemon's loop (validated, so it runs as soon as EMG arrives).
    pub runner: Runner<MemTransport<K>, K>,
    /// The bus (for more endpoints).
    pub bus: MemBus,
    /// Start of the loop on `clock`, µs.
    pub start_us: u64,
    /// What the patient tracks.
    pub tracking: TrackingConfig,
}

/// Builds the [`ClosedLoop`] for `model`; `seed` seeds the patient (and, plus one, the
/// amplifier's noise).
pub fn closed_loop<K: Clock + Clone + Send + Sync + 'static>(
    model: &TrainedModel,
    seed: u64,
    clock: K,
) -> Result<ClosedLoop<K>, DemoError> {
    let tracking = TrackingConfig {
        seed,
        ..TrackingConfig::default()
    };
    let patient = hand_model::patient::ClosedLoopUser::try_new(tracking)?;
    let bus = MemBus::with_clock(clock.clone());
    let b = bus.clone();
    let start_us = clock.now_us();
    let world = World::try_new(
        WorldConfig {
            amplifier: AmplifierNodeConfig {
                signal: AmplifierConfig {
                    seed: seed + 1,
                    ..AmplifierConfig::default()
                },
                ..AmplifierNodeConfig::default()
            },
            start_us,
            ..WorldConfig::default()
        },
        PatientMode::ClosedLoop(Box::new(patient)),
        || Ok::<_, String>(b.endpoint()),
    )?;
    let chain = model
        .chain()
        .validate()
        .map_err(|e| DemoError::Gates(format!("the model's chain is invalid: {e}")))?;
    let config = Config::default();
    let mut engine = Engine::new(
        &chain,
        model.predictor(),
        engine_settings(&config, 0),
        clock.now_us(),
    );
    engine.validated(clock.now_us());
    let transport = MemTransport::new(bus.endpoint(), clock.clone());
    let runner = Runner::new(engine, transport, clock, config.tick_ms * 1000);
    Ok(ClosedLoop {
        world,
        runner,
        bus,
        start_us,
        tracking,
    })
}

/// Runs the closed loop; returns (target, tracked) at every index FINGER_STATUS.
fn track<K: DemoClock>(
    model: &TrainedModel,
    opts: &DemoOptions,
    clock: K,
    virtual_time: bool,
    on: &mut impl FnMut(DemoEvent<'_>),
) -> Result<(Vec<(f64, f64)>, Snapshot), DemoError> {
    let ClosedLoop {
        mut world,
        mut runner,
        bus,
        start_us: start,
        tracking,
    } = closed_loop(model, opts.seed, clock.clone())?;
    let mut probe = bus.endpoint();
    let end = start + (opts.track_s * 1e6) as u64;
    let mut samples = Vec::new();
    let mut next_live = start;
    let mut now = start;
    let mut tracked = 0.0;
    while now < end {
        now = if virtual_time {
            let t = now + 1000;
            clock.set(t);
            t
        } else {
            let next = (clock.now_us() / 1000 + 1) * 1000;
            std::thread::sleep(Duration::from_micros(next.saturating_sub(clock.now_us())));
            clock.now_us()
        };
        world.step(now);
        if now >= runner.next_deadline_us() {
            runner.step();
        }
        while let Some(r) = probe.receive_timestamped() {
            let id = r.frame.raw_id();
            if FingerStatus::instance_of(id) == Some(tracking.finger) {
                if let Ok(st) = FingerStatus::decode(id, r.frame.data()) {
                    let t = r.time_us.unwrap_or(now).saturating_sub(start);
                    tracked = st.force() / tracking.full_scale_force_n;
                    samples.push((tracking.target.at(t), tracked));
                }
            }
        }
        if now >= next_live {
            next_live += 250_000;
            let snap = *runner.snapshot().lock().unwrap_or_else(|e| e.into_inner());
            let t = now.saturating_sub(start);
            on(DemoEvent::Live {
                t_s: t as f64 * 1e-6,
                snapshot: &snap,
                target: tracking.target.at(t),
                tracked,
            });
        }
    }
    let snap = *runner.snapshot().lock().unwrap_or_else(|e| e.into_inner());
    Ok((samples, snap))
}
