//! `handctl calibrate`: the guided calibration of a real patient (issue 14), from the first
//! cue to a verified model ready to deploy.
//!
//! - [`protocol`]: the trials and their timing (built-in default, or a validated TOML file);
//! - [`sequencer`]: the pure state machine PREPARE -> HOLD -> RELAX -> check, on the caller's
//!   clock; [`cue`]: its CALIBRATION_CUE frames;
//! - [`recorder`]: the candump log and the live level trace (the monitor's frame decoder);
//!   [`placement`]: each trial placed from its cue times and the measured onset;
//! - [`check`]: the quality gates on each attempt; [`store`]: the session on disk after every
//!   kept trial, and `--resume`; [`resume_check`]: `--resume`'s age limit and rest check;
//! - [`workflow`]: the loop over a [`workflow::Transport`] and a [`workflow::Pace`] (shared by
//!   the command and the in-memory test); [`socket`]: SocketCAN and the wall clock;
//! - [`link`]: the calibrating hold asked of a running handd;
//! - [`training`] and [`summary`]: train, verify, write `model.hsm`, the per-finger summary;
//! - [`output`]: the live line, plain lines, or nothing.

pub mod check;
pub mod cue;
pub mod error;
pub mod link;
pub mod output;
pub mod placement;
pub mod protocol;
pub mod recorder;
pub mod resume_check;
pub mod sequencer;
pub mod socket;
pub mod store;
pub mod summary;
pub mod training;
pub mod workflow;

#[cfg(test)]
mod mem_test;
#[cfg(test)]
mod tests;

use std::io::{BufRead, IsTerminal};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use decoder::dsp::ChainConfig;
use hand_dbc::emg::EMG_CHANNELS;

use self::link::{DaemonLink, HoldOutcome, SocketLink};
use self::output::{Mode, Output};
use self::protocol::Protocol;
use self::workflow::Plan;
use super::args::CalibrateArgs;
use super::error::CliError;

/// The session's chain: the bus's 12 channels at 1 kHz, the mains to notch.
pub fn chain(mains_hz: u32) -> ChainConfig {
    ChainConfig {
        channels: EMG_CHANNELS,
        sample_rate_hz: 1000.0,
        mains_hz,
        ..ChainConfig::default()
    }
}

/// `handctl calibrate`.
pub fn run(a: &CalibrateArgs) -> Result<(), CliError> {
    // The protocol first: a bad file fails before anything else happens.
    let protocol = a
        .protocol
        .as_deref()
        .map(Protocol::load)
        .transpose()
        .map_err(error::CalibrateError::from)?;
    let mode = if a.yes || !std::io::stdout().is_terminal() {
        Mode::Plain
    } else {
        Mode::Live
    };
    let trials = protocol.clone().unwrap_or_default().trials().len();
    let mut out = Output::new(mode, trials);
    let mut bus = socket::SocketBus::open(&a.iface)?;
    if let Some((got, wanted)) = bus.small_rcvbuf() {
        out.say(&format!(
            "warning: the kernel granted a {got}-byte receive buffer of the {wanted} asked for: \
             set net.core.rmem_max (README, install), or a trial's check may lose frames (the \
             session line counts them)"
        ));
    }
    hold_hand(a, &mut out)?;
    if !a.yes {
        confirm(&mut out)?;
    }
    let stop = catch_ctrl_c()?;
    let plan = Plan {
        protocol,
        dir: a.out.clone(),
        iface: a.iface.clone(),
        chain: chain(a.mains),
        resume: a.resume,
        max_resume_age_min: a.max_resume_age_min,
        force_rest_mismatch: a.force_rest_mismatch,
    };
    let done = workflow::record_session(&mut bus, &mut socket::WallClock, &plan, &mut out, &stop)?;
    // From here on Ctrl-C ends the process at once (the model file is written atomically).
    stop.store(true, Ordering::Relaxed);
    out.say(&format!(
        "session: {} trials kept in {} ({} frames logged, {} dropped by the kernel, {} \
         attempt(s) repeated); training",
        done.kept,
        a.out.display(),
        done.frames,
        bus.kernel_drops(),
        done.repeats.len()
    ));
    let trained = training::train_session(&a.out, &a.training, a.tolerance, a.patient.as_deref())?;
    print!(
        "{}",
        summary::render(&trained, &summary::summarize(&trained))
    );
    Ok(())
}

/// Ctrl-C: while the flag is down the first one raises it (the recording stops cleanly and
/// keeps what is done); once it is up, Ctrl-C ends the process.
fn catch_ctrl_c() -> Result<Arc<AtomicBool>, CliError> {
    use signal_hook::consts::SIGINT;
    let stop = Arc::new(AtomicBool::new(false));
    let bad = |e: std::io::Error| CliError::Usage(format!("cannot catch Ctrl-C: {e}"));
    signal_hook::flag::register_conditional_shutdown(SIGINT, 130, Arc::clone(&stop))
        .map_err(bad)?;
    signal_hook::flag::register(SIGINT, Arc::clone(&stop)).map_err(bad)?;
    Ok(stop)
}

/// Asks a running handd to hold the hand; says clearly when none runs.
fn hold_hand(a: &CalibrateArgs, out: &mut Output) -> Result<(), CliError> {
    let mut link = SocketLink {
        path: super::daemon::socket_of(&a.daemon)?,
    };
    match link.calibrating().map_err(CliError::Usage)? {
        HoldOutcome::NoDaemon(p) => out.say(&format!(
            "no handd runs (no daemon on {}): nothing drives the hand while calibrating",
            p.display()
        )),
        HoldOutcome::Held(m) => out.say(&format!(
            "handd holds the hand while calibrating ({m}); it moves again only after \
             `handctl deploy` and `handctl arm`"
        )),
    }
    Ok(())
}

/// Waits for Enter before the first cue.
fn confirm(out: &mut Output) -> Result<(), CliError> {
    out.say(
        "electrodes on, the patient seated with the arm relaxed and able to see the cues? \
         press Enter to start (Ctrl-C stops; --resume continues later)",
    );
    let mut line = String::new();
    std::io::stdin()
        .lock()
        .read_line(&mut line)
        .map_err(|source| CliError::Io {
            path: "stdin".into(),
            source,
        })?;
    Ok(())
}
