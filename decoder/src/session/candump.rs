//! Loading a candump log of the bus as a recording: EMG_SAMPLES frames are checked (CRC),
//! decoded and reassembled into samples by `hand_dbc::emg::EmgAssembler`, exactly as the daemon
//! does live, so features computed offline equal the ones the daemon computed.

use std::path::Path;

use hand_dbc::candump::{read_log, CandumpError};
use hand_dbc::e2e::{E2eChecker, E2eStatus};
use hand_dbc::emg::{EmgAssembler, EmgConfig, EmgFrame, EMG_CHANNELS, EMG_LSB_UV};
use hand_dbc::messages::{EmgSamplesG0, EmgSamplesG1, EmgSamplesG2};

use super::error::SessionError;
use super::meta::SessionMeta;
use super::recording::Recording;

pub(crate) fn load_candump(meta: &SessionMeta, path: &Path) -> Result<Recording, SessionError> {
    let channels = meta.chain.channels;
    if channels > EMG_CHANNELS {
        return Err(SessionError::invalid(
            path,
            format!(
                "[chain] channels = {channels}, but the bus carries {EMG_CHANNELS} EMG channels"
            ),
        ));
    }
    let entries = read_log(path).map_err(|e| match e {
        CandumpError::Io(source) => SessionError::io(path, source),
        other => SessionError::recording(path, other.to_string()),
    })?;
    let period_us = (1e6 / meta.chain.sample_rate_hz).round() as u64;
    let mut assembler = EmgAssembler::try_new(EmgConfig {
        sample_period_us: period_us,
        ..EmgConfig::default()
    })
    .map_err(|e| SessionError::recording(path, format!("EMG reassembly: {e}")))?;
    // Only the CRC matters offline: counter steps are the assembler's business.
    let checker =
        |p| E2eChecker::try_new(p, 255).map_err(|e| SessionError::recording(path, e.to_string()));
    let mut checkers = [
        checker(EmgSamplesG0::E2E)?,
        checker(EmgSamplesG1::E2E)?,
        checker(EmgSamplesG2::E2E)?,
    ];
    let ids = [EmgSamplesG0::ID, EmgSamplesG1::ID, EmgSamplesG2::ID];
    let mut samples = Vec::new();
    let mut time_us = Vec::new();
    let mut breaks = Vec::new();
    let mut bad_crc = 0u64;
    let mut sink = |s: &hand_dbc::emg::EmgSample| {
        if s.after_gap {
            breaks.push(time_us.len());
        }
        samples.extend(s.raw[..channels].iter().map(|&r| f64::from(r) * EMG_LSB_UV));
        time_us.push(s.received_us);
    };
    for (line, e) in entries.iter().enumerate() {
        let id = e.frame.raw_id();
        let Some(g) = ids.iter().position(|&i| i == id) else {
            continue;
        };
        if e.frame.is_extended() || e.frame.is_remote() {
            continue;
        }
        if checkers[g].check(Some(e.frame.data())) == E2eStatus::Error {
            bad_crc += 1;
            continue;
        }
        let frame = EmgFrame::decode(id, e.frame.data())
            .map_err(|err| SessionError::recording(path, format!("line {}: {err}", line + 1)))?;
        if let Some(frame) = frame {
            assembler.push(&frame, e.time_us, &mut sink);
        }
    }
    assembler.flush(&mut sink);
    if time_us.is_empty() {
        return Err(SessionError::recording(
            path,
            format!(
                "no EMG_SAMPLES frames in the log ({} lines, {bad_crc} with a bad CRC)",
                entries.len()
            ),
        ));
    }
    // Receive times can step back by a frame's worth under reordering; the trial lookup needs
    // them non-decreasing.
    for i in 1..time_us.len() {
        time_us[i] = time_us[i].max(time_us[i - 1]);
    }
    let stats = assembler.stats();
    Ok(Recording {
        channels,
        samples,
        time_us,
        lost_samples: stats.lost_samples,
        breaks,
        bad_frames: bad_crc,
        unit_per_raw: EMG_LSB_UV,
    })
}
