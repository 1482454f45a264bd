//! The receive side: every frame in with its receive time. EMG sample frames go through the
//! shared front end ([`EmgFront`]) into the signal chain; finger status feeds the watchdog,
//! the amplifier's status the signal quality, an E-stop latches SAFE.
//!
//! Finger status is checked as AUTOSAR E2E Profile 1 means it
//! ([`E2eCheckConfig::profile1`]): after a counter jump or a repeat, two in-sequence frames
//! pass before a status is used again (not heard by the watchdog, its force, position and
//! flags not read). HAND_ESTOP keeps resynchronising at once (its senders interleave counters,
//! and a stop must never wait); EMG_STATUS too (a lead-off report must not wait either).
//!
//! Two masters on the bus are a latched fault, [`Fault::SecondMaster`]:
//! - any FINGER_SETPOINT handd receives: SocketCAN does not loop a socket's own frames back to
//!   it (handd does not set `recv_own_msgs`, and installs no receive filter, so every id
//!   reaches the engine), so the frame came from another sender;
//! - a controller's FINGER_STATUS fault bit 6 (it ignored a valid setpoint of another epoch)
//!   more than [`STALE_EPOCH_GRACE_US`] after handd first heard that finger in its current
//!   epoch: handd's own frames of an older epoch drain from the queues within milliseconds of
//!   the new epoch's SAFE_STOP, so a later one is somebody else's.
//!
//! A controller's bit 4 (a setpoint failed its E2E check since its previous status) is what
//! a second sender interleaving with handd, or a damaged bus, produces: one report is noted
//! (a bus recovery legitimately gives one per finger: handd's counter jumped), and
//! [`SETPOINT_E2E_LATCH`] reports from one finger within [`SETPOINT_E2E_WINDOW_US`] latch
//! [`Fault::RepeatedE2e`].

use decoder::dsp::{Chain, ChainSettings};
use hand_dbc::e2e::{E2eCheckConfig, E2eChecker, E2eProfile, E2eStatus};
use hand_dbc::emg_front::{EmgFront, EmgFrontConfig, EmgFrontSettings, FrameVerdict};
use hand_dbc::messages::{
    self, AmpSampleRate, AmpState, EmgStatus, EstopRequest, FingerSetpoint, FingerState,
    FingerStatus, HandEstop, Message,
};
use hand_dbc::CanFrame;

use super::Engine;
use crate::conditioner::Feedback;
use crate::safety::Fault;
use crate::units::N_FINGERS;

/// FINGER_STATUS fault bit 3 (hand.dbc): the controller braked by itself, setpoint timeout.
const STATUS_SETPOINT_TIMEOUT: u8 = 1 << 3;
/// FINGER_STATUS fault bit 4 (hand.dbc): a setpoint failed the controller's E2E check since
/// its previous status.
const STATUS_SETPOINT_E2E: u8 = 1 << 4;
/// FINGER_STATUS fault bit 5 (hand.dbc): the joint is at a stop and the command pushes into it.
const STATUS_JOINT_LIMIT: u8 = 1 << 5;
/// FINGER_STATUS fault bit 6 (hand.dbc): the controller ignored a valid setpoint of a stale or
/// not yet opened epoch since its previous status.
const STATUS_STALE_EPOCH: u8 = 1 << 6;

/// How long after handd first heard a finger in its current epoch a stale-epoch report (bit 6)
/// may still be handd's own older frames, µs. Those leave the kernel's and the controller's
/// queues before the new epoch's SAFE_STOP (FIFO per id), within a few ms at 1 Mbit/s; 200 ms
/// also covers the tick that sends the SAFE_STOP and the status period (20 ms).
pub const STALE_EPOCH_GRACE_US: u64 = 200_000;
/// Status reports of bit 4 from one finger within [`SETPOINT_E2E_WINDOW_US`] that latch
/// [`Fault::RepeatedE2e`].
pub const SETPOINT_E2E_LATCH: usize = 3;
/// See [`SETPOINT_E2E_LATCH`], µs.
pub const SETPOINT_E2E_WINDOW_US: u64 = 1_000_000;

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
    /// no gap inside, fresh, the stream still flowing, no bad sample in it. Otherwise the
    /// first rule it breaks, in that order.
    pub(super) fn window_check(
        &self,
        now_us: u64,
        tick_us: u64,
        max_gap_us: u64,
    ) -> Result<(), WindowProblem> {
        let window_len = self.chain.settings().window_len() as u64;
        if self.chain.samples_seen() < window_len {
            return Err(WindowProblem::Filling);
        }
        if self
            .last_gap_at
            .is_some_and(|at| self.samples_in - at < window_len)
        {
            return Err(WindowProblem::GapInWindow);
        }
        let age_us = self
            .newest_rx_us
            .map_or(u64::MAX, |t| now_us.saturating_sub(t));
        if age_us > 2 * tick_us {
            return Err(WindowProblem::Stale { age_us });
        }
        // Silence longer than the gap limit is a gap in progress: the window will not be
        // complete, so stop now rather than wait for the silence timeout.
        let silent_us = now_us.saturating_sub(self.last_emg_us);
        if silent_us > max_gap_us {
            return Err(WindowProblem::Silent { silent_us });
        }
        if self.chain.faults().any_in_window() {
            return Err(WindowProblem::BadSample);
        }
        Ok(())
    }
}

/// Why a window may not drive the fingers (the `invalid_window` fault's reason), for the log
/// and `handctl status`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WindowProblem {
    /// Fewer samples than the window since start or since the stream broke.
    Filling,
    /// The stream broke (samples lost, or a silence the counter cannot vouch for) within the
    /// window.
    GapInWindow,
    /// The newest sample was received this long before the tick's deadline, µs.
    Stale {
        /// µs.
        age_us: u64,
    },
    /// No EMG frame for this long before the tick's deadline, over the gap limit, µs.
    Silent {
        /// µs.
        silent_us: u64,
    },
    /// A sample the chain could not use (non-finite) is in the window.
    BadSample,
}

impl core::fmt::Display for WindowProblem {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Filling => f.write_str("the window is filling"),
            Self::GapInWindow => f.write_str("the EMG stream broke within the window"),
            Self::Stale { age_us } if *age_us == u64::MAX => f.write_str("no EMG sample yet"),
            Self::Stale { age_us } => write!(
                f,
                "the newest EMG sample is {:.1} ms old",
                *age_us as f64 * 1e-3
            ),
            Self::Silent { silent_us } => {
                write!(f, "no EMG frame for {:.1} ms", *silent_us as f64 * 1e-3)
            }
            Self::BadSample => f.write_str("a non-finite sample in the window"),
        }
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
    /// Per finger: the epoch count ([`super::epoch::Epochs::begun`]) handd last heard the
    /// finger in, and when it first heard it in that epoch.
    epoch_heard: [(u64, u64); N_FINGERS],
    /// Per finger: when its last `SETPOINT_E2E_LATCH - 1` bit-4 reports arrived, oldest first.
    setpoint_e2e_at: [[Option<u64>; SETPOINT_E2E_LATCH - 1]; N_FINGERS],
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

fn checker(profile: E2eProfile, config: E2eCheckConfig) -> E2eChecker {
    E2eChecker::with_config(profile, config).expect("hand.dbc's profiles accept these deltas")
}

impl Inputs {
    pub(super) fn new(now_us: u64) -> Self {
        Self {
            status: FingerStatus::E2E.map(|p| checker(p, E2eCheckConfig::profile1(3))),
            estop: checker(HandEstop::E2E, E2eCheckConfig::resync_at_once(15)),
            amp_status: checker(EmgStatus::E2E, E2eCheckConfig::resync_at_once(3)),
            amp_reports_bad: false,
            reported_force: [0.0; N_FINGERS],
            reported_position: [0.0; N_FINGERS],
            feedback: [Feedback::default(); N_FINGERS],
            amp_masks: (0, 0),
            last_amp_status_us: now_us,
            amp_problem: None,
            epoch_heard: [(0, 0); N_FINGERS],
            setpoint_e2e_at: [[None; SETPOINT_E2E_LATCH - 1]; N_FINGERS],
        }
    }

    /// Finger `f` was heard at `rx_us` in handd's epoch number `begun`: how long handd has
    /// heard it in that epoch.
    fn heard_in_epoch(&mut self, f: usize, begun: u64, rx_us: u64) -> u64 {
        if self.epoch_heard[f].0 != begun {
            self.epoch_heard[f] = (begun, rx_us);
        }
        rx_us.saturating_sub(self.epoch_heard[f].1)
    }

    /// Finger `f` reported a setpoint E2E error at `rx_us`: whether that makes
    /// [`SETPOINT_E2E_LATCH`] within [`SETPOINT_E2E_WINDOW_US`].
    fn setpoint_e2e_report(&mut self, f: usize, rx_us: u64) -> bool {
        let times = &mut self.setpoint_e2e_at[f];
        let repeated = times[0].is_some_and(|t| rx_us.saturating_sub(t) <= SETPOINT_E2E_WINDOW_US);
        times.rotate_left(1);
        times[SETPOINT_E2E_LATCH - 2] = Some(rx_us);
        if repeated {
            *times = [None; SETPOINT_E2E_LATCH - 1];
        }
        repeated
    }
}

impl Engine {
    /// One received frame with its receive time.
    pub fn on_frame(&mut self, frame: &CanFrame, rx_us: u64) {
        self.record(crate::tape::Entry::Frame {
            rx_us,
            frame: *frame,
        });
        if frame.is_remote() || frame.is_extended() {
            self.counters.bad_frames += 1;
            return;
        }
        if let Some(d) = self.drives.as_mut().filter(|d| d.claims(frame)) {
            d.on_frame(frame, rx_us);
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
        if FingerSetpoint::IDS.contains(&id) {
            // Never our own (no loopback): another node is driving the fingers.
            let t = self.safety.raise(rx_us, Fault::SecondMaster);
            self.note(t);
            return;
        }
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
            // A CiA 402 finger's state comes from its drive, not from hand.dbc.
            Message::FingerStatus(s)
                if self.drives.as_ref().is_some_and(|d| d.has(s.instance())) => {}
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
                        self.on_setpoint_reports(f, s.faults(), rx_us);
                    }
                    // In sequence, but resynchronising after a jump or a repeat: not used.
                    E2eStatus::Sync => {}
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

    /// What finger `f`'s controller says about the setpoints it received (status bits 4 and
    /// 6): see the module docs.
    fn on_setpoint_reports(&mut self, f: usize, faults: u8, rx_us: u64) {
        let in_epoch_us = self.inputs.heard_in_epoch(f, self.epochs.begun(f), rx_us);
        if faults & STATUS_STALE_EPOCH != 0 && in_epoch_us > STALE_EPOCH_GRACE_US {
            let t = self.safety.raise(rx_us, Fault::SecondMaster);
            self.note(t);
        }
        if faults & STATUS_SETPOINT_E2E != 0 && self.inputs.setpoint_e2e_report(f, rx_us) {
            let t = self.safety.raise(rx_us, Fault::RepeatedE2e);
            self.note(t);
        }
    }

    fn e2e_error(&mut self, at_us: u64) {
        self.counters.e2e_errors += 1;
        let t = self.safety.raise(at_us, Fault::E2eError);
        self.note(t);
    }
}

#[cfg(test)]
mod tests {
    use decoder::dsp::ChainConfig;
    use hand_dbc::e2e::E2eProtector;

    use super::*;
    use crate::engine::EngineSettings;

    fn engine() -> Engine {
        let chain = ChainConfig::default().validate().expect("chain");
        let mut e = Engine::without_model(&chain, EngineSettings::default(), 0);
        e.validated(0);
        e
    }

    /// FINGER_STATUS of finger `f`, ACTIVE, reporting `force` and `faults`, next counter of
    /// `tx`.
    fn status(tx: &mut E2eProtector, f: usize, force: f64, faults: u8) -> CanFrame {
        let s = FingerStatus::new(f, FingerState::Active, 0.1, 0.0, force, faults).expect("range");
        tx.protect_message(&s).expect("own profile")
    }

    #[test]
    fn a_status_after_a_counter_jump_is_used_only_after_two_in_sequence() {
        let mut e = engine();
        let mut tx = E2eProtector::new(FingerStatus::E2E[2]);
        e.on_frame(&status(&mut tx, 2, 1.0, 0), 20_000);
        assert_eq!(e.reported_force()[2], 1.0);
        // Eight frames lost (more than the 3 allowed): a wrong sequence, then two Sync.
        for _ in 0..8 {
            status(&mut tx, 2, 0.0, 0);
        }
        for (k, force) in [2.0, 3.0, 4.0].into_iter().enumerate() {
            e.on_frame(&status(&mut tx, 2, force, 0), 40_000 + 20_000 * k as u64);
            assert_eq!(
                e.reported_force()[2],
                1.0,
                "frame {k} after the jump was used"
            );
        }
        e.on_frame(&status(&mut tx, 2, 5.0, 0), 100_000);
        assert_eq!(e.reported_force()[2], 5.0);
    }

    #[test]
    fn a_setpoint_frame_received_is_a_latched_second_master() {
        let mut e = engine();
        assert!(!e.faults().contains(Fault::SecondMaster));
        let sp =
            FingerSetpoint::new(0, messages::FingerMode::SafeStop, 0.0, 0.0, 7).expect("range");
        let frame = E2eProtector::new(FingerSetpoint::E2E[0])
            .protect_message(&sp)
            .expect("own profile");
        e.on_frame(&frame, 1_000);
        assert!(e.faults().contains(Fault::SecondMaster));
        assert!(Fault::SecondMaster.is_latched());
        assert_eq!(Fault::SecondMaster.name(), "second_master");
        assert_eq!(Fault::SecondMaster.bit(), 1 << 14);
        // Whatever the frame holds: a wrong length or CRC does not make it handd's own.
        let mut e = engine();
        let short = CanFrame::new_standard(FingerSetpoint::IDS[4] as u16, &[0; 3]).expect("frame");
        e.on_frame(&short, 2_000);
        assert!(e.faults().contains(Fault::SecondMaster));
    }

    #[test]
    fn a_stale_epoch_report_long_into_the_epoch_is_a_second_master() {
        let mut e = engine();
        let mut tx = E2eProtector::new(FingerStatus::E2E[1]);
        // Heard first at 20 ms; a stale-epoch report within the grace is handd's own queue.
        e.on_frame(&status(&mut tx, 1, 0.0, 0), 20_000);
        e.on_frame(&status(&mut tx, 1, 0.0, STATUS_STALE_EPOCH), 40_000);
        assert!(!e.faults().contains(Fault::SecondMaster));
        let late = 20_000 + STALE_EPOCH_GRACE_US + 20_000;
        e.on_frame(&status(&mut tx, 1, 0.0, 0), late - 20_000);
        e.on_frame(&status(&mut tx, 1, 0.0, STATUS_STALE_EPOCH), late);
        assert!(e.faults().contains(Fault::SecondMaster));
        // A new epoch restarts the grace.
        let mut e = engine();
        let mut tx = E2eProtector::new(FingerStatus::E2E[1]);
        e.on_frame(&status(&mut tx, 1, 0.0, 0), 20_000);
        e.new_epoch();
        e.on_frame(&status(&mut tx, 1, 0.0, 0), late - 20_000);
        e.on_frame(&status(&mut tx, 1, 0.0, STATUS_STALE_EPOCH), late);
        assert!(!e.faults().contains(Fault::SecondMaster));
    }

    #[test]
    fn repeated_setpoint_e2e_reports_of_one_finger_latch_repeated_e2e() {
        let mut e = engine();
        let mut tx: [E2eProtector; N_FINGERS] = FingerStatus::E2E.map(E2eProtector::new);
        // One report from every finger (a bus recovery): nothing latched.
        for (f, tx) in tx.iter_mut().enumerate() {
            e.on_frame(&status(tx, f, 0.0, STATUS_SETPOINT_E2E), 20_000);
        }
        assert!(!e.faults().contains(Fault::RepeatedE2e), "{}", e.faults());
        // A second and a third report from finger 3 within a second: latched.
        e.on_frame(&status(&mut tx[3], 3, 0.0, STATUS_SETPOINT_E2E), 400_000);
        assert!(!e.faults().contains(Fault::RepeatedE2e));
        e.on_frame(&status(&mut tx[3], 3, 0.0, 0), 420_000);
        e.on_frame(&status(&mut tx[3], 3, 0.0, STATUS_SETPOINT_E2E), 440_000);
        assert!(e.faults().contains(Fault::RepeatedE2e), "{}", e.faults());
        // Reports spread wider than the window do not latch.
        let mut e = engine();
        let mut tx = E2eProtector::new(FingerStatus::E2E[0]);
        for k in 0..6u64 {
            let t = 20_000 + k * (SETPOINT_E2E_WINDOW_US / 2 + 20_000);
            e.on_frame(&status(&mut tx, 0, 0.0, STATUS_SETPOINT_E2E), t);
        }
        assert!(!e.faults().contains(Fault::RepeatedE2e), "{}", e.faults());
    }
}
