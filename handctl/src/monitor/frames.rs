//! Frames from the bus or a candump log into the monitor's state, without the daemon.
//!
//! EMG goes through the one front end ([`hand_dbc::emg_front::EmgFront`]: E2E, reassembly,
//! µV) and the one signal chain ([`decoder::dsp::Chain`]); a channel's amplitude is the chain's
//! RMS feature over its 200 ms window, the same number handd computes. What only the daemon
//! knows is taken from the frames it sends, and shown only as far as they carry it:
//!
//! - HAND_HEARTBEAT: state, faults in force (its fault mask, decoded with handd's own
//!   [`driver::FaultSet`]), the model id (no model kind or path: the bus does not carry them);
//! - HAND_DIAG: each tick's latency (p50/p99 over the last 200 ticks here), deadline misses
//!   and lost samples (modulo 256 on the bus: counted here as the sum of the steps since the
//!   monitor started), and each finger's label (quantised to 0.05 for display);
//! - FINGER_SETPOINT: commanded force and velocity, ACTIVE or not (a DISABLED setpoint counts
//!   as disabled);
//! - FINGER_STATUS: reported position and force; a controller reporting DISABLED or FAULT, or
//!   silent for 200 ms, shows its finger disabled;
//! - EMG_STATUS: lead-off and saturation masks;
//! - each CiA 402 drive's heartbeat, TPDO1 and EMCY, when handd's config names the drives
//!   ([`super::drives`]).
//!
//! E2E errors are those this monitor sees itself: EMG frames the front end drops for their CRC
//! or length, and other protected frames whose CRC is wrong. The bus load is the worst-case bits
//! of every frame seen over the last second.

use decoder::dsp::{Chain, ChainSettings, FEATURES_PER_CHANNEL};
use driver::FaultSet;
use hand_dbc::e2e::E2eProfile;
use hand_dbc::emg_front::{EmgFront, EmgFrontConfig, EmgFrontSettings, FrameVerdict};
use hand_dbc::hand::N_FINGERS;
use hand_dbc::messages::{self, FingerMode, FingerState, Message};
use hand_dbc::CanFrame;

use super::drives::BusDrives;
use super::meters::{BusLoadMeter, LatencyWindow};
use super::state::MonitorState;

/// The monitor's refresh period in source time, µs (10 Hz).
pub const SAMPLE_PERIOD_US: u64 = 100_000;
/// A finger controller silent this long shows its finger disabled, µs.
const STATUS_STALE_US: u64 = 200_000;

/// Frames in, state out (see the module docs).
#[derive(Debug, Clone)]
pub struct FrameDecoder {
    front: EmgFront,
    chain: Chain,
    load: BusLoadMeter,
    latency: LatencyWindow,
    /// HAND_DIAG's last (deadline misses, samples lost), modulo 256.
    last_diag: Option<(u8, u8)>,
    last_status_us: [Option<u64>; N_FINGERS],
    status_disabled: [bool; N_FINGERS],
    setpoint_disabled: [bool; N_FINGERS],
    crc_errors: u64,
    next_sample_us: Option<u64>,
    last_frame_us: Option<u64>,
    drives: BusDrives,
}

impl FrameDecoder {
    /// A decoder for the chain `settings` (its channel count is the EMG front end's).
    pub fn new(settings: &ChainSettings) -> Self {
        let front = EmgFrontConfig {
            channels: settings.n_channels(),
            ..EmgFrontConfig::at_rate(settings.sample_rate_hz())
        };
        let front = EmgFrontSettings::try_new(front)
            .expect("a validated chain has 1..=12 channels, as the bus carries");
        Self {
            front: EmgFront::new(&front),
            chain: Chain::new(settings),
            load: BusLoadMeter::default(),
            latency: LatencyWindow::default(),
            last_diag: None,
            last_status_us: [None; N_FINGERS],
            status_disabled: [false; N_FINGERS],
            setpoint_disabled: [false; N_FINGERS],
            crc_errors: 0,
            next_sample_us: None,
            last_frame_us: None,
            drives: BusDrives::default(),
        }
    }

    /// Follows these CiA 402 drives' frames too (handd's config says which node is which
    /// finger).
    pub fn set_drives(&mut self, drives: BusDrives) {
        self.drives = drives;
    }

    /// Takes one frame received at `t_us`. Every 100 ms of frame time the state is refreshed
    /// (amplitudes, counters, one plot point) before the frame is taken.
    pub fn on_frame(&mut self, st: &mut MonitorState, frame: &CanFrame, t_us: u64) {
        let next = *self.next_sample_us.get_or_insert(t_us + SAMPLE_PERIOD_US);
        if t_us >= next {
            self.refresh(st, next);
            // Skip whole periods of silence rather than plotting each.
            self.next_sample_us =
                Some(next + SAMPLE_PERIOD_US * ((t_us - next) / SAMPLE_PERIOD_US + 1));
        }
        self.last_frame_us = Some(t_us);
        self.load.add(t_us, frame.data().len());
        let chain = &mut self.chain;
        let verdict = self.front.on_frame(frame, t_us, &mut |s| {
            chain.push(s.uv());
        });
        if verdict == FrameVerdict::NotEmg && !frame.is_extended() && !frame.is_remote() {
            self.on_message(st, frame, t_us);
        }
    }

    /// Receive time of the newest frame taken, µs.
    pub fn last_frame_us(&self) -> Option<u64> {
        self.last_frame_us
    }

    /// Refreshes the state at `t_us` (also at the end of a log, for its last values).
    pub fn refresh(&mut self, st: &mut MonitorState, t_us: u64) {
        st.t_us = t_us;
        let features = self.chain.features();
        for (c, v) in st.channels.iter_mut().enumerate() {
            v.rms_uv = features
                .get(c * FEATURES_PER_CHANNEL)
                .copied()
                .unwrap_or(0.0);
        }
        for f in 0..N_FINGERS {
            let stale =
                self.last_status_us[f].is_none_or(|s| t_us.saturating_sub(s) > STATUS_STALE_US);
            st.fingers[f].disabled = stale || self.status_disabled[f] || self.setpoint_disabled[f];
        }
        let d = &mut st.daemon;
        if let Some((p50, p99)) = self.latency.percentiles() {
            d.latency_p50_us = Some(p50);
            d.latency_p99_us = Some(p99);
        }
        d.e2e_errors = self.front.counters().e2e_errors + self.crc_errors;
        d.bus_load = self.load.load(t_us);
        if !self.drives.is_empty() {
            st.drives = self.drives.lines(t_us);
        }
        st.update_noisy();
        st.sample_history();
    }

    /// A non-EMG frame.
    fn on_message(&mut self, st: &mut MonitorState, frame: &CanFrame, t_us: u64) {
        let (id, data) = (frame.raw_id(), frame.data());
        if self.drives.on_frame(id, data, t_us) {
            return;
        }
        if let Some(profile) = profile_of(id) {
            if data.is_empty() || profile.crc(data) != data[0] {
                self.crc_errors += 1;
                return;
            }
        }
        let Ok(msg) = messages::decode(id, data) else {
            return;
        };
        match msg {
            Message::EmgStatus(m) => {
                for (c, v) in st.channels.iter_mut().enumerate() {
                    v.lead_off = m.lead_off_mask() & (1 << c) != 0;
                    v.saturated = m.saturation_mask() & (1 << c) != 0;
                }
            }
            Message::FingerSetpoint(m) => {
                let f = &mut st.fingers[m.instance()];
                f.force_n = m.force();
                f.velocity_rad_s = m.velocity();
                f.active = m.mode() == FingerMode::Active;
                self.setpoint_disabled[m.instance()] = m.mode() == FingerMode::Disabled;
            }
            Message::FingerStatus(m) => {
                let f = &mut st.fingers[m.instance()];
                f.position_rad = m.position();
                f.reported_force_n = m.force();
                self.last_status_us[m.instance()] = Some(t_us);
                self.status_disabled[m.instance()] =
                    matches!(m.state(), FingerState::Disabled | FingerState::Fault);
            }
            Message::HandHeartbeat(m) => {
                let d = &mut st.daemon;
                d.state = Some(m.state().dbc_name().to_owned());
                d.faults = FaultSet(m.fault_mask())
                    .iter()
                    .map(|f| f.name().to_owned())
                    .collect();
                d.model_id = (m.model_id() != 0).then(|| format!("{:08x}", m.model_id()));
            }
            Message::HandDiag(m) => self.on_diag(st, &m),
            _ => {}
        }
    }

    fn on_diag(&mut self, st: &mut MonitorState, m: &messages::HandDiag) {
        self.latency.add(u64::from(m.tick_latency()));
        let now = (m.deadline_misses(), m.emg_samples_lost());
        if let Some((misses, lost)) = self.last_diag {
            st.daemon.deadline_misses += u64::from(now.0.wrapping_sub(misses));
            st.daemon.samples_lost += u64::from(now.1.wrapping_sub(lost));
        }
        self.last_diag = Some(now);
        let labels = [m.label0(), m.label1(), m.label2(), m.label3(), m.label4()];
        for (f, l) in st.fingers.iter_mut().zip(labels) {
            f.label = Some(l);
        }
    }
}

/// The E2E profile of a protected non-EMG message of hand.dbc, by id.
fn profile_of(id: u32) -> Option<E2eProfile> {
    use messages::{EmgStatus, FingerSetpoint, FingerStatus, HandEstop, HandHeartbeat};
    match id {
        HandEstop::ID => Some(HandEstop::E2E),
        EmgStatus::ID => Some(EmgStatus::E2E),
        HandHeartbeat::ID => Some(HandHeartbeat::E2E),
        _ => FingerSetpoint::instance_of(id)
            .map(|i| FingerSetpoint::E2E[i])
            .or_else(|| FingerStatus::instance_of(id).map(|i| FingerStatus::E2E[i])),
    }
}
