//! What the monitor shows, whatever the source: [`MonitorState`], fed by the daemon's live
//! lines ([`super::live`]) or by frames from the bus or a log ([`super::frames`]), drawn by the
//! widgets. Plain data: a widget takes a state, never a source.

use decoder::session::{noisy_against_others, GateConfig};
use hand_dbc::hand::N_FINGERS;

/// Points kept for the scrolling plot: 60 s at the monitor's 10 Hz.
pub const HISTORY_LEN: usize = 600;

/// One EMG channel.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ChannelView {
    /// RMS of the band-passed signal over the last 200 ms, µV.
    pub rms_uv: f64,
    /// Rest level of the deployed model's calibration, µV, when known.
    pub rest_uv: Option<f64>,
    /// The amplifier reports the electrode off the skin.
    pub lead_off: bool,
    /// The amplifier reports the channel clipped.
    pub saturated: bool,
    /// Noisy by the calibration gate's rule (see [`MonitorState::update_noisy`]).
    pub noisy: bool,
}

/// One finger.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct FingerView {
    /// Conditioned label (flexion +1, extension -1); `None` when the source does not carry it.
    pub label: Option<f64>,
    /// Commanded force, N.
    pub force_n: f64,
    /// Commanded velocity, rad/s.
    pub velocity_rad_s: f64,
    /// Joint angle the finger's controller reports, rad.
    pub position_rad: f64,
    /// Force the finger's controller reports, N.
    pub reported_force_n: f64,
    /// The finger is disabled.
    pub disabled: bool,
    /// The last setpoint was ACTIVE.
    pub active: bool,
}

/// The daemon's side.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct DaemonView {
    /// BOOT, READY, RUNNING, SAFE; `None` before anything was heard from the daemon.
    pub state: Option<String>,
    /// Faults in force.
    pub faults: Vec<String>,
    /// Model id, 8 hex digits as HAND_HEARTBEAT carries it.
    pub model_id: Option<String>,
    /// The model's kind and file (the daemon source only).
    pub model_detail: Option<String>,
    /// Tick latency (newest sample -> setpoints written) p50 and p99, µs.
    pub latency_p50_us: Option<u64>,
    /// See `latency_p50_us`.
    pub latency_p99_us: Option<u64>,
    /// Deadline misses counted.
    pub deadline_misses: u64,
    /// E2E errors counted.
    pub e2e_errors: u64,
    /// EMG samples lost counted.
    pub samples_lost: u64,
    /// Windows beyond the calibration's envelope (held inside it) counted.
    pub beyond_calibration: u64,
    /// Implausible windows counted (one channel far beyond the calibration, the others not).
    pub implausible: u64,
    /// Bus load, fraction of the bit rate over the last second.
    pub bus_load: Option<f64>,
    /// The CAN controller's state and its error count since start, e.g. "error_active, 0
    /// errors" (from the daemon's live lines).
    pub can: Option<String>,
}

/// Scrolling history of every finger's label and reported force, one point per sample.
#[derive(Debug, Clone, PartialEq)]
pub struct History {
    /// (source time µs, label per finger, reported force per finger), oldest first in ring
    /// order from `head`.
    points: Vec<(u64, [f64; N_FINGERS], [f64; N_FINGERS])>,
    head: usize,
}

impl Default for History {
    fn default() -> Self {
        Self {
            points: Vec::with_capacity(HISTORY_LEN),
            head: 0,
        }
    }
}

impl History {
    /// Adds a point, dropping the oldest beyond [`HISTORY_LEN`].
    pub fn push(&mut self, t_us: u64, fingers: &[FingerView]) {
        let mut label = [0.0; N_FINGERS];
        let mut force = [0.0; N_FINGERS];
        for (f, v) in fingers.iter().take(N_FINGERS).enumerate() {
            label[f] = v.label.unwrap_or(f64::NAN);
            force[f] = v.reported_force_n;
        }
        if self.points.len() < HISTORY_LEN {
            self.points.push((t_us, label, force));
        } else {
            self.points[self.head] = (t_us, label, force);
            self.head = (self.head + 1) % HISTORY_LEN;
        }
    }

    /// (time s, label, reported force N) of one finger, oldest first; labels unknown are NaN.
    pub fn finger(&self, f: usize) -> impl Iterator<Item = (f64, f64, f64)> + '_ {
        let (new, old) = self.points.split_at(self.head);
        old.iter()
            .chain(new)
            .map(move |(t, l, r)| (*t as f64 * 1e-6, l[f], r[f]))
    }

    /// Points held.
    #[cfg(test)]
    pub fn len(&self) -> usize {
        self.points.len()
    }
}

/// Everything the monitor shows.
#[derive(Debug, Clone, PartialEq)]
pub struct MonitorState {
    /// Where the data comes from, for the title.
    pub source: String,
    /// Source time of the newest data, µs (the daemon's clock, or the frames' receive times).
    pub t_us: u64,
    /// Source time of the first refresh, µs: the screen shows time since then.
    pub first_us: Option<u64>,
    /// Per EMG channel.
    pub channels: Vec<ChannelView>,
    /// Per finger, 0 thumb .. 4 pinky.
    pub fingers: Vec<FingerView>,
    /// The daemon.
    pub daemon: DaemonView,
    /// The plot's history.
    pub history: History,
    /// Each CiA 402 finger's drive (the daemon source only; empty when every finger is native).
    pub drives: Vec<driver::protocol::DriveLine>,
    /// The source ended (end of the log, daemon gone), and why.
    pub ended: Option<String>,
}

impl MonitorState {
    /// An empty state for `channels` EMG channels.
    pub fn new(source: impl Into<String>, channels: usize) -> Self {
        Self {
            source: source.into(),
            t_us: 0,
            first_us: None,
            channels: vec![ChannelView::default(); channels],
            fingers: vec![FingerView::default(); N_FINGERS],
            daemon: DaemonView::default(),
            history: History::default(),
            drives: Vec::new(),
            ended: None,
        }
    }

    /// Sets every channel's noisy flag by the calibration gate's rule
    /// ([`decoder::session::noisy_against_others`] with the gate's ratio): on the rest levels
    /// when all are known (an electrode that was noisy at calibration), else on the current
    /// levels (meaningful while the patient rests: during a contraction one channel can be
    /// far above the others without being noisy).
    pub fn update_noisy(&mut self) {
        let ratio = GateConfig::default().noisy_ratio;
        let rest: Option<Vec<f64>> = self.channels.iter().map(|c| c.rest_uv).collect();
        let levels =
            rest.unwrap_or_else(|| self.channels.iter().map(|c| c.rms_uv).collect::<Vec<_>>());
        for c in 0..self.channels.len() {
            self.channels[c].noisy = noisy_against_others(&levels, c, ratio).is_some();
        }
    }

    /// Seconds of data since the first refresh.
    pub fn elapsed_s(&self) -> f64 {
        self.first_us
            .map_or(0.0, |f| self.t_us.saturating_sub(f) as f64 * 1e-6)
    }

    /// One point of the plot at the current time.
    pub fn sample_history(&mut self) {
        self.first_us.get_or_insert(self.t_us);
        self.history.push(self.t_us, &self.fingers);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn history_keeps_the_newest_points_in_order() {
        let mut h = History::default();
        let mut f = vec![FingerView::default(); N_FINGERS];
        for k in 0..(HISTORY_LEN as u64 + 7) {
            f[2].reported_force_n = k as f64;
            h.push(k * 100_000, &f);
        }
        assert_eq!(h.len(), HISTORY_LEN);
        let pts: Vec<_> = h.finger(2).collect();
        assert_eq!(pts[0].2, 7.0);
        assert_eq!(pts[HISTORY_LEN - 1].2, (HISTORY_LEN + 6) as f64);
        assert!(pts.windows(2).all(|w| w[0].0 < w[1].0));
        assert!(pts[0].1.is_nan(), "no label from this source");
    }

    #[test]
    fn noisy_uses_rest_levels_when_known_else_current_levels() {
        let mut s = MonitorState::new("t", 4);
        for (c, v) in [1.0, 1.2, 0.9, 30.0].into_iter().enumerate() {
            s.channels[c].rms_uv = v;
        }
        s.update_noisy();
        let flags: Vec<bool> = s.channels.iter().map(|c| c.noisy).collect();
        assert_eq!(flags, [false, false, false, true]);
        for (c, v) in [10.0, 1.0, 1.1, 1.0].into_iter().enumerate() {
            s.channels[c].rest_uv = Some(v);
        }
        s.update_noisy();
        let flags: Vec<bool> = s.channels.iter().map(|c| c.noisy).collect();
        assert_eq!(flags, [true, false, false, false]);
    }
}
