//! `handctl monitor`: the technician's live view of the hand (issue 13), on an 80x24 terminal
//! or larger, over SSH too.
//!
//! - [`state`]: what is shown ([`state::MonitorState`]), whatever the source;
//! - [`live`]: the daemon's subscription lines into it; [`frames`]: bus or log frames into it
//!   (the one EMG front end and the one signal chain), [`drives`]: the CiA 402 drives' own
//!   frames, [`meters`]: bus load and latency;
//! - [`feed`]: one monitor fed by events; [`source`]: the three sources;
//! - [`widgets`]: channel bars, finger table, daemon panel, plot: plain widgets over state,
//!   for the guided calibration to reuse; [`screen`]: the layout and the text capture;
//! - [`view`]: keys (finger, freeze, reset, quit); [`tui`]: the 10 Hz loop;
//!   [`plain`]: one line per second; [`cpu`]: the monitor's own CPU use.

pub mod cpu;
pub mod drives;
pub mod feed;
pub mod frames;
pub mod live;
pub mod meters;
pub mod plain;
pub mod screen;
pub mod source;
pub mod state;
pub mod tui;
pub mod view;
pub mod widgets;

use std::io::IsTerminal;
use std::sync::mpsc::{sync_channel, Receiver};

use decoder::dsp::{ChainConfig, ChainSettings};
use decoder::model::TrainedModel;

use self::cpu::CpuMeter;
use self::drives::BusDrives;
use self::feed::{Event, Monitor};
use self::plain::PlainPrinter;
use self::view::View;
use super::args::MonitorArgs;
use super::error::CliError;

/// Events buffered between a source's thread and the screen (about a second of the bus).
const QUEUE: usize = 8192;

/// Where the data comes from.
enum Source {
    Daemon,
    Bus(String),
    Log(std::path::PathBuf),
}

impl Source {
    /// The screen's title for the source.
    fn title(&self) -> String {
        match self {
            Source::Daemon => "daemon".into(),
            Source::Bus(i) => format!("bus {i}"),
            Source::Log(p) => format!(
                "log {}",
                p.file_name().map_or_else(
                    || p.display().to_string(),
                    |n| n.to_string_lossy().into_owned()
                )
            ),
        }
    }
}

/// The chain the bus and log sources run (the model's, with `--model`) and the rest levels
/// to mark (the model's calibration's). A model whose chain does not fit the bus (and so a
/// log of it: other channels, another sample rate) is refused, by the check handd makes of a
/// model before it runs or deploys it.
fn chain_and_rest(a: &MonitorArgs) -> Result<(ChainSettings, Option<Vec<f64>>), CliError> {
    if let Some(path) = &a.model {
        let model = TrainedModel::load(path, None)?;
        driver::startup::check_fits_bus(path, model.chain())
            .map_err(|e| CliError::Usage(format!("--model: {e}")))?;
        let settings = ChainSettings::try_new(model.chain())
            .map_err(|e| CliError::Usage(format!("--model {}: its chain: {e}", path.display())))?;
        return Ok((settings, model.rest_rms_uv().map(<[f64]>::to_vec)));
    }
    let chain = ChainConfig {
        mains_hz: a.mains,
        ..ChainConfig::default()
    };
    let settings = ChainSettings::try_new(&chain)
        .map_err(|e| CliError::Usage(format!("--mains {}: {e}", a.mains)))?;
    Ok((settings, None))
}

/// The CiA 402 drives of handd's config, for the bus and log sources: `--config` (refused
/// when it cannot be read or is not valid), or else the default file when there is one (a
/// default file that cannot be used is said, and the bus shown without drives).
fn bus_drives(a: &MonitorArgs) -> Result<BusDrives, CliError> {
    let of = |path: &std::path::Path| {
        let config = driver::config::Config::load(path)?;
        Ok::<_, CliError>(BusDrives::of(&config.drives()?))
    };
    if let Some(path) = &a.daemon.config {
        return of(path);
    }
    let path = std::path::Path::new(driver::config::DEFAULT_CONFIG_PATH);
    if !path.exists() {
        return Ok(BusDrives::default());
    }
    of(path).or_else(|e| {
        eprintln!("handctl monitor: no CiA 402 drives shown: {e}");
        Ok(BusDrives::default())
    })
}

/// `handctl monitor`.
pub fn run(a: &MonitorArgs) -> Result<(), CliError> {
    let (settings, rest) = chain_and_rest(a)?;
    let finger = hand_dbc::hand::finger_index(&a.finger).ok_or_else(|| {
        CliError::Usage(format!(
            "--finger {:?}: expected thumb, index, middle, ring, pinky or 0-4",
            a.finger
        ))
    })?;
    let source = match (&a.iface, &a.log) {
        (Some(i), None) => Source::Bus(i.clone()),
        (None, Some(l)) => Source::Log(l.clone()),
        _ => Source::Daemon,
    };
    let cpu = CpuMeter::start();
    let tui = !a.plain && a.screen.is_none() && std::io::stdout().is_terminal();
    let mut m = Monitor::new(source.title(), &settings);
    if !matches!(source, Source::Daemon) {
        m.set_drives(bus_drives(a)?);
    }
    for (c, level) in m.state.channels.iter_mut().zip(rest.iter().flatten()) {
        c.rest_uv = Some(*level);
    }
    let mut view = View::with_finger(finger);
    let mut printer = PlainPrinter::default();
    let mut print_plain = |m: &Monitor| {
        if a.plain && printer.due(&m.state) {
            println!("{}", plain::line(&m.state, &cpu));
        }
    };
    let fast = matches!(source, Source::Log(_)) && (a.fast || a.speed == 0.0);
    if let (Source::Log(path), true) = (&source, fast) {
        source::read_log_fast(path, &mut m, a.seconds, &mut print_plain)?;
    } else {
        let rx = start(&source, a)?;
        if tui {
            tui::run(&mut m, &mut view, &rx, a.seconds)?;
        } else {
            headless(&mut m, &rx, a.seconds, &mut print_plain);
        }
    }
    if let Some((cols, rows)) = a.screen {
        for row in screen::render_text(view.shown(&m.state), &view, cols, rows) {
            println!("{}", row.trim_end());
        }
    }
    if let Some(why) = &m.state.ended {
        eprintln!("handctl monitor: {why}");
    }
    let refresh_hz = 1e6 / frames::SAMPLE_PERIOD_US as f64;
    println!("{}", cpu.summary((!fast).then_some(refresh_hz)));
    Ok(())
}

/// Starts the source's thread.
fn start(source: &Source, a: &MonitorArgs) -> Result<Receiver<Event>, CliError> {
    let (tx, rx) = sync_channel(QUEUE);
    match source {
        Source::Daemon => {
            let socket = super::daemon::socket_of(&a.daemon)?;
            let reader = source::subscribe(&socket, a.every_ms)?;
            std::thread::spawn(move || source::pump_daemon(reader, tx));
        }
        Source::Bus(iface) => {
            let sock = source::open_bus(iface)?;
            let iface = iface.clone();
            std::thread::spawn(move || source::pump_bus(sock, iface, tx));
        }
        Source::Log(path) => {
            let reader = source::open_log(path)?;
            let (path, speed) = (path.clone(), a.speed);
            std::thread::spawn(move || source::pump_log(reader, path, speed, tx));
        }
    }
    Ok(rx)
}

/// Without a screen: events until the source ends or `seconds` of source time have passed.
fn headless(
    m: &mut Monitor,
    rx: &Receiver<Event>,
    seconds: Option<f64>,
    on_event: &mut impl FnMut(&Monitor),
) {
    for e in rx {
        let end = matches!(e, Event::End(_));
        m.apply(e);
        on_event(m);
        if end {
            return;
        }
        if let Some(s) = seconds.filter(|&s| m.elapsed_s() >= s) {
            m.apply(Event::End(format!("{s} s of data")));
            return;
        }
    }
}

#[cfg(test)]
mod tests {
    use clap::Parser;
    use decoder::model::{AnyModel, ModelKind, ModelSpec, Normalizer, TrainingSummary};

    use super::*;
    use crate::args::{Cli, Command};

    fn monitor_args(extra: &[&str]) -> MonitorArgs {
        let cli = Cli::parse_from(["handctl", "monitor", "--log", "x.log"].iter().chain(extra));
        match cli.command {
            Command::Monitor(a) => a,
            _ => unreachable!("parsed as monitor"),
        }
    }

    #[test]
    fn model_gives_the_chain_and_the_rest_levels_of_its_calibration() {
        let chain = ChainConfig {
            mains_hz: 60,
            ..ChainConfig::default()
        };
        let n_in = 8 * chain.channels;
        let spec = ModelSpec::default();
        let model = AnyModel::random(ModelKind::ResDd, &spec, n_in, 5, 3).expect("model");
        let norm = Normalizer::from_scales(vec![100.0; n_in]).expect("scales");
        let summary = TrainingSummary::untrained(ModelKind::ResDd);
        let levels: Vec<f64> = (0..chain.channels).map(|c| 2.0 + c as f64).collect();
        let trained = TrainedModel::new(model, spec, norm, chain.clone(), summary)
            .and_then(|m| m.with_rest_rms_uv(levels.clone()))
            .expect("trained");
        let path = std::env::temp_dir().join(format!("monitor-model-{}.hsm", std::process::id()));
        trained.save(&path).expect("saved");

        let (settings, rest) = chain_and_rest(&monitor_args(&["--model", path.to_str().unwrap()]))
            .expect("the model's chain");
        assert_eq!(rest, Some(levels));
        assert_eq!(settings.config(), &chain, "the model's chain, mains 60 Hz");
        let (settings, rest) = chain_and_rest(&monitor_args(&[])).expect("defaults");
        assert_eq!((rest, settings.config().mains_hz), (None, 50));
        let e = chain_and_rest(&monitor_args(&["--model", "/nonexistent.hsm"])).unwrap_err();
        assert!(e.to_string().contains("/nonexistent.hsm"), "{e}");
        std::fs::remove_file(&path).expect("removed");
    }

    /// A model of `channels` channels (default chain otherwise), saved to a scratch file.
    fn saved_model(channels: usize, name: &str) -> std::path::PathBuf {
        let chain = ChainConfig {
            channels,
            ..ChainConfig::default()
        };
        let n_in = 8 * chain.channels;
        let spec = ModelSpec::default();
        let model = AnyModel::random(ModelKind::ResDd, &spec, n_in, 5, 3).expect("model");
        let norm = Normalizer::from_scales(vec![100.0; n_in]).expect("scales");
        let summary = TrainingSummary::untrained(ModelKind::ResDd);
        let trained = TrainedModel::new(model, spec, norm, chain, summary).expect("trained");
        let path = std::env::temp_dir().join(format!("monitor-{name}-{}.hsm", std::process::id()));
        trained.save(&path).expect("saved");
        path
    }

    /// Issue 29: a 10-channel model on the 12-channel bus (or a log of it) is refused, as
    /// handd refuses to run or deploy it, not shown as 10 channels without a word.
    #[test]
    fn a_model_whose_chain_does_not_fit_the_bus_is_refused_with_the_reason() {
        let ten = saved_model(10, "ten");
        let e = chain_and_rest(&monitor_args(&["--model", ten.to_str().unwrap()]))
            .expect_err("a 10-channel model on the 12-channel bus");
        let text = e.to_string();
        assert!(
            text.contains("trained on 10 EMG channels, the bus carries 12")
                && text.contains(&ten.display().to_string()),
            "the refusal names the model and the mismatch: {text}"
        );
        std::fs::remove_file(&ten).expect("removed");
        let twelve = saved_model(hand_dbc::emg::EMG_CHANNELS, "twelve");
        let (settings, _) = chain_and_rest(&monitor_args(&["--model", twelve.to_str().unwrap()]))
            .expect("a model of the bus's channels is taken");
        assert_eq!(settings.n_channels(), hand_dbc::emg::EMG_CHANNELS);
        std::fs::remove_file(&twelve).expect("removed");
    }
}
