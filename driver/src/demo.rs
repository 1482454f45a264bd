//! The embedded demo (feature `sim`), in one process over the in-memory bus: the simulated patient is
//! calibrated (rest, maximal flexion and extension of each finger and of the whole hand),
//! ResDD is trained on that session and verified as `handctl train` verifies it (every
//! calibration ray, exactly; a model that reverses beyond the default tolerance is refused, as
//! `handctl train` refuses it without `--force`), then the real daemon loop drives the simulated hand
//! while the simulated patient tracks a sine with the index finger. Tracking is scored on the
//! force the index finger's controller reports (divided by the patient's full-scale force)
//! against the target, with the paper's RMSE, MAPE and R².
//!
//! The calibration is always simulated faster than real time (it is a recording); the
//! tracking runs on the system clock in real time, or on a virtual clock with `fast`.
//!
//! With [`DriveProfile::Cia402`] every finger of the tracking phase is moved by a simulated
//! CiA 402 drive (`hand_model::nodes::DriveFingerNode`, node 5 + finger, in the profile's mode:
//! cyclic synchronous torque, or velocity with the force as its torque limit) that handd starts
//! over the bus and drives as a handd.toml with `[fingers.NAME.drive] profile = "cia402"` asks; the patient then feels the index finger's
//! force from the finger itself (a drive sends no FINGER_STATUS), and the score reads it there.

use std::path::{Path, PathBuf};
use std::time::Duration;

use decoder::eval::tracking_metrics;
use decoder::model::verify::{
    verify_windows, RayVerifier, VerificationRecord, VerifyError, DEFAULT_TOLERANCE,
};
use decoder::model::{
    train, EpochReport, ModelKind, ModelSpec, TrainConfig, TrainedModel, N_FINGERS,
};
use decoder::session::{check_gates, GateConfig, LabelledWindows, Session, WindowOptions};
use hand_clock::{Clock, SystemClock, VirtualClock};
use hand_dbc::candump::LogWriter;
use hand_dbc::messages::{FingerSetpoint, FingerStatus};
use hand_dbc::CanFrame;
use hand_model::emg::AmplifierConfig;
use hand_model::nodes::drive::simulated_node_id;
use hand_model::nodes::{AmplifierNodeConfig, DriveFingerConfig};
use hand_model::patient::TrackingConfig;
use hand_model::record::run_on_mem_bus;
use hand_model::world::{PatientMode, World, WorldConfig};
use hand_model::{MemBus, MemEndpoint, Scenario};

use crate::config::{Config, ConfigError};
use crate::daemon::{Runner, Snapshot};
use crate::drive_config::{DriveConfig, DriveMode, Profile};
use crate::engine::{Command, Engine};
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
    /// The paper's plain training, without the effort-ray penalty.
    pub plain: bool,
    /// The paper's labels: the fingers a single-finger trial does not move are masked out of
    /// the loss instead of trained toward 0.
    pub mask_others: bool,
    /// The output law of the tracking phase: the shipped one, or the paper's pure integrator.
    pub law: OutputLaw,
    /// What moves the fingers in the tracking phase.
    pub drives: DriveProfile,
}

/// What moves the demo's fingers.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum DriveProfile {
    /// hand.dbc's native finger controllers (FINGER_SETPOINT, FINGER_STATUS).
    #[default]
    Native,
    /// A simulated CiA 402 drive per finger, started and driven by handd over CANopen in this
    /// mode.
    Cia402(DriveMode),
}

impl DriveProfile {
    /// The daemon's configuration for this profile: the defaults, and for CiA 402 each
    /// finger's `[fingers.NAME.drive]` table as a technician would write it for the simulated
    /// drives (node 5 + finger, the profile's mode, their scaling).
    pub fn config(self) -> Config {
        let mut config = Config::default();
        if let Self::Cia402(mode) = self {
            let s = DriveFingerConfig::SIM_SCALING;
            for f in 0..N_FINGERS {
                config.fingers.get_mut(f).drive = DriveConfig {
                    profile: Profile::Cia402,
                    node_id: Some(simulated_node_id(f)),
                    mode: Some(mode),
                    rated_torque_mnm: Some(s.rated_torque_mnm),
                    gear_ratio: Some(s.gear_ratio),
                    moment_arm_m: Some(s.moment_arm_m),
                    max_torque_permille: Some(s.max_torque_permille),
                    max_speed_rpm: Some(s.max_speed_rpm),
                };
            }
        }
        config
    }

    /// The simulated world's drives for this profile.
    fn world_drives(self) -> Result<[Option<DriveFingerConfig>; N_FINGERS], DemoError> {
        let mut out = [None; N_FINGERS];
        if matches!(self, Self::Cia402(_)) {
            for (f, slot) in out.iter_mut().enumerate() {
                *slot = Some(DriveFingerConfig::simulated(f)?);
            }
        }
        Ok(out)
    }
}

/// Which velocity law the tracking phase's conditioners run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum OutputLaw {
    /// The shipped defaults: ω decays at rest and while driven (no wind-up).
    #[default]
    Shipped,
    /// The paper's law: `ω = ω0 + α·t`, held at rest ([`crate::conditioner::FingerGains::paper_law`]).
    Paper,
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
            plain: false,
            mask_others: false,
            law: OutputLaw::Shipped,
            drives: DriveProfile::Native,
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
    /// The verification of the model's calibration rays, as its file records it.
    pub verification: VerificationRecord,
    /// The tracking phase.
    pub tracking: TrackingReport,
}

/// What the tracking phase measured.
#[derive(Debug, Clone)]
pub struct TrackingReport {
    /// Scored samples (the index finger's force at 50 Hz: its FINGER_STATUS, or read off the
    /// finger when a CiA 402 drive moves it).
    pub samples: usize,
    /// Root mean square error of force/full-scale against the target.
    pub rmse: f64,
    /// MAPE over |target| >= 0.1, percent.
    pub mape: Option<f64>,
    /// Coefficient of determination.
    pub r2: f64,
    /// Selectivity: per finger (0 thumb .. 4 pinky), the mean |label| the decoder gave it over
    /// the scored samples, while only the index finger moves (the other fingers should stay
    /// near 0).
    pub mean_abs_label: [f64; N_FINGERS],
    /// Per finger, the mean |velocity setpoint| handd sent over the scored time, rad/s: what
    /// the output law makes of the labels (the fingers the patient does not move should stay
    /// near 0). For a finger on a CiA 402 drive (in any mode), the joint's mean |velocity|.
    pub mean_abs_velocity: [f64; N_FINGERS],
    /// Per finger, the time its controller reported being at a joint stop with the command
    /// pushing into it (FINGER_STATUS fault bit 5) over the scored time, s.
    pub at_stop_s: [f64; N_FINGERS],
    /// Per finger, the entries into a joint stop over the whole tracking (the simulated
    /// controller counts them) and the fastest, rad/s.
    pub impacts: [(u64, f64); N_FINGERS],
    /// The CiA 402 drives ([`DriveProfile::Cia402`]).
    pub drives: DrivesRecord,
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
    /// The verification could not run.
    #[error("verification: {0}")]
    Verify(#[from] VerifyError),
    /// The model could not record its verification or rest level.
    #[error("model: {0}")]
    Model(#[from] decoder::model::ModelError),
    /// The trained model goes back against the effort on some calibration ray: refused, as
    /// `handctl train` refuses it.
    #[error("the trained model is refused, as handctl train refuses it: {0}")]
    Reverses(String),
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
    /// The daemon's configuration for the chosen drives is refused.
    #[error("the demo's configuration: {0}")]
    Config(#[from] ConfigError),
}

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> DemoError + '_ {
    move |source| DemoError::Io {
        path: path.to_owned(),
        source,
    }
}

/// Record a simulated calibration session (candump `frames.log` + `session.toml`) in `dir`.
pub fn record_calibration(dir: &Path, seed: u64) -> Result<usize, DemoError> {
    record_scenario(dir, seed, Scenario::Calibration)
}

/// [`record_calibration`] with another scripted calibration scenario (e.g.
/// [`Scenario::CalibrationQuick`], the 0.5 s plateaus of `CalibrationProtocol::quick`).
pub fn record_scenario(dir: &Path, seed: u64, scenario: Scenario) -> Result<usize, DemoError> {
    std::fs::create_dir_all(dir).map_err(io(dir))?;
    let run = scenario.build(seed)?;
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

/// The demo's calibration for `seed` recorded into a scratch directory under the system's
/// temporary directory (named after the process), trained with the demo's options
/// ([`train_on_session`]), the directory removed: the model a calibrated handd runs in the
/// simulated world, for tests and the tick benchmark.
pub fn calibrated_model(seed: u64) -> Result<TrainedModel, DemoError> {
    let dir = std::env::temp_dir().join(format!("handstack-cal-{}-{seed}", std::process::id()));
    let opts = DemoOptions {
        work_dir: dir.clone(),
        seed,
        ..DemoOptions::default()
    };
    record_calibration(&dir, seed)?;
    let model = train_on_session(&Session::open(&dir)?, &opts, &mut |_| {});
    std::fs::remove_dir_all(&dir).map_err(io(&dir))?;
    model
}

/// ResDD trained on `session`'s calibration with the demo's label and training options, then
/// verified as `handctl train` verifies it ([`certify`]); the long-run script trains the same way.
pub fn train_on_session(
    session: &Session,
    opts: &DemoOptions,
    on_epoch: &mut dyn FnMut(EpochReport),
) -> Result<TrainedModel, DemoError> {
    let windows = session.windows(&WindowOptions {
        mask_others: opts.mask_others,
        ..WindowOptions::default()
    })?;
    let data = windows.to_dataset(&session.meta.chain)?;
    let base = if opts.plain {
        TrainConfig::plain()
    } else {
        TrainConfig::default()
    };
    let cfg = TrainConfig {
        max_epochs: opts.max_epochs,
        seed: opts.seed,
        ..base
    };
    let model = train(
        ModelKind::ResDd,
        &ModelSpec::default(),
        &data,
        &cfg,
        on_epoch,
    )?;
    certify(model, session, &windows, opts.plain)
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
        "training ResDD on the calibration session and verifying its effort rays",
    ));
    let model = train_on_session(&session, opts, &mut |r| on(DemoEvent::Epoch(r)))?;
    let model_path = opts.work_dir.join("model.hsm");
    model.save(&model_path)?;

    let tracking = track_model(&model, opts, &mut on)?;
    let s = model.summary();
    Ok(DemoReport {
        session_dir,
        model_path,
        trials,
        epochs: s.epochs_run,
        train_ms: s.duration_ms,
        verification: model.verification().cloned().expect("certify recorded it"),
        tracking,
    })
}

/// The demo's tracking phase alone, with `model` (trained and certified): the daemon's loop
/// drives the simulated hand as `opts.drives` says while the patient tracks the sine; scored
/// after `opts.settle_s`.
pub fn track_model(
    model: &TrainedModel,
    opts: &DemoOptions,
    mut on: impl FnMut(DemoEvent<'_>),
) -> Result<TrackingReport, DemoError> {
    on(DemoEvent::Phase(match opts.drives {
        DriveProfile::Native => {
            "tracking: the daemon drives the hand, the patient follows a sine with the index finger"
        }
        DriveProfile::Cia402(DriveMode::Cst) => {
            "tracking: the daemon starts a CiA 402 drive per finger and drives the hand through \
             them in torque mode (cst), the patient follows a sine with the index finger"
        }
        DriveProfile::Cia402(DriveMode::Csv | DriveMode::Pv) => {
            "tracking: the daemon starts a CiA 402 drive per finger and drives the hand through \
             them in velocity mode with the force as torque limit, the patient follows a sine \
             with the index finger"
        }
    }));
    let (
        Tracked {
            samples,
            motion,
            drives,
        },
        end,
    ) = if opts.fast {
        track(model, opts, VirtualClock::new(), true, &mut on)?
    } else {
        track(model, opts, SystemClock::new(), false, &mut on)?
    };
    let skip = (opts.settle_s * 50.0) as usize;
    let scored = samples.get(skip..).unwrap_or(&[]);
    let target: Vec<f64> = scored.iter().map(|s| s.target).collect();
    let tracked: Vec<f64> = scored.iter().map(|s| s.tracked).collect();
    let n = scored.len().max(1) as f64;
    let mean_abs_label: [f64; N_FINGERS] =
        std::array::from_fn(|f| scored.iter().map(|s| s.labels[f].abs()).sum::<f64>() / n);
    let m = tracking_metrics(&target, &tracked)?;
    Ok(TrackingReport {
        samples: scored.len(),
        rmse: m.rmse,
        mape: m.mape,
        r2: m.r2,
        mean_abs_label,
        mean_abs_velocity: std::array::from_fn(|f| {
            motion.abs_velocity[f] / motion.rounds[f].max(1) as f64
        }),
        at_stop_s: motion.at_stop_s,
        impacts: motion.impacts,
        drives,
        end,
    })
}

/// Verifies every calibration ray of `model` as `handctl train` does (no `--force`: a
/// reversing model is refused) and records the verification and the calibration's rest level.
/// Verifies the model's effort rays as `handctl train` does and refuses a reversing model,
/// unless the demo was asked for the paper's plain training (`paper`), whose reversals are
/// what it is there to show: that model is kept and its file says FORCED.
fn certify(
    model: TrainedModel,
    session: &Session,
    windows: &LabelledWindows,
    paper: bool,
) -> Result<TrainedModel, DemoError> {
    let trials = &session.meta.trials;
    let report = verify_windows(
        &mut RayVerifier::new(&model),
        windows,
        trials,
        DEFAULT_TOLERANCE,
    )?;
    let record = VerificationRecord::from_report(&report, paper);
    if !record.passed() && !paper {
        return Err(DemoError::Reverses(record.to_string()));
    }
    let model = model.with_verification(record)?;
    Ok(match windows.rest_rms(trials) {
        Some(levels) => model.with_rest_rms_uv(levels)?,
        None => model,
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

/// Builds the [`ClosedLoop`] for `model` with native fingers; `seed` seeds the patient (and,
/// plus one, the amplifier's noise).
pub fn closed_loop<K: Clock + Clone + Send + Sync + 'static>(
    model: &TrainedModel,
    seed: u64,
    clock: K,
) -> Result<ClosedLoop<K>, DemoError> {
    closed_loop_with(model, seed, clock, DriveProfile::Native)
}

/// As [`closed_loop`], the fingers moved as `drives` says.
pub fn closed_loop_with<K: Clock + Clone + Send + Sync + 'static>(
    model: &TrainedModel,
    seed: u64,
    clock: K,
    drives: DriveProfile,
) -> Result<ClosedLoop<K>, DemoError> {
    let config = drives.config();
    // The drive table checked as handd checks handd.toml, before the engine takes it.
    config.drives()?;
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
            drives: drives.world_drives()?,
            ..WorldConfig::default()
        },
        PatientMode::ClosedLoop(Box::new(patient)),
        || Ok::<_, String>(b.endpoint()),
    )?;
    let chain = model
        .chain()
        .validate()
        .map_err(|e| DemoError::Gates(format!("the model's chain is invalid: {e}")))?;
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

/// One scored moment: at an index FINGER_STATUS.
struct TrackSample {
    /// The sine's target.
    target: f64,
    /// The index finger's force / full scale.
    tracked: f64,
    /// The decoder's raw label of every finger (before conditioning), from the snapshot.
    labels: [f64; N_FINGERS],
}

/// What every finger did over the scored time.
#[derive(Debug, Default)]
struct Motion {
    /// Velocities summed per finger (setpoints seen, or ticks for a drive's finger).
    rounds: [usize; N_FINGERS],
    /// Sum of |velocity| per finger: of the setpoint handd sent a native controller, of the
    /// joint for a finger on a CiA 402 drive (a torque-mode drive gets a torque, not a speed).
    abs_velocity: [f64; N_FINGERS],
    /// Seconds at a joint stop per finger (FINGER_STATUS bit 5, one status period each).
    at_stop_s: [f64; N_FINGERS],
    /// Impacts into a joint stop per finger, and the fastest.
    impacts: [(u64, f64); N_FINGERS],
}

/// The tracking phase's record.
struct Tracked {
    samples: Vec<TrackSample>,
    motion: Motion,
    drives: DrivesRecord,
}

/// How the CiA 402 drives came up (all zero with native fingers).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct DrivesRecord {
    /// Drives handd ran.
    pub drives: usize,
    /// When every drive first followed its target (Operation enabled), s after the loop
    /// started; None if they never all did.
    pub all_enabled_s: Option<f64>,
    /// Drives following their target at the end.
    pub enabled_at_end: usize,
}

/// Drives handd runs and how many of them follow their target now.
fn drives_enabled(engine: &Engine) -> (usize, usize) {
    (0..N_FINGERS)
        .filter_map(|f| engine.drive_status(f))
        .fold((0, 0), |(n, on), s| {
            let enabled = matches!(s, hand_canopen::DriveStatus::Running { enabled: true, .. });
            (n + 1, on + usize::from(enabled))
        })
}

/// FINGER_STATUS fault bit 5: at a joint stop, the command pushing into it.
const STATUS_JOINT_LIMIT: u8 = 1 << 5;

/// Runs the closed loop; returns a sample at every index FINGER_STATUS and every finger's
/// motion after the settling time.
fn track<K: DemoClock>(
    model: &TrainedModel,
    opts: &DemoOptions,
    clock: K,
    virtual_time: bool,
    on: &mut impl FnMut(DemoEvent<'_>),
) -> Result<(Tracked, Snapshot), DemoError> {
    let ClosedLoop {
        mut world,
        mut runner,
        bus,
        start_us: start,
        tracking,
    } = closed_loop_with(model, opts.seed, clock.clone(), opts.drives)?;
    if opts.law == OutputLaw::Paper {
        for f in 0..N_FINGERS {
            let g = runner.engine().gains()[f].paper_law();
            runner
                .engine_mut()
                .command(start, Command::SetGains(f, g))
                .map_err(|e| DemoError::Gates(format!("the paper's law: {e}")))?;
        }
    }
    let scored_from = start + (opts.settle_s * 1e6) as u64;
    let status_period_s = 0.02;
    let mut motion = Motion::default();
    let mut probe = bus.endpoint();
    let end = start + (opts.track_s * 1e6) as u64;
    let mut samples = Vec::new();
    let mut next_live = start;
    let mut next_felt = start;
    let mut drives = DrivesRecord::default();
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
        // As the daemon's real-time loop: the tick at its deadline, the bus read in between
        // (a CiA 402 drive's start-up answers go out at once, not at the next tick).
        if now >= runner.next_deadline_us() {
            runner.step();
            let (n, on) = drives_enabled(runner.engine());
            if n > 0 && on == n && drives.all_enabled_s.is_none() {
                drives.all_enabled_s = Some(now.saturating_sub(start) as f64 * 1e-6);
            }
            if now >= scored_from {
                for d in world.drive_fingers() {
                    let f = d.finger();
                    motion.abs_velocity[f] += d.physics().velocity_rad_s.abs();
                    motion.rounds[f] += 1;
                }
            }
        } else if now >= runner.next_wake_us() {
            runner.service_bus();
        }
        // A drive's finger reports no FINGER_STATUS: read at the native status rate.
        if now >= next_felt {
            next_felt += (status_period_s * 1e6) as u64;
            for d in world.drive_fingers() {
                let (f, p) = (d.finger(), d.physics());
                if now >= scored_from && p.at_limit {
                    motion.at_stop_s[f] += status_period_s;
                }
                if f == tracking.finger {
                    tracked = p.force_n / tracking.full_scale_force_n;
                    let snap = *runner.snapshot().lock().unwrap_or_else(|e| e.into_inner());
                    samples.push(TrackSample {
                        target: tracking.target.at(now.saturating_sub(start)),
                        tracked,
                        labels: snap.labels,
                    });
                }
            }
        }
        while let Some(r) = probe.receive_timestamped() {
            let id = r.frame.raw_id();
            let at = r.time_us.unwrap_or(now);
            if at >= scored_from {
                if let Some(f) = FingerSetpoint::instance_of(id) {
                    if let Ok(sp) = FingerSetpoint::decode(id, r.frame.data()) {
                        motion.abs_velocity[f] += sp.velocity().abs();
                        motion.rounds[f] += 1;
                    }
                }
                if let Some(f) = FingerStatus::instance_of(id) {
                    if let Ok(st) = FingerStatus::decode(id, r.frame.data()) {
                        if st.faults() & STATUS_JOINT_LIMIT != 0 {
                            motion.at_stop_s[f] += status_period_s;
                        }
                    }
                }
            }
            if FingerStatus::instance_of(id) == Some(tracking.finger) {
                if let Ok(st) = FingerStatus::decode(id, r.frame.data()) {
                    let t = r.time_us.unwrap_or(now).saturating_sub(start);
                    tracked = st.force() / tracking.full_scale_force_n;
                    let snap = *runner.snapshot().lock().unwrap_or_else(|e| e.into_inner());
                    samples.push(TrackSample {
                        target: tracking.target.at(t),
                        tracked,
                        labels: snap.labels,
                    });
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
    for finger in world.fingers() {
        let m = finger.motion_stats();
        motion.impacts[finger.finger()] = (m.impacts, m.max_impact_speed_rad_s);
    }
    for d in world.drive_fingers() {
        let m = d.physics().stats;
        motion.impacts[d.finger()] = (m.impacts, m.max_impact_speed_rad_s);
    }
    (drives.drives, drives.enabled_at_end) = drives_enabled(runner.engine());
    let snap = *runner.snapshot().lock().unwrap_or_else(|e| e.into_inner());
    Ok((
        Tracked {
            samples,
            motion,
            drives,
        },
        snap,
    ))
}
