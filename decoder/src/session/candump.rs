//! Loading a candump log of the bus as a recording: the EMG_SAMPLES frames go through
//! `hand_dbc::emg_front::EmgFront`, the daemon's own front end (E2E check before decoding, the
//! same counter delta, gap rule, rails and µV conversion), so a session reads a log exactly as
//! the daemon would have read the bus, and the features computed offline equal the daemon's.

use std::path::Path;

use hand_dbc::candump::{read_log, CandumpError};
use hand_dbc::emg::{EMG_CHANNELS, EMG_LSB_UV};
use hand_dbc::emg_front::{EmgFront, EmgFrontConfig, EmgFrontSettings, FrontSample};

use super::error::SessionError;
use super::meta::SessionMeta;
use super::recording::Recording;

/// The front end's settings for a session: the daemon's defaults at the session's rate.
fn front_settings(meta: &SessionMeta, path: &Path) -> Result<EmgFrontSettings, SessionError> {
    let channels = meta.chain.channels;
    if channels > EMG_CHANNELS {
        return Err(SessionError::invalid(
            path,
            format!(
                "[chain] channels = {channels}, but the bus carries {EMG_CHANNELS} EMG channels"
            ),
        ));
    }
    EmgFrontSettings::try_new(EmgFrontConfig {
        channels,
        ..EmgFrontConfig::at_rate(meta.chain.sample_rate_hz)
    })
    .map_err(|e| SessionError::recording(path, e.to_string()))
}

pub(crate) fn load_candump(meta: &SessionMeta, path: &Path) -> Result<Recording, SessionError> {
    let settings = front_settings(meta, path)?;
    let entries = read_log(path).map_err(|e| match e {
        CandumpError::Io(source) => SessionError::io(path, source),
        other => SessionError::recording(path, other.to_string()),
    })?;
    let mut front = EmgFront::new(&settings);
    let channels = front.channels();
    let mut samples = Vec::new();
    let mut time_us = Vec::new();
    let mut breaks = Vec::new();
    let mut sink = |s: &FrontSample| {
        if s.after_gap {
            breaks.push(time_us.len());
        }
        samples.extend_from_slice(s.uv());
        time_us.push(s.received_us);
    };
    for e in &entries {
        front.on_frame(&e.frame, e.time_us, &mut sink);
    }
    front.flush(&mut sink);
    let c = front.counters();
    let dropped = c.e2e_errors + c.undecodable;
    if time_us.is_empty() {
        return Err(SessionError::recording(
            path,
            format!(
                "no EMG_SAMPLES frames in the log ({} lines, {dropped} failed the E2E check or decoding)",
                entries.len()
            ),
        ));
    }
    // Receive times can step back by a frame's worth under reordering; the trial lookup needs
    // them non-decreasing.
    for i in 1..time_us.len() {
        time_us[i] = time_us[i].max(time_us[i - 1]);
    }
    Ok(Recording {
        channels,
        samples,
        time_us,
        lost_samples: c.samples_lost,
        breaks,
        bad_frames: dropped,
        unit_per_raw: EMG_LSB_UV,
    })
}
