//! The recording side of the calibration: every frame received goes into the candump log
//! (`DIR/frames.log`, appended to when resuming), and through the monitor's own frame decoder
//! (the one EMG front end and signal chain) into a 10 Hz trace of the contraction level: the
//! mean over channels of the 200 ms RMS, in µV. The trace drives the live bar and places each
//! trial on the recording ([`super::placement`]). The EMG samples are also kept in memory as
//! a [`Recording`], exactly as a session later loads them from the log (the same front end,
//! the same settings), so that a trial's check never re-reads the log: a check that took a
//! while would let the socket's receive queue overflow and lose frames.

use std::fs::{File, OpenOptions};
use std::io::BufWriter;
use std::path::{Path, PathBuf};

use decoder::dsp::ChainSettings;
use decoder::session::Recording;
use hand_dbc::candump::LogWriter;
use hand_dbc::emg::EMG_LSB_UV;
use hand_dbc::emg_front::{EmgFront, EmgFrontConfig, EmgFrontSettings, FrontSample};
use hand_dbc::CanFrame;

use super::error::CalibrateError;
use crate::monitor::frames::FrameDecoder;
use crate::monitor::state::MonitorState;

/// The log file inside the output directory (the name `handctl record` uses).
pub const FRAMES_FILE: &str = "frames.log";

/// Trace points kept (an hour at 10 Hz would be 36 000; a calibration is minutes).
const TRACE_CAP: usize = 1 << 16;

/// The log writer and the level trace.
pub struct Recorder {
    path: PathBuf,
    iface: String,
    log: LogWriter<BufWriter<File>>,
    decoder: FrameDecoder,
    state: MonitorState,
    trace: Vec<(u64, f64)>,
    frames: u64,
    front: EmgFront,
    recording: Recording,
}

/// A bus recording of `channels` channels with no sample yet (µV per LSB as the bus's).
pub fn empty_recording(channels: usize) -> Recording {
    Recording {
        channels,
        samples: Vec::new(),
        time_us: Vec::new(),
        lost_samples: 0,
        breaks: Vec::new(),
        bad_frames: 0,
        unit_per_raw: EMG_LSB_UV,
    }
}

/// Appends one front-end sample to `r` (as `decoder::session`'s candump loader does: a gap
/// is a break, times never step back).
fn push_sample(r: &mut Recording, s: &FrontSample) {
    if s.after_gap {
        r.breaks.push(r.time_us.len());
    }
    r.samples.extend_from_slice(s.uv());
    let t = r
        .time_us
        .last()
        .map_or(s.received_us, |&l| s.received_us.max(l));
    r.time_us.push(t);
}

impl Recorder {
    /// Opens `dir/frames.log` for frames of `iface`, decoding EMG with the chain `settings`:
    /// a new log, or with `resumed` (the old log's recording) appended to, the old samples
    /// kept in memory with a break after them.
    pub fn open(
        dir: &Path,
        iface: &str,
        settings: &ChainSettings,
        resumed: Option<Recording>,
    ) -> Result<Self, CalibrateError> {
        let append = resumed.is_some();
        let path = dir.join(FRAMES_FILE);
        let file = OpenOptions::new()
            .create(true)
            .write(true)
            .append(append)
            .truncate(!append)
            .open(&path)
            .map_err(CalibrateError::io(&path))?;
        let front = EmgFrontSettings::try_new(EmgFrontConfig {
            channels: settings.n_channels(),
            ..EmgFrontConfig::at_rate(settings.sample_rate_hz())
        })
        .map_err(|e| CalibrateError::Bus(format!("EMG front end: {e}")))?;
        Ok(Recorder {
            front: EmgFront::new(&front),
            recording: resumed.map_or_else(
                || empty_recording(settings.n_channels()),
                |mut r| {
                    r.breaks.push(r.time_us.len());
                    r
                },
            ),
            path,
            iface: iface.to_owned(),
            log: LogWriter::new(BufWriter::new(file)),
            decoder: FrameDecoder::new(settings),
            state: MonitorState::new("calibrate", settings.n_channels()),
            trace: Vec::new(),
            frames: 0,
        })
    }

    /// Logs one frame received (or sent by us) at `t_us` and feeds the level trace.
    pub fn on_frame(&mut self, frame: &CanFrame, t_us: u64) -> Result<(), CalibrateError> {
        self.log
            .write_frame(t_us, &self.iface, frame)
            .map_err(CalibrateError::io(&self.path))?;
        self.frames += 1;
        let rec = &mut self.recording;
        self.front
            .on_frame(frame, t_us, &mut |s| push_sample(rec, s));
        let before = self.state.t_us;
        self.decoder.on_frame(&mut self.state, frame, t_us);
        if self.state.t_us != before && self.trace.len() < TRACE_CAP {
            let ch = &self.state.channels;
            let mean = ch.iter().map(|c| c.rms_uv).sum::<f64>() / ch.len().max(1) as f64;
            self.trace.push((self.state.t_us, mean));
        }
        Ok(())
    }

    /// Writes what is buffered to the file (before a check reads the log).
    pub fn flush(&mut self) -> Result<(), CalibrateError> {
        self.log.flush().map_err(CalibrateError::io(&self.path))
    }

    /// The level trace: (time µs, mean channel RMS µV), 10 Hz.
    pub fn trace(&self) -> &[(u64, f64)] {
        &self.trace
    }

    /// The newest level, µV (0 before the first 100 ms).
    pub fn level(&self) -> f64 {
        self.trace.last().map_or(0.0, |&(_, l)| l)
    }

    /// The EMG recorded in this run so far.
    pub fn recording(&self) -> &Recording {
        &self.recording
    }

    /// Frames logged so far.
    pub fn frames(&self) -> u64 {
        self.frames
    }
}
