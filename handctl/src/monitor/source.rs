//! The three sources, each a thread sending [`Event`]s: the daemon's subscription on the
//! control socket, the bus itself (listen-only), and a recorded candump log at its recorded
//! speed (or N times it). A log at full speed is read in the caller's thread instead
//! ([`read_log_fast`]).

use std::fs::File;
use std::io::BufReader;
use std::path::{Path, PathBuf};
use std::sync::mpsc::SyncSender;
use std::time::{Duration, Instant};

use crate::listen::Listener;
use driver::control::Subscription;
use hand_dbc::candump::LogReader;

use super::feed::{Event, Monitor};
use crate::error::CliError;

fn io_err(path: &Path) -> impl FnOnce(std::io::Error) -> CliError + '_ {
    move |source| CliError::Io {
        path: path.display().to_string(),
        source,
    }
}

/// Subscribes on handd's control socket (driver's client: handd's answer first, a refusal is an
/// error with handd's reason), then the stream of live lines.
pub fn subscribe(socket: &Path, every_ms: u64) -> Result<Subscription, CliError> {
    Ok(driver::control::subscribe(socket, Some(every_ms))?)
}

/// Sends every live line until handd closes the stream.
pub fn pump_daemon(subscription: Subscription, tx: SyncSender<Event>) {
    for line in subscription {
        match line {
            Ok(l) => {
                if tx.send(Event::Live(Box::new(l))).is_err() {
                    return;
                }
            }
            Err(e) => {
                let _ = tx.send(Event::End(e.to_string()));
                return;
            }
        }
    }
    let _ = tx.send(Event::End("handd closed the subscription".to_owned()));
}

/// Opens `iface` for reading with kernel receive timestamps. A raw CAN socket that never
/// writes: the monitor is listen-only on the bus.
pub fn open_bus(iface: &str) -> Result<Listener, CliError> {
    Listener::open(iface, Duration::from_millis(100), false)
}

/// Sends every data frame read from the bus, with its kernel receive time.
pub fn pump_bus(mut sock: Listener, iface: String, tx: SyncSender<Event>) {
    let mut error_frames = 0;
    let why = loop {
        let (f, t) = match sock.read_frame(&mut error_frames) {
            Ok(Some(x)) => x,
            Ok(None) => continue,
            Err(e) => break format!("reading {iface} failed: {e}"),
        };
        if f.is_remote() {
            continue;
        }
        if tx.send(Event::Frame(t, f)).is_err() {
            return;
        }
    };
    let _ = tx.send(Event::End(why));
}

/// Opens a candump log.
pub fn open_log(path: &Path) -> Result<LogReader<BufReader<File>>, CliError> {
    Ok(LogReader::new(BufReader::new(
        File::open(path).map_err(io_err(path))?,
    )))
}

/// Sends a log's frames at `speed` times their recorded pace.
pub fn pump_log(
    reader: LogReader<BufReader<File>>,
    path: PathBuf,
    speed: f64,
    tx: SyncSender<Event>,
) {
    let start = Instant::now();
    let mut t0 = None;
    for entry in reader {
        let e = match entry {
            Ok(e) => e,
            Err(e) => {
                let _ = tx.send(Event::End(format!("{}: {e}", path.display())));
                return;
            }
        };
        let t0 = *t0.get_or_insert(e.time_us);
        let due = Duration::from_secs_f64(e.time_us.saturating_sub(t0) as f64 * 1e-6 / speed);
        if let Some(wait) = due.checked_sub(start.elapsed()) {
            std::thread::sleep(wait);
        }
        if tx.send(Event::Frame(e.time_us, e.frame)).is_err() {
            return;
        }
    }
    let _ = tx.send(Event::End("end of the log".into()));
}

/// Reads a whole log as fast as possible into `m`, stopping after `seconds` of log time;
/// `on_event` sees the monitor after every event (the plain printer).
pub fn read_log_fast(
    path: &Path,
    m: &mut Monitor,
    seconds: Option<f64>,
    mut on_event: impl FnMut(&Monitor),
) -> Result<(), CliError> {
    for entry in open_log(path)? {
        let e = entry.map_err(|e| CliError::Usage(format!("{}: {e}", path.display())))?;
        m.apply(Event::Frame(e.time_us, e.frame));
        on_event(m);
        if seconds.is_some_and(|s| m.elapsed_s() >= s) {
            m.apply(Event::End(format!(
                "{} s of the log",
                seconds.unwrap_or(0.0)
            )));
            return Ok(());
        }
    }
    m.apply(Event::End("end of the log".into()));
    on_event(m);
    Ok(())
}

#[cfg(test)]
mod tests {
    use std::io::{BufRead, Write};
    use std::os::unix::net::UnixListener;
    use std::sync::mpsc::sync_channel;

    use super::*;

    /// A one-connection stand-in for handd: checks the request, answers `answer`, then sends
    /// `lines` and closes.
    fn fake_handd(name: &str, answer: &'static str, lines: Vec<String>) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("monitor-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("temp dir");
        let path = dir.join("handctl.sock");
        let listener = UnixListener::bind(&path).expect("bind");
        std::thread::spawn(move || {
            let (stream, _) = listener.accept().expect("accept");
            let mut reader = BufReader::new(stream.try_clone().expect("dup"));
            let mut req = String::new();
            reader.read_line(&mut req).expect("request");
            let req: serde_json::Value = serde_json::from_str(&req).expect("JSON request");
            assert_eq!(req["cmd"], "subscribe");
            assert_eq!(req["every_ms"], 100);
            let mut w = stream;
            writeln!(w, "{answer}").expect("answer");
            for l in lines {
                writeln!(w, "{l}").expect("line");
            }
        });
        path
    }

    #[test]
    fn the_daemon_source_streams_live_lines_until_handd_closes() {
        let line = |t: u64, state: &str| {
            format!(
                r#"{{"t_us":{t},"state":"{state}","fingers":[{{"label":0.25}}],"channels":[{{"rms_uv":7.5}}]}}"#
            )
        };
        let ok = r#"{"result":"ok","message":"subscribed: one line every 100 ms"}"#;
        let path = fake_handd(
            "ok",
            ok,
            vec![line(1_000_000, "READY"), line(1_100_000, "RUNNING")],
        );
        let reader = subscribe(&path, 100).expect("subscribed");
        let (tx, rx) = sync_channel(16);
        pump_daemon(reader, tx);
        let settings = decoder::dsp::ChainConfig::default()
            .validate()
            .expect("defaults");
        let mut m = Monitor::new("daemon", &settings);
        for e in rx.try_iter() {
            m.apply(e);
        }
        let st = &m.state;
        assert_eq!(st.daemon.state.as_deref(), Some("RUNNING"));
        assert_eq!(st.fingers[0].label, Some(0.25));
        assert_eq!(st.channels[0].rms_uv, 7.5);
        assert_eq!(st.ended.as_deref(), Some("handd closed the subscription"));
        assert!((m.elapsed_s() - 0.1).abs() < 1e-9);
    }

    #[test]
    fn a_refused_subscription_is_an_error_with_handds_reason() {
        let refused = r#"{"result":"refused","reason":"every_ms 10: at least one tick, 50"}"#;
        let path = fake_handd("refused", refused, Vec::new());
        let e = subscribe(&path, 100).expect_err("refused");
        assert!(e.to_string().contains("at least one tick"), "{e}");
    }
}
