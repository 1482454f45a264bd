//! Command-line arguments.

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand};
use decoder::model::ModelKind;

/// Technician tool for the handstack prosthesis.
#[derive(Debug, Parser)]
#[command(name = "handctl", version, about)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// The subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Train a model from a calibration session and write the model file.
    Train(TrainArgs),
    /// Train the named models on a session and score them as in the paper (Tables 3 and 4).
    Eval(EvalArgs),
    /// Write a session directory for the 3DC armband recordings (a proxy calibration).
    #[command(name = "import-3dc")]
    Import3dc(Import3dcArgs),
    /// Run the quality gates on a session and say which trials to redo.
    Check(CheckArgs),
    /// Check that a model's every finger follows the effort monotonically along each
    /// calibration window's effort ray (exact for ResDD and LN, sampled for MLP and CNN).
    Verify(VerifyArgs),
    /// Write a session directory from an external recording: samples (NPY or CSV) plus a
    /// label table CSV with the header finger,kind,repetition,start_sample,end_sample.
    Import(ImportArgs),
    /// Run a model over every window of a session's recording and write, per window, its
    /// time and the five outputs as CSV; with a reference signal (import --reference), print
    /// how well the finger's output follows it (R², RMSE, Pearson r).
    Decode(DecodeArgs),
    /// Show the running daemon's state, faults, latency and per-finger values.
    Status(StatusArgs),
    /// Change one finger's kF and/or kα on the running daemon (saved to its config).
    Tune(TuneArgs),
    /// Clear latched faults (E-stop, bus-off, repeated E2E errors, stop), once the last second
    /// of the patient at rest shows the electrodes where the running model's calibration had
    /// them.
    Arm(ArmArgs),
    /// Safe-stop every finger until `handctl arm`.
    Stop(DaemonOpts),
    /// Swap a model into the running daemon at a tick boundary, without a restart (checked
    /// first: file, shape, chain, verification); the config is updated to name it.
    Deploy(DeployArgs),
    /// Swap back the model the last deploy (or rollback) replaced.
    Rollback(DaemonOpts),
    /// The live view of the hand: EMG per channel, fingers, the daemon, a plot; from the
    /// running daemon (default), the bus (--iface, no daemon needed) or a candump log (--log).
    Monitor(MonitorArgs),
    /// Record a CAN bus to DIR/frames.log (candump) and, with handsim's trials, a session.
    Record(RecordArgs),
    /// Replay a tape that handd recorded (`handd --tape FILE`) through a fresh engine and check
    /// that every tick gives the frames handd computed, bit for bit.
    Replay(ReplayArgs),
    /// The guided calibration of a patient: cues (terminal and bus), recording, a check of
    /// every trial (a failing one repeated at once), training, verification and a summary;
    /// writes DIR/session.toml, DIR/frames.log and DIR/model.hsm.
    Calibrate(CalibrateArgs),
    /// The whole system in one process: calibrate the simulated patient, train ResDD, drive
    /// the simulated hand while the patient tracks a sine, and score the tracking (needs a
    /// handctl built with the `sim` feature).
    Demo(DemoArgs),
    /// Print the shell completion script for SHELL (bash, zsh, fish, elvish, powershell) to
    /// standard output; the Debian package installs bash's, zsh's and fish's.
    Completions(CompletionsArgs),
    /// Write handctl's manual pages (roff, section 1: handctl.1 and handctl-SUBCOMMAND.1 for
    /// every subcommand) into DIR (the package installs them).
    #[command(hide = true)]
    Man(ManArgs),
}

/// `handctl man`.
#[derive(Debug, Args)]
pub struct ManArgs {
    /// Directory to write the pages into (created if missing).
    pub dir: PathBuf,
}

/// `handctl completions`.
#[derive(Debug, Args)]
pub struct CompletionsArgs {
    /// The shell.
    #[arg(value_enum)]
    pub shell: clap_complete::Shell,
}

/// How to reach the running daemon.
#[derive(Debug, Clone, Args)]
pub struct DaemonOpts {
    /// handd's control socket (default: the one in the config file).
    #[arg(long)]
    pub socket: Option<PathBuf>,
    /// handd's config file, to find the socket (default /etc/handstack/handd.toml); `monitor
    /// --iface/--log` also shows the CiA 402 drives it names.
    #[arg(long)]
    pub config: Option<PathBuf>,
}

/// `handctl arm`.
#[derive(Debug, Args)]
pub struct ArmArgs {
    /// Arm although the live rest pattern per channel differs from the running model's
    /// calibration (swapped or shifted electrodes?); recorded in handd's audit log.
    #[arg(long)]
    pub force_rest_mismatch: bool,
    #[command(flatten)]
    pub daemon: DaemonOpts,
}

/// `handctl status`.
#[derive(Debug, Args)]
pub struct StatusArgs {
    #[command(flatten)]
    pub daemon: DaemonOpts,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
}

/// `handctl tune`.
#[derive(Debug, Args)]
pub struct TuneArgs {
    /// Finger: thumb, index, middle, ring, pinky (or 0-4).
    #[arg(long)]
    pub finger: String,
    /// New force gain kF, N per label unit (0 to 40).
    #[arg(long)]
    pub kf: Option<f64>,
    /// New acceleration gain kα, rad/s² per label unit (0 to 50).
    #[arg(long)]
    pub kalpha: Option<f64>,
    #[command(flatten)]
    pub daemon: DaemonOpts,
}

/// `handctl deploy`.
#[derive(Debug, Args)]
pub struct DeployArgs {
    /// The model file (`handctl train` or `handctl calibrate` wrote it).
    pub model: PathBuf,
    /// Deploy a model whose file records no verification, or a failed one.
    #[arg(long)]
    pub force: bool,
    /// Do not ask: deploy even when the model's patient differs from the running model's (or
    /// either is unknown). Without it, and without a terminal to ask on, such a deploy fails.
    #[arg(long)]
    pub yes: bool,
    #[command(flatten)]
    pub daemon: DaemonOpts,
}

/// `handctl monitor`.
#[derive(Debug, Args)]
pub struct MonitorArgs {
    #[command(flatten)]
    pub daemon: DaemonOpts,
    /// Listen to this CAN interface instead of the daemon (listen-only: an electrode check
    /// before handd runs).
    #[arg(long, conflicts_with = "log")]
    pub iface: Option<String>,
    /// Replay this candump log instead of the daemon.
    #[arg(long)]
    pub log: Option<PathBuf>,
    /// Replay speed of --log, times the recorded pace (0: as fast as possible).
    #[arg(long, default_value_t = 1.0, value_parser = parse_speed)]
    pub speed: f64,
    /// Replay --log as fast as possible (as --speed 0).
    #[arg(long)]
    pub fast: bool,
    /// One line per second of data instead of the screen.
    #[arg(long)]
    pub plain: bool,
    /// Without the live screen: at the end print the screen as text, COLSxROWS (e.g. 80x24).
    #[arg(long, value_parser = parse_screen)]
    pub screen: Option<(u16, u16)>,
    /// Stop after this many seconds of data (source time).
    #[arg(long, value_parser = parse_positive)]
    pub seconds: Option<f64>,
    /// The finger plotted first: thumb, index, middle, ring, pinky (or 0-4).
    #[arg(long, default_value = "index")]
    pub finger: String,
    /// The daemon's subscription period, ms (at least one tick, 50).
    #[arg(long, default_value_t = 100)]
    pub every_ms: u64,
    /// Mains frequency the EMG chain notches for the bus and log sources, 50 or 60 Hz.
    #[arg(long, default_value_t = 50)]
    pub mains: u32,
    /// For the bus and log sources: the model whose calibration rest levels are marked on the
    /// channel bars, and whose signal chain computes them (instead of --mains); the daemon
    /// sends its own.
    #[arg(long, value_name = "FILE", conflicts_with = "mains")]
    pub model: Option<PathBuf>,
}

fn parse_speed(s: &str) -> Result<f64, String> {
    let v: f64 = s.parse().map_err(|e| format!("{s:?}: {e}"))?;
    if v.is_finite() && (0.0..=1000.0).contains(&v) {
        Ok(v)
    } else {
        Err(format!("{v}: allowed 0 (as fast as possible) to 1000"))
    }
}

fn parse_positive(s: &str) -> Result<f64, String> {
    let v: f64 = s.parse().map_err(|e| format!("{s:?}: {e}"))?;
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(format!("{v}: must be a positive number"))
    }
}

fn parse_screen(s: &str) -> Result<(u16, u16), String> {
    let bad = || format!("{s:?}: expected COLSxROWS, at least 80x24 and at most 500x200");
    let (c, r) = s.split_once(['x', 'X']).ok_or_else(bad)?;
    let (c, r): (u16, u16) = (c.parse().map_err(|_| bad())?, r.parse().map_err(|_| bad())?);
    if (80..=500).contains(&c) && (24..=200).contains(&r) {
        Ok((c, r))
    } else {
        Err(bad())
    }
}

/// `handctl demo`.
#[derive(Debug, Args)]
pub struct DemoArgs {
    /// Run the tracking on a virtual clock, as fast as the machine goes.
    #[arg(long)]
    pub fast: bool,
    /// Seconds of scored sine tracking (after 4 s of settling).
    #[arg(long, default_value_t = 20.0, value_parser = parse_seconds)]
    pub seconds: f64,
    /// Seed of the simulated amplifier and patient.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Where the calibration session and the model are written (default: a temp directory).
    #[arg(long)]
    pub dir: Option<PathBuf>,
    /// The paper's plain training, without the effort-ray penalty.
    #[arg(long)]
    pub plain: bool,
    /// The paper's labels: fingers a single-finger trial does not move are left out of the loss.
    #[arg(long)]
    pub paper_masks: bool,
    /// The output law while tracking: `shipped` (ω decays at rest, no wind-up) or `paper`
    /// (the paper's `ω = ω0 + α·t`, held at rest), to compare the two.
    #[arg(long, value_enum, default_value_t = DemoLaw::Shipped)]
    pub law: DemoLaw,
    /// What moves the fingers while tracking: `native` (hand.dbc's finger controllers) or
    /// `cia402` (a simulated CiA 402 drive per finger, node 5 + finger, in `--drive-mode`,
    /// started and driven by the daemon over CANopen).
    #[arg(long, value_enum, default_value_t = DemoDrives::Native)]
    pub drives: DemoDrives,
    /// With `--drives cia402`, the drives' mode: `cst` (cyclic synchronous torque: the force
    /// setpoint, the default), `csv` (cyclic synchronous velocity: the velocity setpoint with
    /// the force as torque limit, 0x6072) or `pv` (profile velocity, as csv).
    #[arg(long, value_enum)]
    pub drive_mode: Option<DemoDriveMode>,
}

/// `handctl demo --drive-mode`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum DemoDriveMode {
    /// Cyclic synchronous torque.
    Cst,
    /// Cyclic synchronous velocity with the torque limit.
    Csv,
    /// Profile velocity with the torque limit.
    Pv,
}

/// `handctl demo --drives`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum DemoDrives {
    /// hand.dbc's native finger controllers.
    Native,
    /// A simulated CiA 402 drive per finger.
    Cia402,
}

/// `handctl demo --law`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum DemoLaw {
    /// The shipped defaults (damping, rest damping, gain ramp).
    Shipped,
    /// The paper's pure integrator.
    Paper,
}

fn parse_seconds(s: &str) -> Result<f64, String> {
    let v: f64 = s.parse().map_err(|e| format!("{s:?}: {e}"))?;
    if (4.0..=3600.0).contains(&v) {
        Ok(v)
    } else {
        Err(format!("{v} s: allowed 4 to 3600"))
    }
}

/// Training settings shared by train and eval.
#[derive(Debug, Clone, Args)]
pub struct TrainingOpts {
    /// The paper's two-point calibration: flexion and extension only, rest trials unused.
    #[arg(long)]
    pub two_point: bool,
    /// The paper's plain training: masked MSE alone, without the effort-ray penalty that keeps
    /// the decoder monotonic in effort, and raw outputs (no rest stage).
    #[arg(long)]
    pub plain: bool,
    /// Raw outputs: no rest stage (the soft dead zone per finger fitted from the rest windows
    /// that keeps a relaxed hand still).
    #[arg(long)]
    pub no_rest_stage: bool,
    /// The paper's labels: during a single-finger trial the other fingers are left out of the
    /// loss instead of being trained toward 0.
    #[arg(long)]
    pub paper_masks: bool,
    /// Seed for initialisation, validation split and shuffling.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Upper bound on training epochs (early stopping on held-out windows may end sooner).
    #[arg(long, default_value_t = 200)]
    pub epochs: usize,
    /// Train even when the quality gates find trials to redo (except a finger moved in one
    /// direction only: see --allow-one-direction).
    #[arg(long)]
    pub ignore_gates: bool,
    /// Train even when the session moves a finger in one direction only (flexion without
    /// extension or the reverse), which --ignore-gates does not override: that finger is trained
    /// with one anchor and is never driven the other way. Only for research recordings that hold
    /// one direction (e.g. an EMG and force recording of one contraction), never for a
    /// patient's model.
    #[arg(long)]
    pub allow_one_direction: bool,
    /// Validation split for early stopping: trial-tail (the end of every trial, so every trial
    /// also trains; works with a one-repetition calibration), trial (whole trials held out),
    /// window or none [default: trial-tail; trial with --plain, as the paper's training was
    /// measured]
    #[arg(long, value_parser = parse_split)]
    pub validation: Option<decoder::model::ValidationSplit>,
}

/// `handctl train`.
#[derive(Debug, Args)]
pub struct TrainArgs {
    /// Session directory, or 3dc:DIR:train|test.
    pub session: String,
    /// Model file to write (atomically).
    #[arg(short, long)]
    pub output: PathBuf,
    /// The patient's id, recorded in the model file (letters, digits, '.', '_', '-'; at most
    /// 64): `handctl deploy` asks before a model for another patient replaces the running one.
    /// Without it the file records no patient ("unknown patient").
    #[arg(long, value_parser = parse_patient)]
    pub patient: Option<String>,
    /// Model architecture.
    #[arg(long, default_value = "resdd", value_parser = parse_kind)]
    pub model: ModelKind,
    #[command(flatten)]
    pub training: TrainingOpts,
    /// The model is refused (not written) when a finger goes back against the effort by
    /// more than this on any calibration ray, in label units (full effort is 1).
    #[arg(long, default_value_t = decoder::model::verify::DEFAULT_TOLERANCE, value_parser = parse_tolerance)]
    pub tolerance: f64,
    /// Write the model even when it reverses beyond the tolerance; the file records it as
    /// FORCED and handd's status says so.
    #[arg(long)]
    pub force: bool,
}

/// `handctl verify`.
#[derive(Debug, Args)]
pub struct VerifyArgs {
    /// Model file to verify.
    #[arg(long)]
    pub model: PathBuf,
    /// Session whose flexion and extension windows give the rays: a directory, or
    /// 3dc:DIR:train|test.
    pub session: String,
    /// Reversals up to this, in label units (full effort is 1), are accepted.
    #[arg(long, default_value_t = decoder::model::verify::DEFAULT_TOLERANCE, value_parser = parse_tolerance)]
    pub tolerance: f64,
}

fn parse_resume_age(s: &str) -> Result<u64, String> {
    let max = crate::calibrate::resume_check::MAX_RESUME_AGE_MIN;
    let v: u64 = s.parse().map_err(|e| format!("{s:?}: {e}"))?;
    if (1..=max).contains(&v) {
        Ok(v)
    } else {
        Err(format!("{v}: must be 1 to {max} minutes"))
    }
}

fn parse_patient(s: &str) -> Result<String, String> {
    decoder::model::provenance::check_patient_id(s).map(|()| s.to_owned())
}

fn parse_tolerance(s: &str) -> Result<f64, String> {
    let v: f64 = s.parse().map_err(|e| format!("{s:?}: {e}"))?;
    if v.is_finite() && v >= 0.0 {
        Ok(v)
    } else {
        Err(format!("{v}: must be finite and >= 0"))
    }
}

/// `handctl eval`.
#[derive(Debug, Args)]
pub struct EvalArgs {
    /// Session to train on (and to test on, by its last repetitions, without --test); with
    /// --model, the new session to score the saved model on (every window, nothing trained).
    pub session: String,
    /// Models to compare, comma separated.
    #[arg(long, value_delimiter = ',', default_value = "resdd,ln,mlp,cnn", value_parser = parse_kind)]
    pub models: Vec<ModelKind>,
    /// Score this saved model file on SESSION instead of training: the same tables, and the
    /// verification of its effort rays on SESSION.
    #[arg(long, conflicts_with_all = ["models", "test"])]
    pub model: Option<PathBuf>,
    /// Session to test on; without it the last repetition of every trial kind is held out.
    #[arg(long)]
    pub test: Option<String>,
    /// Directory for the ROC and interpolation curves per model: CSV, and PNG figures in a
    /// handctl built with the `plots` feature.
    #[arg(long)]
    pub plots: Option<PathBuf>,
    /// Also replay the test windows at gains x1.5, x2, x3 and x5 and with one channel at ten
    /// times its level (an electrode transient), per model: wrong-way windows and largest |y|.
    #[arg(long)]
    pub stress: bool,
    #[command(flatten)]
    pub training: TrainingOpts,
}

/// `handctl import-3dc`.
#[derive(Debug, Args)]
pub struct Import3dcArgs {
    /// Directory holding one participant's P<n>_{train,test}_emg.npy and
    /// P<n>_{train,test}_index.csv (P4, P6, P7, ...).
    pub dir: PathBuf,
    /// Which half of the recordings.
    #[arg(long, value_parser = ["train", "test"])]
    pub split: String,
    /// Session directory to write.
    #[arg(short, long)]
    pub output: PathBuf,
}

/// `handctl import`.
#[derive(Debug, Args)]
pub struct ImportArgs {
    /// Samples, n x channels: a .npy file (int16/int32/float32/float64) or a .csv file (one
    /// sample per line, optional header).
    #[arg(long)]
    pub samples: PathBuf,
    /// Label table CSV: finger (0-4, a name or all), kind (flexion|extension|rest), repetition,
    /// start_sample, end_sample (exclusive); an id column is optional.
    #[arg(long)]
    pub labels: PathBuf,
    /// Number of EMG channels in the samples (the columns less --reference and
    /// --ignore-columns).
    #[arg(long)]
    pub channels: usize,
    /// Sample rate in Hz.
    #[arg(long, default_value_t = 1000.0)]
    pub rate: f64,
    /// A column holding a reference signal (force, angle) recorded with the EMG, by CSV
    /// header name or 0-based index: stored with the session for `handctl decode`.
    #[arg(long)]
    pub reference: Option<String>,
    /// Columns that are neither EMG nor the reference (e.g. a time stamp), comma separated,
    /// by name or index.
    #[arg(long, value_delimiter = ',')]
    pub ignore_columns: Vec<String>,
    /// Lower band-pass edge in Hz (default 10).
    #[arg(long)]
    pub band_low: Option<f64>,
    /// Upper band-pass edge in Hz, below Nyquist (default 450 Hz, or 0.9 x Nyquist when the
    /// rate is under 1 kHz: 90 Hz at 200 Hz).
    #[arg(long)]
    pub band_high: Option<f64>,
    /// Feature window in ms, a whole number of samples (default 200, rounded to whole samples).
    #[arg(long)]
    pub window_ms: Option<f64>,
    /// Step between feature windows in ms (default 50, rounded to whole samples).
    #[arg(long)]
    pub step_ms: Option<f64>,
    /// Mains frequency to notch, 50 or 60 Hz.
    #[arg(long, default_value_t = 50)]
    pub mains: u32,
    /// Each label row is a separate recording (filtered on its own from reset state).
    #[arg(long)]
    pub rows_are_recordings: bool,
    /// Raw magnitude at which the recording saturates (enables the saturation gate).
    #[arg(long)]
    pub full_scale: Option<f64>,
    /// Windows starting this soon (ms) after a trial's start are not used.
    #[arg(long, default_value_t = 0.0)]
    pub onset_skip_ms: f64,
    /// Session directory to write.
    #[arg(short, long)]
    pub output: PathBuf,
}

/// `handctl check`.
#[derive(Debug, Args)]
pub struct CheckArgs {
    /// Session directory, or 3dc:DIR:train|test.
    pub session: String,
}

fn parse_split(s: &str) -> Result<decoder::model::ValidationSplit, String> {
    s.parse()
        .map_err(|e: decoder::model::TrainError| e.to_string())
}

fn parse_kind(s: &str) -> Result<ModelKind, String> {
    s.parse::<ModelKind>().map_err(|e| e.to_string())
}

/// `handctl record`.
#[derive(Debug, Args)]
pub struct RecordArgs {
    /// SocketCAN interface to record, e.g. vcan0 or can0.
    #[arg(long)]
    pub iface: String,
    /// Output directory: frames.log (candump format), and session.toml with --trials.
    #[arg(long)]
    pub out: PathBuf,
    /// Seconds to record.
    #[arg(long)]
    pub duration: f64,
    /// The trials file of `handsim --trials-out`: also write session.toml, the trials placed on
    /// the log's time base (start handctl record before handsim).
    #[arg(long)]
    pub trials: Option<PathBuf>,
    /// Mains frequency written into the session's chain settings, 50 or 60 Hz.
    #[arg(long, default_value_t = 50, value_parser = parse_mains)]
    pub mains: u32,
}

fn parse_mains(s: &str) -> Result<u32, String> {
    match s {
        "50" => Ok(50),
        "60" => Ok(60),
        _ => Err(format!("{s:?}: mains is 50 or 60 Hz")),
    }
}

/// `handctl decode`.
#[derive(Debug, Args)]
pub struct DecodeArgs {
    /// Session directory (or 3dc:DIR:train|test) whose whole recording is decoded; or a bare
    /// recording file, read with the model's channels and rate: a candump log (.log) or
    /// samples (.npy, .csv, every column a channel).
    pub session: String,
    /// Model file (trained on the same signal chain as the session's).
    #[arg(long)]
    pub model: PathBuf,
    /// CSV to write: time_s, the five outputs, and the reference (mean over each window).
    #[arg(short, long)]
    pub output: PathBuf,
    /// The finger whose output is compared with the reference (0-4 or a name; default: every
    /// finger). Needs a session with a reference signal.
    #[arg(long)]
    pub finger: Option<String>,
    /// Print the agreement as JSON (exact numbers) instead of a table.
    #[arg(long)]
    pub json: bool,
}

/// `handctl replay`.
#[derive(Debug, Args)]
pub struct ReplayArgs {
    /// The tape (`handd --tape FILE`).
    pub tape: PathBuf,
    /// handd's config file of that run (its timeouts, gains and mains frequency decide the
    /// ticks).
    #[arg(long, default_value = driver::config::DEFAULT_CONFIG_PATH)]
    pub config: PathBuf,
    /// The model file that ran (default: the config's `model`). A tape whose run swapped
    /// models replays up to the swap.
    #[arg(long)]
    pub model: Option<PathBuf>,
}

/// `handctl calibrate`.
#[derive(Debug, Args)]
pub struct CalibrateArgs {
    /// SocketCAN interface of the hand's bus, e.g. can0 or vcan0.
    #[arg(long)]
    pub iface: String,
    /// Output directory: frames.log, protocol.toml, session.toml, model.hsm.
    #[arg(long)]
    pub out: PathBuf,
    /// Protocol TOML (trials, repetitions, phase times); default: the built-in protocol.
    #[arg(long)]
    pub protocol: Option<PathBuf>,
    /// No questions; plain progress lines instead of the live screen.
    #[arg(long)]
    pub yes: bool,
    /// The patient's id, recorded in the model file (letters, digits, '.', '_', '-'; at most
    /// 64): `handctl deploy` asks before a model for another patient replaces the running one.
    /// Without it the file records no patient ("unknown patient").
    #[arg(long, value_parser = parse_patient)]
    pub patient: Option<String>,
    /// Continue an interrupted calibration in --out from its next trial (after 3 s of the
    /// patient relaxed, compared with the session's rest trials).
    #[arg(long)]
    pub resume: bool,
    /// With --resume: refuse a session that started longer ago than this, minutes (1 to 1440).
    #[arg(long, default_value_t = crate::calibrate::resume_check::DEFAULT_MAX_RESUME_AGE_MIN, value_parser = parse_resume_age)]
    pub max_resume_age_min: u64,
    /// With --resume: go on although the live rest pattern per channel differs from the
    /// session's rest trials (swapped or shifted electrodes?).
    #[arg(long, requires = "resume")]
    pub force_rest_mismatch: bool,
    /// Mains frequency written into the session's chain settings, 50 or 60 Hz.
    #[arg(long, default_value_t = 50, value_parser = parse_mains)]
    pub mains: u32,
    /// A trained model reversing beyond this on a calibration ray is refused (label units).
    #[arg(long, default_value_t = decoder::model::verify::DEFAULT_TOLERANCE, value_parser = parse_tolerance)]
    pub tolerance: f64,
    #[command(flatten)]
    pub daemon: DaemonOpts,
    #[command(flatten)]
    pub training: TrainingOpts,
}
