//! The control loop's core, free of I/O: frames in, frames out, one [`Engine::tick`] every
//! 50 ms.
//!
//! Frames go in with their receive time ([`Engine::on_frame`]): EMG sample frames are checked
//! (E2E), reassembled by counter and pushed sample by sample through the signal chain; finger
//! status frames feed the per-finger watchdog; an E-stop latches SAFE. Each tick evaluates the
//! faults, runs the model on the window ending at the newest sample, conditions the labels and builds one
//! FINGER_SETPOINT per finger, plus HAND_DIAG every tick and HAND_HEARTBEAT every other tick.
//!
//! After construction nothing here allocates (a test counts), returns a `Result` on the tick
//! path or panics on any frame: every out-of-range value was excluded by validating the
//! config, so encoding a setpoint cannot fail, and if it ever did the finger gets a safe stop.

use decoder::dsp::{Chain, ChainSettings};
use decoder::model::Predictor;
use hand_dbc::e2e::{E2eChecker, E2eProtector, E2eStatus};
use hand_dbc::emg::{EmgAssembler, EmgConfig, EmgFrame, EmgSample};
use hand_dbc::messages::{
    self, AmpState, DaemonState as BusState, EmgSamplesG0, EmgSamplesG1, EmgSamplesG2, EmgStatus,
    EstopRequest, FingerMode, FingerSetpoint, FingerStatus, HandDiag, HandEstop, HandHeartbeat,
    Message,
};
use hand_dbc::CanFrame;

use crate::conditioner::{FingerConditioner, FingerGains, Setpoint};
use crate::safety::{
    DaemonState, Fault, FaultSet, FingerEvent, FingerWatch, Safety, SafetyTiming, Transition,
};
use crate::stats::Histogram;
use crate::units::N_FINGERS;

/// Raw EMG values at or beyond these are at the 12-bit ADC's rails (`[RAIL_LOW, RAIL_HIGH)` is
/// the unclipped range).
const RAIL_LOW: i16 = -2047;
const RAIL_HIGH: i16 = 2047;
/// Railed samples per tick (all channels) that make the signal unusable: a clipped channel
/// puts one per sample, so 50 ms of one clipped channel gives about 50.
const RAIL_LIMIT: u32 = 5;

/// Most frames one tick sends: five setpoints, HAND_DIAG and HAND_HEARTBEAT.
pub const MAX_TX_PER_TICK: usize = N_FINGERS + 2;

/// Timing and gains of the engine, taken from the validated config.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EngineSettings {
    /// Tick period, µs.
    pub tick_us: u64,
    /// No EMG sample frame for this long is a fault, µs.
    pub emg_silence_us: u64,
    /// A finger controller silent for this long is disabled, µs.
    pub finger_silence_us: u64,
    /// Recovery time of transient faults, µs.
    pub recovery_us: u64,
    /// A gap in the samples longer than this makes the window invalid, µs.
    pub max_gap_us: u64,
    /// A tick starting later than its deadline plus this is a deadline miss, µs.
    pub deadline_slack_us: u64,
    /// Per-finger gains.
    pub gains: [FingerGains; N_FINGERS],
    /// Model identity for HAND_HEARTBEAT.
    pub model_id: u32,
}

impl Default for EngineSettings {
    fn default() -> Self {
        Self {
            tick_us: 50_000,
            emg_silence_us: 100_000,
            finger_silence_us: 100_000,
            recovery_us: 500_000,
            max_gap_us: 20_000,
            deadline_slack_us: 5_000,
            gains: [FingerGains::default(); N_FINGERS],
            model_id: 0,
        }
    }
}

/// Counters since start, for HAND_DIAG and `handctl status`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Counters {
    /// Ticks run.
    pub ticks: u64,
    /// Ticks that started later than their deadline plus the configured slack.
    pub deadline_misses: u64,
    /// EMG samples lost and bridged.
    pub samples_lost: u64,
    /// Frames with an unknown id, a wrong length or values out of range.
    pub bad_frames: u64,
    /// Frames that failed their E2E check (CRC or counter).
    pub e2e_errors: u64,
    /// E-stop frames received.
    pub estops: u64,
}

/// Requests from technicians, applied at the next tick.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Command {
    /// New gains for one finger.
    SetGains(usize, FingerGains),
    /// Clear latched faults.
    Arm,
    /// Go to SAFE until armed.
    Stop,
}

/// The engine. See the module docs. Cloning it forks the whole state (a replay tries
/// alternatives on clones).
#[derive(Clone)]
pub struct Engine {
    settings: EngineSettings,
    chain: Chain,
    predictor: Predictor,
    sample: Vec<f64>,
    assembler: EmgAssembler,
    emg_checkers: [E2eChecker; 3],
    status_checkers: [E2eChecker; N_FINGERS],
    estop_checker: E2eChecker,
    amp_status_checker: E2eChecker,
    /// Samples at the ADC rail since the last tick.
    railed: u32,
    /// The amplifier reports lead-off or saturation, or is in FAULT.
    amp_reports_bad: bool,
    safety: Safety,
    watch: FingerWatch<N_FINGERS>,
    conditioners: [FingerConditioner; N_FINGERS],
    setpoint_tx: [E2eProtector; N_FINGERS],
    heartbeat_tx: E2eProtector,
    last_emg_us: u64,
    /// Receive time of the frame that completed the newest sample, and its bus counter.
    newest_rx_us: Option<u64>,
    newest_counter: u8,
    /// The newest sample counter of the last tick written, for HAND_DIAG.
    last_newest_counter: u8,
    /// Samples in (`samples_in`) when the model last ran.
    samples_used: u64,
    /// Sample index (since start) of the last gap over `max_gap_us`.
    last_gap_at: Option<u64>,
    samples_in: u64,
    labels: [f64; N_FINGERS],
    setpoints: [Setpoint; N_FINGERS],
    reported_force: [f64; N_FINGERS],
    counters: Counters,
    latency: Histogram,
    compute: Histogram,
    lateness: Histogram,
    last_latency_us: u64,
    tx: [CanFrame; MAX_TX_PER_TICK],
    tx_len: usize,
    transitions: [Option<Transition>; 8],
    finger_events: [Option<FingerEvent>; N_FINGERS],
}

fn checker(profile: hand_dbc::e2e::E2eProfile, max_delta: u16) -> E2eChecker {
    E2eChecker::try_new(profile, max_delta).expect("hand.dbc's profiles accept these deltas")
}

impl Engine {
    /// An engine in BOOT for the chain `settings` and a model's `predictor`, at time `now_us`.
    /// Panics if the predictor does not take the chain's feature count: the daemon checks the
    /// model against the chain before it gets here.
    pub fn new(
        chain: &ChainSettings,
        predictor: Predictor,
        settings: EngineSettings,
        now_us: u64,
    ) -> Self {
        assert_eq!(
            predictor.n_inputs(),
            chain.n_features(),
            "model inputs must equal the chain's features"
        );
        assert!(
            chain.n_channels() <= hand_dbc::emg::EMG_CHANNELS,
            "the bus carries {} EMG channels",
            hand_dbc::emg::EMG_CHANNELS
        );
        // The EMG counter is 8 bits at 1 kHz: up to 20 lost samples are bridged, a longer
        // jump is a gap that invalidates the window.
        let emg_delta = 20;
        Self {
            chain: Chain::new(chain),
            predictor,
            sample: vec![0.0; chain.n_channels()],
            assembler: EmgAssembler::try_new(EmgConfig {
                sample_period_us: 1000,
                max_gap_us: settings.max_gap_us,
            })
            .expect("the config layer keeps max_gap_us within the assembler's range"),
            emg_checkers: [
                checker(EmgSamplesG0::E2E, emg_delta),
                checker(EmgSamplesG1::E2E, emg_delta),
                checker(EmgSamplesG2::E2E, emg_delta),
            ],
            status_checkers: FingerStatus::E2E.map(|p| checker(p, 3)),
            estop_checker: checker(HandEstop::E2E, 15),
            amp_status_checker: checker(EmgStatus::E2E, 3),
            railed: 0,
            amp_reports_bad: false,
            safety: Safety::new(SafetyTiming {
                recovery_us: settings.recovery_us,
                ..SafetyTiming::default()
            }),
            watch: FingerWatch::new(now_us, settings.finger_silence_us, settings.recovery_us),
            conditioners: [FingerConditioner::default(); N_FINGERS],
            setpoint_tx: FingerSetpoint::E2E.map(E2eProtector::new),
            heartbeat_tx: E2eProtector::new(HandHeartbeat::E2E),
            last_emg_us: now_us,
            newest_rx_us: None,
            newest_counter: 0,
            last_newest_counter: 0,
            samples_used: 0,
            last_gap_at: None,
            samples_in: 0,
            labels: [0.0; N_FINGERS],
            setpoints: [Setpoint::default(); N_FINGERS],
            reported_force: [0.0; N_FINGERS],
            counters: Counters::default(),
            latency: Histogram::default(),
            compute: Histogram::default(),
            lateness: Histogram::default(),
            last_latency_us: 0,
            tx: [CanFrame::new_standard(0, &[]).expect("an empty frame is valid"); MAX_TX_PER_TICK],
            tx_len: 0,
            transitions: [None; 8],
            finger_events: [None; N_FINGERS],
            settings,
        }
    }

    fn note(&mut self, t: Option<Transition>) {
        if let Some(t) = t {
            if let Some(slot) = self.transitions.iter_mut().find(|s| s.is_none()) {
                *slot = Some(t);
            }
        }
    }

    /// Config, model and bus are validated: BOOT -> READY.
    pub fn validated(&mut self, now_us: u64) {
        let t = self.safety.validated(now_us);
        self.note(t);
    }

    /// Report a fault found outside the engine (bus-off, interface down).
    pub fn raise(&mut self, now_us: u64, fault: Fault) {
        let t = self.safety.raise(now_us, fault);
        self.note(t);
    }

    /// Apply a technician's command (at the next tick's start, by the caller's ordering).
    pub fn command(&mut self, now_us: u64, cmd: Command) -> Result<(), crate::safety::ArmError> {
        match cmd {
            Command::SetGains(f, g) if f < N_FINGERS => self.settings.gains[f] = g,
            Command::SetGains(..) => {}
            Command::Arm => self.safety.arm(now_us)?,
            Command::Stop => self.raise(now_us, Fault::StopRequested),
        }
        Ok(())
    }

    /// One received frame with its receive time.
    pub fn on_frame(&mut self, frame: &CanFrame, rx_us: u64) {
        if frame.is_remote() || frame.is_extended() {
            self.counters.bad_frames += 1;
            return;
        }
        let id = frame.raw_id();
        let data = frame.data();
        let msg = match messages::decode(id, data) {
            Ok(m) => m,
            Err(_) => {
                // A known id with a bad payload may be a corrupted safety frame: count it as
                // an E2E error for the streams we check, as a bad frame otherwise.
                if (0x100..=0x102).contains(&id) || id == HandEstop::ID {
                    self.e2e_error(rx_us);
                } else {
                    self.counters.bad_frames += 1;
                }
                return;
            }
        };
        match msg {
            Message::EmgSamplesG0(_) | Message::EmgSamplesG1(_) | Message::EmgSamplesG2(_) => {
                if let Some(f) = EmgFrame::from_message(&msg) {
                    self.emg(&f, data, rx_us);
                }
            }
            Message::FingerStatus(s) => {
                let f = s.instance();
                match self.status_checkers[f].check(Some(data)) {
                    E2eStatus::Ok => {
                        self.watch.heard(f, rx_us);
                        self.reported_force[f] = s.force();
                    }
                    E2eStatus::Repeated => {}
                    _ => self.counters.e2e_errors += 1,
                }
            }
            Message::EmgStatus(st) => match self.amp_status_checker.check(Some(data)) {
                E2eStatus::Ok | E2eStatus::WrongSequence => {
                    self.amp_reports_bad = st.lead_off_mask() != 0
                        || st.saturation_mask() != 0
                        || st.state() == AmpState::Fault;
                }
                E2eStatus::Error => self.e2e_error(rx_us),
                _ => {}
            },
            Message::HandEstop(e) => match self.estop_checker.check(Some(data)) {
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

    fn emg(&mut self, frame: &EmgFrame, data: &[u8], rx_us: u64) {
        match self.emg_checkers[usize::from(frame.group())].check(Some(data)) {
            // A counter jump is the assembler's business: it bridges or reports a gap.
            E2eStatus::Ok | E2eStatus::WrongSequence => {}
            E2eStatus::Repeated => return,
            E2eStatus::Error | E2eStatus::NoNewData => {
                self.e2e_error(rx_us);
                return;
            }
        }
        self.last_emg_us = rx_us;
        let chain = &mut self.chain;
        let sample = &mut self.sample;
        let samples_in = &mut self.samples_in;
        let last_gap_at = &mut self.last_gap_at;
        let newest_rx_us = &mut self.newest_rx_us;
        let newest_counter = &mut self.newest_counter;
        let railed = &mut self.railed;
        self.assembler.push(frame, rx_us, &mut |s: &EmgSample| {
            *railed += s
                .raw
                .iter()
                .filter(|&&r| !(RAIL_LOW..RAIL_HIGH).contains(&r))
                .count() as u32;
            if s.after_gap {
                *last_gap_at = Some(*samples_in);
            }
            for (ch, v) in sample.iter_mut().enumerate() {
                *v = s.uv(ch);
            }
            *samples_in += 1;
            // The step's own vectors are not used: the tick reads the newest window itself.
            chain.push(sample);
            *newest_rx_us = Some(s.received_us);
            *newest_counter = s.counter;
        });
        self.counters.samples_lost = self.assembler.stats().lost_samples;
    }

    fn window_valid(&self, now_us: u64) -> bool {
        let full = self.chain.samples_seen() >= self.chain.settings().window_len() as u64;
        let gap_left = self
            .last_gap_at
            .is_none_or(|at| self.samples_in - at >= self.chain.settings().window_len() as u64);
        let fresh = self
            .newest_rx_us
            .is_some_and(|t| now_us.saturating_sub(t) <= 2 * self.settings.tick_us);
        // Silence longer than the gap limit is a gap in progress: the window will not be
        // complete, so stop now rather than wait for the silence timeout.
        let flowing = now_us.saturating_sub(self.last_emg_us) <= self.settings.max_gap_us;
        full && gap_left && fresh && flowing && !self.chain.faults().any_in_window()
    }

    /// The tick due at `now_us` (its deadline), which actually started at `started_us`.
    /// Everything the tick decides is at its deadline, from the frames received by then (the
    /// loop holds later ones back for the next tick): so a late wake-up changes when the
    /// setpoints leave, never what they are, and a recording of the bus replays exactly.
    /// `started_us` only counts the lateness. Returns the frames to send, in order. No
    /// allocation.
    pub fn tick(&mut self, now_us: u64, started_us: u64) -> &[CanFrame] {
        self.counters.ticks += 1;
        let late = started_us.saturating_sub(now_us);
        self.lateness.record(late);
        if late > self.settings.deadline_slack_us {
            self.counters.deadline_misses += 1;
        }
        let dt_s = self.settings.tick_us as f64 * 1e-6;

        // Faults of this tick.
        if now_us.saturating_sub(self.last_emg_us) > self.settings.emg_silence_us {
            let t = self.safety.raise(now_us, Fault::EmgSilence);
            self.note(t);
        }
        if self.railed >= RAIL_LIMIT || self.amp_reports_bad {
            let t = self.safety.raise(now_us, Fault::SignalQuality);
            self.note(t);
        }
        self.railed = 0;
        let valid = self.window_valid(now_us);
        if self.chain.faults().any_in_window() {
            let t = self.safety.raise(now_us, Fault::NonFinite);
            self.note(t);
        } else if !valid
            && matches!(
                self.safety.state(),
                DaemonState::Running | DaemonState::Safe
            )
        {
            // Raised in SAFE too: the recovery time counts from the first valid window.
            let t = self.safety.raise(now_us, Fault::InvalidWindow);
            self.note(t);
        }

        // The model, on the window ending at the newest sample, when samples came in since
        // the last run: the setpoints never wait for the chain's next step.
        if valid && self.samples_in != self.samples_used {
            self.samples_used = self.samples_in;
            let y = self.predictor.run(self.chain.features());
            if y.iter().all(|v| v.is_finite()) {
                self.labels = y;
            } else {
                self.labels = [0.0; N_FINGERS];
                let t = self.safety.raise(now_us, Fault::NonFinite);
                self.note(t);
            }
        }
        let t = self.safety.update(now_us, valid);
        self.note(t);

        let mut events = [None; N_FINGERS];
        let mut k = 0;
        self.watch.update(now_us, |e| {
            events[k] = Some(e);
            k += 1;
        });
        self.finger_events = events;

        // Setpoints.
        self.tx_len = 0;
        let running = self.safety.outputs_enabled();
        for f in 0..N_FINGERS {
            let disabled = self.watch.is_disabled(f);
            let (mode, sp) = if running && !disabled {
                let sp = self.conditioners[f].step(self.labels[f], &self.settings.gains[f], dt_s);
                (FingerMode::Active, sp)
            } else {
                self.conditioners[f].reset();
                let mode = if disabled {
                    FingerMode::Disabled
                } else {
                    FingerMode::SafeStop
                };
                (mode, Setpoint::default())
            };
            self.setpoints[f] = sp;
            let frame = FingerSetpoint::new(f, mode, sp.force.0, sp.velocity.0)
                .or_else(|_| FingerSetpoint::new(f, FingerMode::SafeStop, 0.0, 0.0))
                .ok()
                .and_then(|m| self.setpoint_tx[f].protect_message(&m).ok());
            if let Some(frame) = frame {
                self.tx[self.tx_len] = frame;
                self.tx_len += 1;
            }
        }

        // Diagnostics every tick, heartbeat every other.
        let l = |x: f64| {
            (x.clamp(-1.0, 1.0) / HandDiag::LABEL0_FACTOR).round() * HandDiag::LABEL0_FACTOR
        };
        let shown = |f: usize| {
            if running {
                l(self.setpoints[f].label)
            } else {
                0.0
            }
        };
        if let Ok(d) = HandDiag::new(
            self.last_latency_us.min(u64::from(u16::MAX)) as u16,
            self.counters.deadline_misses.min(255) as u8,
            self.counters.samples_lost.min(255) as u8,
            shown(0),
            shown(1),
            shown(2),
            shown(3),
            shown(4),
            self.last_newest_counter % 4,
        ) {
            self.tx[self.tx_len] = d.to_frame();
            self.tx_len += 1;
        }
        if self.counters.ticks % 2 == 1 {
            let state = match self.safety.state() {
                DaemonState::Boot => BusState::Boot,
                DaemonState::Ready => BusState::Ready,
                DaemonState::Running => BusState::Running,
                DaemonState::Safe => BusState::Safe,
            };
            if let Some(frame) =
                HandHeartbeat::new(state, self.safety.faults().0, self.settings.model_id)
                    .ok()
                    .and_then(|m| self.heartbeat_tx.protect_message(&m).ok())
            {
                self.tx[self.tx_len] = frame;
                self.tx_len += 1;
            }
        }
        &self.tx[..self.tx_len]
    }

    /// Safe-stop setpoints for every finger (DISABLED for a disabled one), E2E-protected, to
    /// send at once when the bus comes back after a failure rather than at the next tick. Only
    /// when the outputs are not enabled (a bus failure latches SAFE); otherwise nothing, as the
    /// next tick carries the running setpoints. No allocation.
    pub fn safe_stop_frames(&mut self) -> &[CanFrame] {
        self.tx_len = 0;
        if self.safety.outputs_enabled() {
            return &self.tx[..0];
        }
        for f in 0..N_FINGERS {
            self.conditioners[f].reset();
            self.setpoints[f] = Setpoint::default();
            let mode = if self.watch.is_disabled(f) {
                FingerMode::Disabled
            } else {
                FingerMode::SafeStop
            };
            let frame = FingerSetpoint::new(f, mode, 0.0, 0.0)
                .ok()
                .and_then(|m| self.setpoint_tx[f].protect_message(&m).ok());
            if let Some(frame) = frame {
                self.tx[self.tx_len] = frame;
                self.tx_len += 1;
            }
        }
        &self.tx[..self.tx_len]
    }

    /// The tick's frames were written at `written_us`, after `compute_us` of work: record the
    /// latency from the newest sample frame used.
    pub fn written(&mut self, written_us: u64, compute_us: u64) {
        self.compute.record(compute_us);
        // From the newest sample the tick had (the one its window ends at when the model ran),
        // whether or not the model ran: HAND_DIAG then says which samples each tick had.
        self.last_newest_counter = self.newest_counter;
        if let Some(rx) = self.newest_rx_us {
            let lat = written_us.saturating_sub(rx);
            self.latency.record(lat);
            self.last_latency_us = lat;
        }
    }

    /// Drains the state transitions and finger events of the last calls, for the log.
    pub fn drain_events(
        &mut self,
        mut on_transition: impl FnMut(Transition),
        mut on_finger: impl FnMut(FingerEvent),
    ) {
        for t in self.transitions.iter_mut().filter_map(Option::take) {
            on_transition(t);
        }
        for e in self.finger_events.iter_mut().filter_map(Option::take) {
            on_finger(e);
        }
    }

    /// The daemon's state.
    pub fn state(&self) -> DaemonState {
        self.safety.state()
    }
    /// Faults in force.
    pub fn faults(&self) -> FaultSet {
        self.safety.faults()
    }
    /// Counters since start.
    pub fn counters(&self) -> Counters {
        self.counters
    }
    /// Latency histogram (newest sample frame -> setpoints written).
    pub fn latency(&self) -> &Histogram {
        &self.latency
    }
    /// Compute-time histogram.
    pub fn compute(&self) -> &Histogram {
        &self.compute
    }
    /// How late each tick started after its deadline.
    pub fn lateness(&self) -> &Histogram {
        &self.lateness
    }
    /// Whether a tick that starts at `now_us` for `deadline_us` is on time.
    pub fn on_time(&self, now_us: u64, deadline_us: u64) -> bool {
        now_us <= deadline_us + self.settings.deadline_slack_us
    }
    /// Last setpoints per finger.
    pub fn setpoints(&self) -> &[Setpoint; N_FINGERS] {
        &self.setpoints
    }
    /// Last raw labels from the model.
    pub fn labels(&self) -> &[f64; N_FINGERS] {
        &self.labels
    }
    /// Force each finger controller last reported, N.
    pub fn reported_force(&self) -> &[f64; N_FINGERS] {
        &self.reported_force
    }
    /// Whether finger `f` is disabled.
    pub fn finger_disabled(&self, f: usize) -> bool {
        self.watch.is_disabled(f)
    }
    /// Gains in force.
    pub fn gains(&self) -> &[FingerGains; N_FINGERS] {
        &self.settings.gains
    }
}
