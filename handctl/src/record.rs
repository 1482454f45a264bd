//! `handctl record`: records a SocketCAN bus to a candump log (kernel receive timestamps) and,
//! given the trials `handsim --trials-out` wrote, a calibration session for `handctl train`.
//!
//! ## One time base
//!
//! The log's times are the kernel's receive timestamps (µs since the Unix epoch); handsim's
//! trial times are µs since *its* scenario start. The scenario start is on the bus: handsim's
//! amplifier sends sample 0 (EMG_SAMPLES_G0 with sample counter 0) at scenario time 0 and one
//! sample per millisecond after it. So the recorder takes the receive time of the first
//! EMG_SAMPLES_G0 frame as the scenario start and shifts every trial by it. That frame must
//! carry counter 0: if it does not, the recorder started after handsim, the start is unknown,
//! and the session is refused ("start handctl record before handsim"). The offset is off by
//! the first frame's latency only (well under a millisecond on vcan, about 1 % of a 0.5 s
//! plateau at worst even on a loaded machine), and the decoder's onset skip and windowing
//! absorb it.

use std::fs::File;
use std::io::BufWriter;
use std::path::Path;
use std::time::{Duration, Instant};

use decoder::dsp::ChainConfig;
use decoder::session::{SessionMeta, Trial, TrialTable};
use hand_dbc::candump::LogWriter;
use hand_dbc::emg::EMG_CHANNELS;

use super::args::RecordArgs;
use super::error::CliError;
use super::listen::Listener;
use driver::units::ADC_MAX;

/// EMG_SAMPLES_G0's id (hand.dbc): the frame that carries the sample counter first.
const EMG_G0_ID: u32 = 0x100;
/// The log file inside the output directory.
const FRAMES_FILE: &str = "frames.log";

/// What a recording saw.
#[derive(Debug, Default, Clone, Copy)]
struct Counts {
    frames: u64,
    error_frames: u64,
    /// Receive time (µs since the epoch) of the first EMG_SAMPLES_G0 and its sample counter.
    first_emg: Option<(u64, u8)>,
}

fn io_err(path: &Path) -> impl FnOnce(std::io::Error) -> CliError + '_ {
    move |source| CliError::Io {
        path: path.display().to_string(),
        source,
    }
}

/// Runs `handctl record`.
pub fn run(a: &RecordArgs) -> Result<(), CliError> {
    if !(a.duration.is_finite() && a.duration > 0.0) {
        return Err(CliError::Usage(format!(
            "--duration {}: must be a positive number of seconds",
            a.duration
        )));
    }
    // Read the trials first: a bad file should fail before a long recording, not after it.
    let trials = match &a.trials {
        Some(p) => Some(read_trials(p)?),
        None => None,
    };
    std::fs::create_dir_all(&a.out).map_err(io_err(&a.out))?;
    let log_path = a.out.join(FRAMES_FILE);
    let mut socket = open(&a.iface)?;
    if let Some((got, wanted)) = socket.small_rcvbuf() {
        eprintln!(
            "handctl record: the kernel granted a {got}-byte receive buffer of the {wanted} \
             asked for: set net.core.rmem_max (README, install) or a slow disk may lose frames"
        );
    }
    eprintln!(
        "handctl record: {} for {:.1} s -> {}",
        a.iface,
        a.duration,
        log_path.display()
    );
    let counts = record(&mut socket, &a.iface, &log_path, a.duration)?;
    let drops = socket.kernel_drops();
    eprintln!(
        "handctl record: {} frames ({} error frames not logged), {drops} dropped by the kernel",
        counts.frames, counts.error_frames
    );
    if drops > 0 {
        // The log is kept (it is what was heard), but it is not the bus: refuse it.
        return Err(CliError::Usage(format!(
            "the kernel dropped {drops} frames because handctl record fell behind (its \
             receive queue was full): {} has gaps. Record again with less load on the \
             machine, or a larger net.core.rmem_max",
            log_path.display()
        )));
    }
    if let Some(trials) = trials {
        let start_us = scenario_start(&counts)?;
        session_meta(&trials, start_us, a.mains).write(&a.out)?;
        // The session must open: a recorder that writes what the trainer cannot read is broken.
        let s = decoder::session::Session::open(&a.out)?;
        eprintln!(
            "handctl record: session {} with {} trials (scenario start at {}.{:06} s)",
            a.out.display(),
            s.meta.trials.len(),
            start_us / 1_000_000,
            start_us % 1_000_000
        );
    }
    Ok(())
}

fn open(iface: &str) -> Result<Listener, CliError> {
    // A short timeout so the recording ends on time on a silent bus.
    Listener::open(iface, Duration::from_millis(50), true)
}

fn record(sock: &mut Listener, iface: &str, path: &Path, seconds: f64) -> Result<Counts, CliError> {
    let file = File::create(path).map_err(io_err(path))?;
    let mut log = LogWriter::new(BufWriter::new(file));
    let mut counts = Counts::default();
    let end = Instant::now() + Duration::from_secs_f64(seconds);
    while Instant::now() < end {
        let (f, time_us) = match sock.read_frame(&mut counts.error_frames) {
            Ok(Some(x)) => x,
            Ok(None) => continue,
            Err(source) => {
                return Err(CliError::Can {
                    iface: iface.to_owned(),
                    what: format!("reading failed after {} frames", counts.frames),
                    source,
                })
            }
        };
        if counts.first_emg.is_none() && f.raw_id() == EMG_G0_ID && f.data().len() >= 2 {
            counts.first_emg = Some((time_us, f.data()[1]));
        }
        log.write_frame(time_us, iface, &f).map_err(io_err(path))?;
        counts.frames += 1;
    }
    log.flush().map_err(io_err(path))?;
    Ok(counts)
}

/// The scenario start on the log's time base (see the module doc).
fn scenario_start(c: &Counts) -> Result<u64, CliError> {
    match c.first_emg {
        None => Err(CliError::Usage(
            "no EMG_SAMPLES frame was recorded, so the trials cannot be placed on the \
             recording: is handsim (or the amplifier) running on this interface?"
                .into(),
        )),
        Some((t, 0)) => Ok(t),
        Some((_, n)) => Err(CliError::Usage(format!(
            "the first EMG sample recorded has counter {n}, not 0: the recording started after \
             handsim's scenario, so the trial times cannot be placed; start handctl record \
             before handsim"
        ))),
    }
}

fn read_trials(path: &Path) -> Result<Vec<Trial>, CliError> {
    let text = std::fs::read_to_string(path).map_err(io_err(path))?;
    let table = TrialTable::parse(&text).map_err(|e| {
        CliError::Usage(format!(
            "{}: not a trials file as handsim --trials-out writes it: {e}",
            path.display()
        ))
    })?;
    if table.trial.is_empty() {
        return Err(CliError::Usage(format!(
            "{}: holds no trials (record a calibration scenario)",
            path.display()
        )));
    }
    Ok(table.trial)
}

/// The session's metadata: the trials shifted onto the log's time base by `start_us`.
fn session_meta(trials: &[Trial], start_us: u64, mains_hz: u32) -> SessionMeta {
    let shifted = trials
        .iter()
        .map(|t| Trial {
            start_us: t.start_us + start_us,
            end_us: t.end_us + start_us,
            ..*t
        })
        .collect();
    let chain = ChainConfig {
        channels: EMG_CHANNELS,
        sample_rate_hz: 1000.0,
        mains_hz,
        ..ChainConfig::default()
    };
    // The log's time base is the kernel's receive stamps: the wall clock.
    SessionMeta::candump(chain, FRAMES_FILE, f64::from(ADC_MAX), shifted)
        .recorded_at(start_us / 1_000_000)
}

#[cfg(test)]
mod tests {
    use super::*;
    use decoder::session::TrialKind;

    #[test]
    fn trials_are_shifted_onto_the_log_time_base() {
        let t = Trial {
            id: 1,
            finger: Some(1),
            kind: TrialKind::Flexion,
            start_us: 1_000,
            end_us: 2_000,
            repetition: 1,
        };
        let text = session_meta(&[t], 1_700_000_000_000_000, 50).to_toml();
        let meta = decoder::session::SessionMeta::parse(&text, Path::new("session.toml"))
            .expect("decoder reads what the recorder writes");
        assert_eq!(meta.trials.len(), 1);
        assert_eq!(meta.trials[0].start_us, 1_700_000_000_001_000);
        assert_eq!(meta.trials[0].end_us, 1_700_000_000_002_000);
        // The log's first stamp is the calibration's date in the model file.
        assert_eq!(meta.recorded_utc.as_deref(), Some("2023-11-14T22:13:20Z"));
    }

    #[test]
    fn a_late_start_is_refused_with_the_reason() {
        let c = Counts {
            first_emg: Some((5, 17)),
            ..Counts::default()
        };
        let msg = scenario_start(&c).expect_err("late start").to_string();
        assert!(msg.contains("before handsim"), "{msg}");
        let none = scenario_start(&Counts::default())
            .expect_err("no EMG")
            .to_string();
        assert!(none.contains("no EMG_SAMPLES"), "{none}");
        assert_eq!(
            scenario_start(&Counts {
                first_emg: Some((42, 0)),
                ..Counts::default()
            })
            .expect("counter 0"),
            42
        );
    }
}
