//! The receive side: every frame in with its receive time. EMG sample frames go through the
//! shared front end ([`EmgFront`]) into the signal chain; finger status feeds the watchdog,
//! the amplifier's status the signal quality, an E-stop latches SAFE.

use decoder::dsp::{Chain, ChainSettings};
use hand_dbc::e2e::{E2eChecker, E2eProfile, E2eStatus};
use hand_dbc::emg_front::{EmgFront, EmgFrontConfig, EmgFrontSettings, FrameVerdict};
use hand_dbc::messages::{
    self, AmpSampleRate, AmpState, EmgStatus, EstopRequest, FingerState, FingerStatus, HandEstop,
    Message,
};
use hand_dbc::CanFrame;

use super::Engine;
use crate::conditioner::Feedback;
use crate::safety::Fault;
use crate::units::N_FINGERS;

/// FINGER_STATUS fault bit 3 (hand.dbc): the controller braked by itself, setpoint timeout.
const STATUS_SETPOINT_TIMEOUT: u8 = 1 << 3;
/// FINGER_STATUS fault bit 5 (hand.dbc): the joint is at a stop and the command pushes into it.
const STATUS_JOINT_LIMIT: u8 = 1 << 5;

/// The EMG stream: the front end, the signal chain it feeds and what the tick needs to know
/// about the newest samples.
#[derive(Clone)]
pub(super) struct EmgIn {
    front: EmgFront,
    pub(super) chain: Chain,
    /// Receive time of the newest EMG frame accepted.
    pub(super) last_emg_us: u64,
    /// Receive time of the frame that completed the newest sample, and its bus counter.
    pub(super) newest_rx_us: Option<u64>,
    pub(super) newest_counter: u8,
    /// Sample index (since start) of the last gap over the limit.
    last_gap_at: Option<u64>,
    /// Samples pushed into the chain since start.
    pub(super) samples_in: u64,
    /// The front end's railed count at the last tick.
    railed_at_tick: u64,
}

impl EmgIn {
    /// The stream for `chain`, bridging gaps up to `max_gap_us`, silent since `now_us`.
    /// Panics if the front end refuses the settings: the config layer keeps `max_gap_us` in
    /// range and the engine checks the channel count first.
    pub(super) fn new(chain: &ChainSettings, max_gap_us: u64, now_us: u64) -> Self {
        let front = EmgFrontSettings::try_new(EmgFrontConfig {
            max_gap_us,
            channels: chain.n_channels(),
            ..EmgFrontConfig::at_rate(chain.sample_rate_hz())
        })
        .expect("the config layer keeps max_gap_us within the front end's range");
        Self {
            front: EmgFront::new(&front),
            chain: Chain::new(chain),
            last_emg_us: now_us,
            newest_rx_us: None,
            newest_counter: 0,
            last_gap_at: None,
            samples_in: 0,
            railed_at_tick: 0,
        }
    }

    /// One frame through the front end; its samples go into the chain.
    fn on_frame(&mut self, frame: &CanFrame, rx_us: u64) -> FrameVerdict {
        let chain = &mut self.chain;
        let samples_in = &mut self.samples_in;
        let last_gap_at = &mut self.last_gap_at;
        let newest_rx_us = &mut self.newest_rx_us;
        let newest_counter = &mut self.newest_counter;
        let verdict = self.front.on_frame(frame, rx_us, &mut |s| {
            if s.after_gap {
                *last_gap_at = Some(*samples_in);
            }
            *samples_in += 1;
            chain.push(s.uv());
            *newest_rx_us = Some(s.received_us);
            *newest_counter = s.counter;
        });
        if verdict == FrameVerdict::Accepted {
            self.last_emg_us = rx_us;
        }
        verdict
    }

    /// Samples lost and bridged since start.
    pub(super) fn samples_lost(&self) -> u64 {
        self.front.counters().samples_lost
    }

    /// Railed channel values since the last call.
    pub(super) fn take_railed(&mut self) -> u64 {
        let railed = self.front.counters().railed;
        let since = railed - self.railed_at_tick;
        self.railed_at_tick = railed;
        since
    }

    /// Whether the window ending at the newest sample may drive the fingers at `now_us`: full,
    /// no gap inside, fresh, the stream still flowing, no bad sample in it.
    pub(super) fn window_valid(&self, now_us: u64, tick_us: u64, max_gap_us: u64) -> bool {
        let window_len = self.chain.settings().window_len() as u64;
        let full = self.chain.samples_seen() >= window_len;
        let gap_left = self
            .last_gap_at
            .is_none_or(|at| self.samples_in - at >= window_len);
        let fresh = self
            .newest_rx_us
            .is_some_and(|t| now_us.saturating_sub(t) <= 2 * tick_us);
        // Silence longer than the gap limit is a gap in progress: the window will not be
        // complete, so stop now rather than wait for the silence timeout.
        let flowing = now_us.saturating_sub(self.last_emg_us) <= max_gap_us;
        full && gap_left && fresh && flowing && !self.chain.faults().any_in_window()
    }
}

/// The E2E checkers of the other streams the engine reads, and what they last said.
#[derive(Clone)]
pub(super) struct Inputs {
    status: [E2eChecker; N_FINGERS],
    estop: E2eChecker,
    amp_status: E2eChecker,
    /// The amplifier reports lead-off or saturation, or is in FAULT.
    pub(super) amp_reports_bad: bool,
    /// Force each finger controller last reported, N.
    pub(super) reported_force: [f64; N_FINGERS],
    /// Joint angle each finger controller last reported, rad.
    pub(super) reported_position: [f64; N_FINGERS],
    /// What each finger controller last reported that the control law uses.
    pub(super) feedback: [Feedback; N_FINGERS],
    /// The amplifier's last lead-off and saturation masks (bit c = channel c).
    pub(super) amp_masks: (u16, u16),
    /// Receive time of the last valid EMG_STATUS (the engine's start before the first one).
    pub(super) last_amp_status_us: u64,
    /// What the amplifier's last status says is wrong with its samples, if anything.
    pub(super) amp_problem: Option<AmpProblem>,
}

/// EMG_STATUS at 10 Hz: three missed in a row (300 ms) is a silence, and the lead-off and
/// saturation flags of the last one can no longer be trusted.
pub const AMP_STATUS_SILENCE_US: u64 = 300_000;

/// EMG_STATUS fault bits that make the samples unusable (hand.dbc): ADC, supply,
/// over-temperature, clock. Bit 4 (transmit overrun) is not one: the samples it dropped are
/// counted and bridged or faulted by the front end like any other loss.
const AMP_FAULT_BITS: u8 = 0x0F;

/// Why the amplifier's own status says its samples cannot drive the hand.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AmpProblem {
    /// Not RUNNING (samples are only meaningful while RUNNING, hand.dbc).
    State(AmpState),
    /// Sampling at another rate than the chain runs, Hz.
    Rate {
        /// The amplifier's rate.
        amplifier_hz: u32,
        /// The chain's.
        chain_hz: u32,
    },
    /// A fault bit (ADC, supply, over-temperature, clock).
    Fault(u8),
    /// No EMG_STATUS for [`AMP_STATUS_SILENCE_US`].
    Silent,
}

impl std::fmt::Display for AmpProblem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            AmpProblem::State(s) => write!(f, "the amplifier is {s:?}, not RUNNING"),
            AmpProblem::Rate {
                amplifier_hz,
                chain_hz,
            } => write!(
                f,
                "the amplifier samples at {amplifier_hz} Hz, the signal chain runs at {chain_hz} Hz"
            ),
            AmpProblem::Fault(bits) => write!(f, "the amplifier reports fault bits {bits:#04x}"),
            AmpProblem::Silent => {
                write!(f, "no EMG_STATUS for {} ms", AMP_STATUS_SILENCE_US / 1000)
            }
        }
    }
}

/// The problem an EMG_STATUS reports for a chain sampling at `chain_hz`, if any.
pub fn amp_problem(st: &EmgStatus, chain_hz: u32) -> Option<AmpProblem> {
    let amplifier_hz = match st.sample_rate() {
        AmpSampleRate::Sr500Hz => 500,
        AmpSampleRate::Sr1000Hz => 1000,
        AmpSampleRate::Sr2000Hz => 2000,
    };
    if st.state() != AmpState::Running {
        Some(AmpProblem::State(st.state()))
    } else if amplifier_hz != chain_hz {
        Some(AmpProblem::Rate {
            amplifier_hz,
            chain_hz,
        })
    } else if st.faults() & AMP_FAULT_BITS != 0 {
        Some(AmpProblem::Fault(st.faults() & AMP_FAULT_BITS))
    } else {
        None
    }
}

fn checker(profile: E2eProfile, max_delta: u16) -> E2eChecker {
    E2eChecker::try_new(profile, max_delta).expect("hand.dbc's profiles accept these deltas")
}

impl Inputs {
    pub(super) fn new(now_us: u64) -> Self {
        Self {
            status: FingerStatus::E2E.map(|p| checker(p, 3)),
            estop: checker(HandEstop::E2E, 15),
            amp_status: checker(EmgStatus::E2E, 3),
            amp_reports_bad: false,
            reported_force: [0.0; N_FINGERS],
            reported_position: [0.0; N_FINGERS],
            feedback: [Feedback::default(); N_FINGERS],
            amp_masks: (0, 0),
            last_amp_status_us: now_us,
            amp_problem: None,
        }
    }
}

impl Engine {
    /// One received frame with its receive time.
    pub fn on_frame(&mut self, frame: &CanFrame, rx_us: u64) {
        if frame.is_remote() || frame.is_extended() {
            self.counters.bad_frames += 1;
            return;
        }
        match self.emg.on_frame(frame, rx_us) {
            FrameVerdict::NotEmg => {}
            FrameVerdict::Accepted => {
                self.counters.samples_lost = self.emg.samples_lost();
                return;
            }
            FrameVerdict::Repeated => return,
            FrameVerdict::E2eError | FrameVerdict::Undecodable => {
                self.e2e_error(rx_us);
                return;
            }
        }
        let id = frame.raw_id();
        match messages::decode(id, frame.data()) {
            Ok(msg) => self.on_message(&msg, frame.data(), rx_us),
            // A known id with a bad payload may be a corrupted safety frame: count it as an
            // E2E error for the streams we check, as a bad frame otherwise.
            Err(_) if id == HandEstop::ID => self.e2e_error(rx_us),
            Err(_) => self.counters.bad_frames += 1,
        }
    }

    /// A decoded frame other than EMG samples.
    fn on_message(&mut self, msg: &Message, data: &[u8], rx_us: u64) {
        match msg {
            Message::FingerStatus(s) => {
                let f = s.instance();
                match self.inputs.status[f].check(Some(data)) {
                    E2eStatus::Ok => {
                        self.watch.heard(f, rx_us);
                        self.inputs.reported_force[f] = s.force();
                        self.inputs.reported_position[f] = s.position();
                        // It retired our epoch: only a new one's SAFE_STOP moves it again.
                        let self_braked = s.state() == FingerState::Braked
                            && s.faults() & STATUS_SETPOINT_TIMEOUT != 0;
                        if self.epochs.on_status(f, self_braked) {
                            // That finger alone: the others did not retire their epochs.
                            self.epochs.next_for(f);
                        }
                        self.inputs.feedback[f] = Feedback {
                            at_joint_limit: s.faults() & STATUS_JOINT_LIMIT != 0,
                        };
                    }
                    E2eStatus::Repeated => {}
                    _ => self.counters.e2e_errors += 1,
                }
            }
            Message::EmgStatus(st) => match self.inputs.amp_status.check(Some(data)) {
                E2eStatus::Ok | E2eStatus::WrongSequence => {
                    self.inputs.amp_masks = (st.lead_off_mask(), st.saturation_mask());
                    self.inputs.last_amp_status_us = rx_us;
                    self.inputs.amp_problem =
                        amp_problem(st, self.emg.chain.settings().sample_rate_hz() as u32);
                    self.inputs.amp_reports_bad = st.lead_off_mask() != 0
                        || st.saturation_mask() != 0
                        || self.inputs.amp_problem.is_some();
                }
                E2eStatus::Error => self.e2e_error(rx_us),
                _ => {}
            },
            Message::HandEstop(e) => match self.inputs.estop.check(Some(data)) {
                E2eStatus::Error => self.e2e_error(rx_us),
                _ if e.request() == EstopRequest::Stop => {
                    self.counters.estops += 1;
                    let t = self.safety.raise(rx_us, Fault::EStop);
                    self.note(t);
                }
                _ => {}
            },
            // Our own messages echoed by another sender, and status frames we do not use.
            _ => {}
        }
    }

    fn e2e_error(&mut self, at_us: u64) {
        self.counters.e2e_errors += 1;
        let t = self.safety.raise(at_us, Fault::E2eError);
        self.note(t);
    }
}
