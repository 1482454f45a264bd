//! `handctl monitor`: the technician's live view of the hand (issue 13), on an 80x24 terminal
//! or larger, over SSH too.
//!
//! - [`state`]: what is shown ([`state::MonitorState`]), whatever the source;
//! - [`live`]: the daemon's subscription lines into it; [`frames`]: bus or log frames into it
//!   (the one EMG front end and the one signal chain), [`meters`]: bus load and latency;
//! - [`feed`]: one monitor fed by events; [`source`]: the three sources;
//! - [`widgets`]: channel bars, finger table, daemon panel, plot: plain widgets over state,
//!   for the guided calibration to reuse; [`screen`]: the layout and the text capture;
//! - [`view`]: keys (finger, freeze, reset, quit); [`tui`]: the 10 Hz loop;
//!   [`plain`]: one line per second; [`cpu`]: the monitor's own CPU use.

pub mod cpu;
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

use self::cpu::CpuMeter;
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

/// `handctl monitor`.
pub fn run(a: &MonitorArgs) -> Result<(), CliError> {
    let chain = ChainConfig {
        mains_hz: a.mains,
        ..ChainConfig::default()
    };
    let settings = ChainSettings::try_new(&chain)
        .map_err(|e| CliError::Usage(format!("--mains {}: {e}", a.mains)))?;
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
