//! The live snapshot `handctl monitor` shows: one [`Live`] per line on a subscription
//! (`{"cmd":"subscribe","every_ms":100}` on the control socket).
//!
//! The tick only copies fixed-size values into the loop's [`Snapshot`] (no allocation); the
//! publisher thread turns that copy into a [`Live`] and serialises it, off the tick. Unknown
//! fields are not denied, so fields can be added later without breaking older clients.

use serde::{Deserialize, Serialize};

use crate::daemon::Snapshot;
use crate::stats::Percentiles;
use crate::units::N_FINGERS;

/// Which model runs.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(default)]
pub struct ModelInfo {
    /// The model id as HAND_HEARTBEAT carries it (FNV-1a of the file), 8 hex digits.
    pub id: String,
    /// The model file.
    pub path: String,
    /// The model's kind (`ResDD`, ...).
    pub kind: String,
}

/// Counters since start.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(default)]
pub struct Counters {
    /// Ticks that started later than their deadline plus the configured slack.
    pub deadline_misses: u64,
    /// EMG samples lost (bridged).
    pub samples_lost: u64,
    /// Frames that failed their E2E check.
    pub e2e_errors: u64,
    /// Frames with an unknown id, a wrong length or values out of range.
    pub bad_frames: u64,
    /// Frames received from the bus (all of them, read at the ticks).
    pub frames_rx: u64,
    /// Frames the daemon sent.
    pub frames_tx: u64,
    /// Windows beyond the calibration's envelope, held inside it before the model.
    pub beyond_calibration: u64,
    /// Windows found implausible (one channel far beyond the calibration, the others not).
    #[serde(default)]
    pub implausible: u64,
}

/// One EMG channel.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
#[serde(default)]
pub struct ChannelLive {
    /// RMS of the band-passed signal over the window the model last ran on, µV: the daemon's
    /// RMS feature. 0 before the model's first run; it holds its last value while the window
    /// is invalid (the model does not run then).
    pub rms_uv: f64,
    /// The amplifier's last EMG_STATUS reports this channel's lead off.
    pub lead_off: bool,
    /// The amplifier's last EMG_STATUS reports this channel saturated.
    pub saturated: bool,
}

/// One finger.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
#[serde(default)]
pub struct FingerLive {
    /// Conditioned label of the last setpoint (0 when stopped).
    pub label: f64,
    /// Commanded force, N.
    pub force_n: f64,
    /// Commanded velocity, rad/s.
    pub velocity_rad_s: f64,
    /// Joint angle the finger controller last reported, rad (0 before its first status).
    pub reported_position_rad: f64,
    /// Force the finger controller last reported, N (0 before its first status).
    pub reported_force_n: f64,
    /// The finger is disabled (its controller fell silent).
    pub disabled: bool,
    /// The last setpoint was ACTIVE mode (not a hold or a safe stop).
    pub active: bool,
}

/// One line of a subscription. See the module docs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
#[serde(default)]
pub struct Live {
    /// The tick's deadline on the daemon's clock, µs.
    pub t_us: u64,
    /// Ticks since start.
    pub tick: u64,
    /// BOOT, READY, RUNNING or SAFE.
    pub state: String,
    /// Faults in force; empty when none.
    pub faults: Vec<String>,
    /// Which model runs.
    pub model: ModelInfo,
    /// Newest sample frame -> setpoints written.
    pub latency_us: Percentiles,
    /// Tick compute time.
    pub compute_us: Percentiles,
    /// Counters since start.
    pub counters: Counters,
    /// Worst-case bits (stuffing included, hand.dbc's formula) of the frames the daemon read
    /// and sent over the last second, as a fraction of the bus's 1 Mbit/s; 0..1.
    pub bus_load: f64,
    /// The CAN controller's state and every bus error class counted (absent from a daemon
    /// older than this field).
    #[serde(default)]
    pub bus: crate::protocol::BusStatus,
    /// Per EMG channel.
    pub channels: Vec<ChannelLive>,
    /// Per channel rest level of the running model's calibration (the mean RMS feature over its
    /// rest windows), µV; `None` when the model file does not carry it (older files, a
    /// calibration without rest).
    pub rest_rms_uv: Option<Vec<f64>>,
    /// Per finger, 0 thumb .. 4 pinky.
    pub fingers: Vec<FingerLive>,
    /// Each CiA 402 finger's drive (none when every finger is native, and from a daemon older
    /// than this field).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub drives: Vec<crate::protocol::DriveLine>,
}

impl Live {
    /// The live view of a tick's snapshot, for the model `model` whose calibration's rest
    /// levels are `rest_rms_uv`. Off the tick: allocates.
    pub fn from_snapshot(s: &Snapshot, model: &ModelInfo, rest_rms_uv: Option<&[f64]>) -> Self {
        Self {
            t_us: s.t_us,
            tick: s.counters.ticks,
            state: s.state.to_string(),
            faults: s.faults.iter().map(|f| f.name().to_owned()).collect(),
            model: model.clone(),
            latency_us: s.latency,
            compute_us: s.compute,
            counters: Counters {
                deadline_misses: s.counters.deadline_misses,
                samples_lost: s.counters.samples_lost,
                e2e_errors: s.counters.e2e_errors,
                bad_frames: s.counters.bad_frames,
                frames_rx: s.frames_rx,
                frames_tx: s.frames_tx,
                beyond_calibration: s.counters.beyond_calibration,
                implausible: s.counters.implausible,
            },
            bus_load: s.bus_load,
            bus: crate::protocol::BusStatus {
                controller: s.bus.state.name().into(),
                counters: s.bus.counters,
            },
            channels: (0..s.channels)
                .map(|c| ChannelLive {
                    rms_uv: s.channel_rms_uv[c],
                    lead_off: s.lead_off_mask & (1 << c) != 0,
                    saturated: s.saturation_mask & (1 << c) != 0,
                })
                .collect(),
            rest_rms_uv: rest_rms_uv.map(<[f64]>::to_vec),
            fingers: (0..N_FINGERS)
                .map(|f| FingerLive {
                    label: s.setpoints[f].label,
                    force_n: s.setpoints[f].force.0,
                    velocity_rad_s: s.setpoints[f].velocity.0,
                    reported_position_rad: s.reported_position[f],
                    reported_force_n: s.reported_force[f],
                    disabled: s.disabled[f],
                    active: s.active[f],
                })
                .collect(),
            drives: crate::protocol::drive_lines(&s.drives, s.t_us),
        }
    }
}
