//! `handd`: the handstack daemon. Reads sEMG from the amplifier on the CAN bus, runs the signal
//! chain and the model every 50 ms, and sends per-finger setpoints to the motor controllers.
//! See README.md ("Installing handd on the board") and `handd --help`.
//!
//! As a service: latches (E-stop, a technician's stop, the calibrating hold, ...) are kept in
//! `state_dir` and honoured at start (`driver::persist`); a bus that is down at start is
//! waited for, SAFE; SIGTERM and SIGINT send one round of safe stops and save the latches
//! before exit; SIGHUP is ignored (restart handd to load a changed config).

use std::io::IsTerminal;
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{mpsc, Arc, Mutex};
use std::time::{Duration, Instant};

use clap::Parser;
use decoder::dsp::ChainConfig;
use decoder::model::Model as _;
use driver::config::{Config, DEFAULT_CONFIG_PATH};
use driver::control::{ControlServer, LiveFeed, LiveModel};
use driver::daemon::Runner;
use driver::engine::{Command, Engine, Hold};
use driver::live::ModelInfo;
use driver::persist::LatchStore;
use driver::rt::{lock_memory, set_fifo, RtReport};
use driver::service::{ControlHandler, COMMAND_QUEUE};
use driver::socketcan_bus::SocketCanTransport;
use driver::startup::{engine_settings, load_model, remove_stale_temps, LoadedModel};
use hand_clock::{Clock, SystemClock};
use tracing_appender::non_blocking::ErrorCounter;

/// The handstack daemon.
#[derive(Parser, Debug)]
#[command(name = "handd", version, about)]
struct Args {
    /// Config file.
    #[arg(long, default_value = DEFAULT_CONFIG_PATH)]
    config: PathBuf,
    /// Log as JSON lines (for log collectors) instead of human-readable text.
    #[arg(long)]
    json_logs: bool,
    /// SCHED_FIFO priority of the control loop (1-99); normal scheduling if not given. Keep it
    /// below 50, the kernel's threaded interrupt handlers (the CAN controller's among them):
    /// handd warns at 50 or more.
    #[arg(long, value_parser = clap::value_parser!(u8).range(1..=99))]
    rt_priority: Option<u8>,
    /// Check the config and the model, print what would run, and exit.
    #[arg(long)]
    check: bool,
    /// Record a tape to FILE (replaced if it exists): every frame the control loop read with
    /// the receive time it used, every tick, command and fault from the bus, and every frame
    /// the loop computed, so the run replays bit for bit (`handctl replay`). About 100 kB/s:
    /// for tests and investigations, not for everyday use.
    #[arg(long, value_name = "FILE")]
    tape: Option<PathBuf>,
    /// Print handd's manual page (roff) to standard output and exit (the package installs it).
    #[arg(long, hide = true)]
    man: bool,
}

/// Whether the human-readable log may carry ANSI colours: only on a terminal, never in JSON
/// logs, and never when `NO_COLOR` is set to a non-empty value (<https://no-color.org>). Under
/// systemd stderr is a pipe to the journal, so no escapes end up there.
fn use_colour(json: bool, stderr_is_tty: bool, no_color: Option<&std::ffi::OsStr>) -> bool {
    !json && stderr_is_tty && no_color.is_none_or(|v| v.is_empty())
}

/// SCHED_FIFO at `priority` for the calling thread (the loop's), if asked; a refusal is logged.
fn loop_priority(priority: Option<u8>) {
    let Some(p) = priority else { return };
    if p >= IRQ_THREAD_PRIORITY {
        tracing::warn!(
            priority = p,
            "the control loop's SCHED_FIFO priority is not below the kernel's threaded interrupt \
             handlers ({IRQ_THREAD_PRIORITY}): the CAN interrupt cannot preempt a tick and the \
             controller's receive buffers may overflow; use 40 as the shipped unit does"
        );
    }
    let mut rt = RtReport::default();
    set_fifo(p, &mut rt);
    for w in &rt.warnings {
        tracing::warn!("{w}");
    }
}

/// SCHED_FIFO priority of the kernel's threaded interrupt handlers.
const IRQ_THREAD_PRIORITY: u8 = 50;

/// Log lines queued for the writer thread before further lines are dropped (and counted).
const LOG_QUEUE_LINES: usize = 16_384;

/// The log's writer: every thread formats its line and queues it; one thread of its own, at
/// normal priority, writes the queue to stderr. The control loop (SCHED_FIFO) thus never waits
/// on stderr: not on the process's stderr lock (a control-socket thread preempted while holding
/// it would stall the loop behind it, a priority inversion), nor on a journal pipe that is full.
/// A full queue drops the line rather than block; the count is printed at exit.
fn init_logs(json: bool) -> (tracing_appender::non_blocking::WorkerGuard, ErrorCounter) {
    let filter = tracing_subscriber::EnvFilter::try_from_default_env()
        .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new("info"));
    let colour = use_colour(
        json,
        std::io::stderr().is_terminal(),
        std::env::var_os("NO_COLOR").as_deref(),
    );
    let (writer, guard) = tracing_appender::non_blocking::NonBlockingBuilder::default()
        .buffered_lines_limit(LOG_QUEUE_LINES)
        .lossy(true)
        .thread_name("handd-log")
        .finish(std::io::stderr());
    let dropped = writer.error_counter();
    let builder = tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(writer)
        .with_ansi(colour);
    // Under systemd the journal adds its own timestamps.
    let journald = std::env::var_os("JOURNAL_STREAM").is_some();
    if json {
        builder.json().init();
    } else if journald {
        builder.without_time().init();
    } else {
        builder.init();
    }
    (guard, dropped)
}

fn main() -> ExitCode {
    let args = Args::parse();
    if args.man {
        return print_man();
    }
    let (log_writer, dropped) = init_logs(args.json_logs);
    let code = match run(&args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            // Once, through the log: it reaches the terminal, the journal and a log collector
            // alike (an extra eprintln! printed it a second time on the same stderr).
            tracing::error!("refusing to start: {e}");
            ExitCode::from(2)
        }
    };
    // Every queued line written before handd ends.
    drop(log_writer);
    let lost = dropped.dropped_lines();
    if lost > 0 {
        eprintln!(
            "handd: {lost} log lines were dropped: the log's queue was full (stderr too slow)"
        );
    }
    code
}

/// Prints the manual page generated from [`Args`] (clap_mangen).
fn print_man() -> ExitCode {
    use clap::CommandFactory;
    use std::io::Write;
    let mut out = Vec::new();
    let written = clap_mangen::Man::new(Args::command())
        .section("8")
        .render(&mut out)
        .and_then(|()| std::io::stdout().write_all(&out));
    match written {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("handd: cannot write the manual page: {e}");
            ExitCode::FAILURE
        }
    }
}

/// The model the config names, or None when its file is absent (handd then starts SAFE with
/// `no_model` latched and waits for `handctl deploy`).
fn load_configured(config: &Config, check: bool) -> Result<Option<LoadedModel>, String> {
    if !check && !config.model.exists() {
        tracing::warn!(
            model = %config.model.display(),
            "no model: the hand stays SAFE; handctl deploy MODEL"
        );
        return Ok(None);
    }
    let loaded = load_model(&config.model, config.mains_hz).map_err(|e| e.to_string())?;
    tracing::info!(
        model = %config.model.display(),
        kind = %loaded.model.model().kind(),
        model_id = format!("{:08x}", loaded.model_id),
        "model validated"
    );
    loaded.log_verification(&config.model);
    Ok(Some(loaded))
}

/// The engine for `loaded` (or without a model), and the chain it runs.
fn build_engine(
    config: &Config,
    loaded: Option<&LoadedModel>,
    tape: Option<driver::tape::Recorder>,
    now_us: u64,
) -> (Engine, ChainConfig) {
    let settings = engine_settings(config, loaded.map_or(0, |l| l.model_id));
    let (mut engine, chain) = match loaded {
        Some(l) => (
            Engine::new(&l.chain, l.model.predictor(), settings, now_us),
            l.model.chain().clone(),
        ),
        None => {
            let chain = ChainConfig {
                mains_hz: config.mains_hz,
                ..ChainConfig::default()
            };
            let designed = chain.validate().expect("the default chain is valid");
            (Engine::without_model(&designed, settings, now_us), chain)
        }
    };
    if let Some(t) = tape {
        engine.record_to(t);
    }
    engine.validated(now_us);
    (engine, chain)
}

/// The drive table against the bank it makes at this tick (beyond the config's own checks:
/// the SYNC period must fit each drive's 0x60C2). handd and `--check` refuse a table that does
/// not, naming why.
fn check_drive_bank(config: &Config) -> Result<(), String> {
    let drives = config.drives().map_err(|e| e.to_string())?;
    driver::engine::check_drives(&drives, config.tick_ms * 1000)
        .map_err(|e| format!("fingers.*.drive (CiA 402): {e}"))
}

fn run(args: &Args) -> Result<(), String> {
    let config = Config::load(&args.config).map_err(|e| e.to_string())?;
    check_drive_bank(&config)?;
    let loaded = load_configured(&config, args.check)?;
    tracing::info!(config = %args.config.display(), interface = %config.interface, "config validated");
    if args.check {
        print_check(args, &config, loaded.as_ref());
        return Ok(());
    }
    let latch_file = driver::persist::latch_path(&config.state_dir);
    // Saves killed midway (a writer's .tmp.PID files) are cleaned up before anything runs.
    remove_stale_temps(&[&args.config, &config.model, &latch_file]);
    let restored = driver::persist::load(&latch_file);
    restored.log(&latch_file);

    let mut rt = RtReport::default();
    lock_memory(&mut rt);
    for w in &rt.warnings {
        tracing::warn!("{w}");
    }

    let clock = SystemClock::new();
    let (transport, bus_down) = match SocketCanTransport::open(&config.interface, clock) {
        Ok(t) => (t, false),
        Err(e) => {
            tracing::error!(error = %e, "bus down at start: the hand stays SAFE; reopening until it is up");
            (SocketCanTransport::closed(&config.interface, clock), true)
        }
    };
    let (recorder, tape_writer) = match &args.tape {
        Some(path) => {
            let (r, w) = driver::tape::start(path).map_err(|e| e.to_string())?;
            tracing::info!(tape = %path.display(), "recording a tape");
            (Some(r), Some(w))
        }
        None => (None, None),
    };
    let (mut engine, chain) = build_engine(&config, loaded.as_ref(), recorder, clock.now_us());
    let latches = restored.latches();
    engine.restore(clock.now_us(), latches);
    let (publisher, store) = driver::persist::spawn_writer(latch_file, restored.on_disk())
        .map_err(|e| format!("latch writer thread: {e}"))?;
    let (tx, rx) = mpsc::sync_channel(COMMAND_QUEUE);
    let mut runner = Runner::new(engine, transport, clock, config.tick_ms * 1000)
        .with_commands(rx)
        .with_latches(publisher);
    if bus_down {
        runner = runner.with_bus_down();
    }
    spawn_control(
        args,
        &config,
        loaded.as_ref(),
        &runner,
        chain,
        tx,
        (store, latches.hold),
    )?;

    let stop = Arc::new(AtomicBool::new(false));
    for sig in [signal_hook::consts::SIGTERM, signal_hook::consts::SIGINT] {
        signal_hook::flag::register(sig, Arc::clone(&stop)).map_err(|e| format!("signals: {e}"))?;
    }
    // SIGHUP is ignored (its default would end handd, and systemd would count that as a clean
    // exit): a changed handd.toml takes effect with `systemctl restart handd`.
    let hangup = Arc::new(AtomicBool::new(false));
    signal_hook::flag::register(signal_hook::consts::SIGHUP, Arc::clone(&hangup))
        .map_err(|e| format!("signals: {e}"))?;
    // Only now: threads inherit the policy, and the control threads (spawned above, and the
    // connections they spawn) must not compete with the loop at its priority.
    loop_priority(args.rt_priority);
    let _ = sd_notify::notify(&[sd_notify::NotifyState::Ready]);
    tracing::info!(socket = %config.control.socket.display(), "running");
    let watchdog = sd_notify::watchdog_enabled().map(|d| d / 2);
    let mut last_ping = Instant::now();
    runner.run_realtime(&stop, |r| {
        // Ping only while ticks meet their deadlines: a stalled loop gets restarted.
        if let Some(every) = watchdog {
            if r.last_tick_on_time() && last_ping.elapsed() >= every.min(Duration::from_secs(1)) {
                let _ = sd_notify::notify(&[sd_notify::NotifyState::Watchdog]);
                last_ping = Instant::now();
            }
        }
        if hangup.swap(false, Ordering::Relaxed) {
            tracing::warn!("SIGHUP ignored: to load a changed config, `systemctl restart handd`");
        }
    });
    let _ = sd_notify::notify(&[sd_notify::NotifyState::Stopping]);
    let (sent, saved) = runner.shutdown(Duration::from_secs(1));
    let stops = if sent > 0 {
        "safe stops sent to every finger"
    } else {
        "no safe stops sent (the bus is down)"
    };
    if saved {
        tracing::info!(safe_stops = sent, "stopping: {stops}; latches saved");
    } else {
        tracing::error!(
            safe_stops = sent,
            "stopping: {stops}; the latches could NOT be saved (see above)"
        );
    }
    let lost = runner.engine().tape().map_or(0, |t| t.lost());
    // The engine holds the recorder: the writer ends once it is gone.
    drop(runner);
    if let Some(w) = tape_writer {
        if w.finish() && lost == 0 {
            tracing::info!("tape complete");
        } else {
            tracing::warn!(lost_entries = lost, "the tape is incomplete (see above)");
        }
    }
    Ok(())
}

/// `--check`: what would run.
fn print_check(args: &Args, config: &Config, loaded: Option<&LoadedModel>) {
    if let Some(l) = loaded {
        println!(
            "config {} and model {} ({}, id {:08x}) are valid; interface {}\nmodel {}",
            args.config.display(),
            config.model.display(),
            l.model.model().kind(),
            l.model_id,
            config.interface,
            l.status(&config.model).verification
        );
    }
    if let Ok(drives) = config.drives() {
        println!(
            "{}",
            driver::planned_load::planned_load(&drives, config.tick_ms * 1000)
        );
        for (name, d) in driver::units::FINGER_NAMES.iter().zip(drives.fingers) {
            if let driver::drive_config::Drive::Cia402 { node, mode, .. } = d {
                println!(
                    "finger {name}: CiA 402 drive, {node}, mode {} (started, configured \
                     and enabled by handd at start)",
                    mode.value()
                );
            }
        }
    }
}

/// The control socket's server on its own thread (`handd-control`): the handler that answers
/// `handctl` (commands reach the loop through `commands`) and the live feed.
fn spawn_control(
    args: &Args,
    config: &Config,
    loaded: Option<&LoadedModel>,
    runner: &Runner<SocketCanTransport<SystemClock>, SystemClock>,
    chain: ChainConfig,
    commands: mpsc::SyncSender<Command>,
    (latches, hold): (LatchStore, Hold),
) -> Result<(), String> {
    let live_model = Arc::new(Mutex::new(LiveModel {
        info: ModelInfo {
            id: format!("{:08x}", loaded.map_or(0, |l| l.model_id)),
            path: config.model.display().to_string(),
            kind: loaded.map_or("none".into(), |l| l.model.model().kind().to_string()),
        },
        rest_rms_uv: loaded.and_then(|l| l.model.rest_rms_uv().map(<[f64]>::to_vec)),
    }));
    let live = LiveFeed {
        snapshot: runner.snapshot(),
        model: Arc::clone(&live_model),
        tick_us: config.tick_ms * 1000,
    };
    let server = ControlServer::bind(&config.control.socket, config.control.group.as_deref())
        .map_err(|e| e.to_string())?
        .with_live(live);
    let handler = ControlHandler::new(
        config.clone(),
        args.config.clone(),
        runner.snapshot(),
        commands,
    )
    .with_chain(chain)
    .with_live_model(live_model)
    .with_latches(latches, hold)
    .with_rest_levels(loaded.and_then(|l| l.model.rest_rms_uv().map(<[f64]>::to_vec)));
    let mut handler = match loaded {
        Some(l) => handler.with_model(l.status(&config.model)),
        None => handler.without_model(),
    };
    std::thread::Builder::new()
        .name("handd-control".into())
        .stack_size(driver::control::THREAD_STACK_BYTES)
        .spawn(move || server.serve(move |req, peer| handler.handle(req, peer)))
        .map_err(|e| format!("control thread: {e}"))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::use_colour;
    use std::ffi::OsStr;

    #[test]
    fn colour_only_on_a_terminal_without_json_or_no_color() {
        assert!(use_colour(false, true, None), "a terminal gets colours");
        assert!(
            !use_colour(false, false, None),
            "a pipe (the journal) gets none"
        );
        assert!(!use_colour(true, true, None), "JSON logs get none");
        assert!(
            !use_colour(false, true, Some(OsStr::new("1"))),
            "NO_COLOR=1 turns them off"
        );
        assert!(
            use_colour(false, true, Some(OsStr::new(""))),
            "an empty NO_COLOR is ignored, as no-color.org says"
        );
    }
}
