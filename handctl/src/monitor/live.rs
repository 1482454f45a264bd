//! The daemon's subscription lines (`{"cmd":"subscribe"}` on the control socket), applied to
//! the monitor's state.
//!
//! [`Live`] mirrors `driver::live::Live` field for field (the schema both sides code to); it is
//! kept here until that type is in the driver this crate builds against, then it is replaced by
//! a `pub use`. Unknown fields are ignored and missing ones take their defaults, as the schema
//! allows fields to be added.

use driver::stats::Percentiles;
use serde::Deserialize;

use super::state::MonitorState;

/// The model in use.
#[derive(Debug, Clone, PartialEq, Eq, Deserialize, Default)]
#[serde(default)]
pub struct ModelInfo {
    /// As HAND_HEARTBEAT's model id, hex.
    pub id: String,
    /// The model file.
    pub path: String,
    /// The model's kind.
    pub kind: String,
}

/// Counters since the daemon started.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Default)]
#[serde(default)]
pub struct Counters {
    /// Ticks late beyond their slack.
    pub deadline_misses: u64,
    /// EMG samples lost (bridged).
    pub samples_lost: u64,
    /// Frames that failed their E2E check.
    pub e2e_errors: u64,
    /// Frames refused otherwise.
    pub bad_frames: u64,
    /// Frames received.
    pub frames_rx: u64,
    /// Frames sent.
    pub frames_tx: u64,
}

/// One EMG channel.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Default)]
#[serde(default)]
pub struct ChannelLive {
    /// RMS of the band-passed signal over the 200 ms window, µV.
    pub rms_uv: f64,
    /// Electrode off.
    pub lead_off: bool,
    /// Clipped.
    pub saturated: bool,
}

/// One finger.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Default)]
#[serde(default)]
pub struct FingerLive {
    /// Conditioned label.
    pub label: f64,
    /// Commanded force, N.
    pub force_n: f64,
    /// Commanded velocity, rad/s.
    pub velocity_rad_s: f64,
    /// Reported joint angle, rad.
    pub reported_position_rad: f64,
    /// Reported force, N.
    pub reported_force_n: f64,
    /// Disabled.
    pub disabled: bool,
    /// ACTIVE setpoint.
    pub active: bool,
}

/// One subscription line.
#[derive(Debug, Clone, PartialEq, Deserialize, Default)]
#[serde(default)]
pub struct Live {
    /// Daemon clock at the tick, µs.
    pub t_us: u64,
    /// Ticks since start.
    pub tick: u64,
    /// BOOT | READY | RUNNING | SAFE.
    pub state: String,
    /// Faults in force.
    pub faults: Vec<String>,
    /// The model.
    pub model: ModelInfo,
    /// Newest sample -> setpoints written, µs.
    pub latency_us: Percentiles,
    /// Tick compute time, µs.
    pub compute_us: Percentiles,
    /// Counters.
    pub counters: Counters,
    /// Bus load, 0..1.
    pub bus_load: f64,
    /// Per channel.
    pub channels: Vec<ChannelLive>,
    /// Rest levels of the model's calibration, µV.
    pub rest_rms_uv: Option<Vec<f64>>,
    /// Per finger.
    pub fingers: Vec<FingerLive>,
}

impl MonitorState {
    /// Takes one live line: everything it carries replaces what was shown, then one plot point.
    pub fn apply_live(&mut self, l: &Live) {
        self.t_us = l.t_us;
        if self.channels.len() != l.channels.len() {
            self.channels.resize(l.channels.len(), Default::default());
        }
        for (c, (v, ch)) in self.channels.iter_mut().zip(&l.channels).enumerate() {
            v.rms_uv = ch.rms_uv;
            v.lead_off = ch.lead_off;
            v.saturated = ch.saturated;
            v.rest_uv = l.rest_rms_uv.as_ref().and_then(|r| r.get(c).copied());
        }
        for (v, f) in self.fingers.iter_mut().zip(&l.fingers) {
            v.label = Some(f.label);
            v.force_n = f.force_n;
            v.velocity_rad_s = f.velocity_rad_s;
            v.position_rad = f.reported_position_rad;
            v.reported_force_n = f.reported_force_n;
            v.disabled = f.disabled;
            v.active = f.active;
        }
        let d = &mut self.daemon;
        d.state = Some(l.state.clone());
        d.faults.clone_from(&l.faults);
        d.model_id = (!l.model.id.is_empty()).then(|| l.model.id.clone());
        d.model_detail = (!l.model.kind.is_empty() || !l.model.path.is_empty()).then(|| {
            format!("{} {}", l.model.kind, l.model.path)
                .trim()
                .to_owned()
        });
        d.latency_p50_us = Some(l.latency_us.p50_us);
        d.latency_p99_us = Some(l.latency_us.p99_us);
        d.deadline_misses = l.counters.deadline_misses;
        d.e2e_errors = l.counters.e2e_errors;
        d.samples_lost = l.counters.samples_lost;
        d.bus_load = Some(l.bus_load);
        self.update_noisy();
        self.sample_history();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_line_of_the_schema_fills_the_state() {
        let line = r#"{"t_us":5000000,"tick":100,"state":"RUNNING","faults":[],
            "model":{"id":"1a2b3c4d","path":"/var/lib/handstack/model.hsm","kind":"ResDD"},
            "latency_us":{"count":10,"p50_us":800,"p99_us":1500,"max_us":2000},
            "compute_us":{"count":10,"p50_us":20,"p99_us":40,"max_us":50},
            "counters":{"deadline_misses":2,"samples_lost":3,"e2e_errors":4,"bad_frames":0,
                        "frames_rx":1,"frames_tx":2},
            "bus_load":0.46,
            "channels":[{"rms_uv":12.5,"lead_off":true,"saturated":false},
                        {"rms_uv":3.0,"lead_off":false,"saturated":true}],
            "rest_rms_uv":[2.0,2.5],
            "fingers":[{"label":0.5,"force_n":5.0,"velocity_rad_s":0.1,
                        "reported_position_rad":0.7,"reported_force_n":4.5,
                        "disabled":false,"active":true}],
            "a_field_added_later":1}"#;
        let live: Live = serde_json::from_str(line).expect("the schema parses");
        let mut s = MonitorState::new("daemon", 12);
        s.apply_live(&live);
        assert_eq!(s.channels.len(), 2);
        assert_eq!(s.channels[0].rms_uv, 12.5);
        assert!(s.channels[0].lead_off && s.channels[1].saturated);
        assert_eq!(s.channels[1].rest_uv, Some(2.5));
        assert_eq!(s.fingers[0].label, Some(0.5));
        assert!(s.fingers[0].active);
        assert_eq!(s.daemon.state.as_deref(), Some("RUNNING"));
        assert_eq!(s.daemon.model_id.as_deref(), Some("1a2b3c4d"));
        assert_eq!(
            (s.daemon.latency_p50_us, s.daemon.latency_p99_us),
            (Some(800), Some(1500))
        );
        assert_eq!(s.daemon.deadline_misses, 2);
        assert_eq!(s.history.len(), 1);
        assert_eq!(s.t_us, 5_000_000);
    }
}
