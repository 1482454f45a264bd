//! The control loop's core, free of I/O: frames in, frames out, one [`Engine::tick`] every
//! 50 ms.
//!
//! Frames go in with their receive time ([`Engine::on_frame`], `rx`): EMG sample frames pass
//! the shared front end (`hand_dbc::emg_front`: E2E, decode, reassembly by counter, rails,
//! µV) and are pushed sample by sample through the signal chain; finger status frames feed the
//! per-finger watchdog; an E-stop latches SAFE. Each tick evaluates the faults (`faults`), runs
//! the model on the window ending at the newest sample, conditions the labels and builds one
//! FINGER_SETPOINT per finger, plus HAND_DIAG every tick and HAND_HEARTBEAT every other tick
//! (`tx`). Every setpoint carries the current setpoint epoch (`epoch`), and a finger gets a
//! SAFE_STOP first in each epoch, so no stale setpoint can move a finger.
//!
//! After construction nothing here allocates (a test counts), returns a `Result` on the tick
//! path or panics on any frame: every out-of-range value was excluded by validating the
//! config, so encoding a setpoint cannot fail, and if it ever did the finger gets a safe stop.

#[cfg(test)]
mod amp_tests;
mod drives;
mod epoch;
mod faults;
mod rx;
mod swap;
#[cfg(test)]
mod test_support;
mod tx;

pub use drives::{bank_settings, check_drives, MAX_IMMEDIATE};
pub use epoch::{fresh_epoch, fresh_epochs};
pub use rx::{amp_problem, AmpProblem, WindowProblem, AMP_STATUS_SILENCE_US};
pub use swap::{Hold, ModelSwap, SwapTicket};

use decoder::dsp::ChainSettings;
use decoder::model::Predictor;
use hand_dbc::CanFrame;

use crate::conditioner::{Feedback, FingerConditioner, FingerGains, Setpoint};
use crate::safety::{
    DaemonState, Fault, FaultSet, FingerEvent, FingerWatch, Safety, SafetyTiming, Transition,
};
use crate::stats::Histogram;
use crate::tape::{Entry, Recorded, Recorder};
use crate::units::N_FINGERS;

/// Most frames one tick sends: five setpoints (FINGER_SETPOINT or a CiA 402 drive's RPDO1),
/// HAND_DIAG and HAND_HEARTBEAT; with CiA 402 drives also SYNC, handd's CANopen heartbeat and
/// up to two start-up frames per drive.
pub const MAX_TX_PER_TICK: usize = 3 * N_FINGERS + 4;

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
    /// The spread of the input plausibility check (`decoder::model::Envelope::implausible`),
    /// applied to every model the engine runs.
    pub plausible_spread: f64,
    /// The margin of the plausibility check's *off the patterns* test over the calibration's
    /// own worst misfit (`decoder::model::PatternCone::bar`), applied to every model.
    pub pattern_margin: f64,
    /// Each finger's drive: native (hand.dbc's FINGER_SETPOINT) or a CiA 402 drive.
    pub drives: crate::drive_config::Drives,
}

impl Default for EngineSettings {
    fn default() -> Self {
        Self {
            tick_us: 50_000,
            emg_silence_us: 100_000,
            finger_silence_us: 100_000,
            recovery_us: 500_000,
            max_gap_us: hand_dbc::emg::DEFAULT_MAX_GAP_US,
            deadline_slack_us: 5_000,
            gains: [FingerGains::default(); N_FINGERS],
            model_id: 0,
            plausible_spread: decoder::model::PLAUSIBLE_SPREAD,
            pattern_margin: decoder::model::CONE_MARGIN,
            drives: crate::drive_config::Drives::default(),
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
    /// Windows beyond the calibration's envelope, moved back into it before the model
    /// (`decoder::model::Envelope`): a stronger grip than the calibration's, or an electrode
    /// far above its calibrated level.
    pub beyond_calibration: u64,
    /// Windows found implausible (one channel far beyond the calibration while the others are
    /// not: a pressed, lifted or hit electrode): the model gave rest, `signal_quality` was
    /// raised.
    pub implausible: u64,
}

/// Requests from technicians, applied at the next tick.
#[derive(Debug, Clone)]
pub enum Command {
    /// New gains for one finger.
    SetGains(usize, FingerGains),
    /// Clear latched faults (refused during the calibrating hold and without a model).
    Arm,
    /// Go to SAFE until armed.
    Stop,
    /// Begin the calibrating hold (see [`Hold`]).
    Calibrating,
    /// Swap in a prepared model (a deploy or a rollback); see [`ModelSwap`].
    Swap(Box<ModelSwap>),
}

/// Timing of the ticks, for HAND_DIAG and `handctl status`.
#[derive(Clone, Default)]
struct TickTiming {
    latency: Histogram,
    compute: Histogram,
    lateness: Histogram,
    last_latency_us: u64,
    /// The newest sample counter of the last tick written, for HAND_DIAG.
    last_newest_counter: u8,
}

/// The engine. See the module docs. Cloning it forks the whole state (a replay tries
/// alternatives on clones).
#[derive(Clone)]
pub struct Engine {
    settings: EngineSettings,
    emg: rx::EmgIn,
    inputs: rx::Inputs,
    predictor: Option<Predictor>,
    hold: Hold,
    /// Samples in when the model last ran.
    samples_used: u64,
    safety: Safety,
    watch: FingerWatch<N_FINGERS>,
    conditioners: [FingerConditioner; N_FINGERS],
    labels: [f64; N_FINGERS],
    setpoints: [Setpoint; N_FINGERS],
    counters: Counters,
    timing: TickTiming,
    tx: tx::Tx,
    /// The CiA 402 drives, when a finger has one.
    drives: Option<drives::Drives>,
    epochs: epoch::Epochs,
    transitions: [Option<Transition>; 8],
    /// Why the last tick's window was not valid, if it was not.
    window_problem: Option<WindowProblem>,
    finger_events: [Option<FingerEvent>; N_FINGERS],
    /// Where every input goes when handd records a tape (`crate::tape`), and what it needs to
    /// say first: when the engine was built and its first epochs.
    tape: Option<Recorder>,
    built_us: u64,
    built_epochs: [u16; N_FINGERS],
}

impl Engine {
    /// An engine in BOOT for the chain `settings` and a model's `predictor`, at time `now_us`,
    /// in a fresh setpoint epoch ([`fresh_epoch`]; [`Engine::begin_epoch`] sets another).
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
        Self::build(chain, Some(predictor), settings, now_us)
    }

    /// An engine with no model yet: once validated it is SAFE with [`Fault::NoModel`] latched,
    /// sends safe stops, and refuses `arm` until a model is swapped in ([`Command::Swap`]).
    pub fn without_model(chain: &ChainSettings, settings: EngineSettings, now_us: u64) -> Self {
        Self::build(chain, None, settings, now_us)
    }

    fn build(
        chain: &ChainSettings,
        mut predictor: Option<Predictor>,
        settings: EngineSettings,
        now_us: u64,
    ) -> Self {
        if let Some(p) = &mut predictor {
            p.set_plausible_spread(settings.plausible_spread);
            p.set_pattern_margin(settings.pattern_margin);
        }
        assert!(
            chain.n_channels() <= hand_dbc::emg::EMG_CHANNELS,
            "the bus carries {} EMG channels",
            hand_dbc::emg::EMG_CHANNELS
        );
        let epochs = fresh_epochs();
        Self {
            emg: rx::EmgIn::new(chain, settings.max_gap_us, now_us),
            inputs: rx::Inputs::new(now_us),
            predictor,
            hold: Hold::Free,
            samples_used: 0,
            safety: Safety::new(SafetyTiming {
                recovery_us: settings.recovery_us,
                ..SafetyTiming::default()
            }),
            watch: FingerWatch::new(now_us, settings.finger_silence_us, settings.recovery_us),
            conditioners: [FingerConditioner::default(); N_FINGERS],
            labels: [0.0; N_FINGERS],
            setpoints: [Setpoint::default(); N_FINGERS],
            counters: Counters::default(),
            timing: TickTiming::default(),
            tx: tx::Tx::new(),
            drives: drives::Drives::try_new(&settings.drives, settings.tick_us)
                .expect("the drive table was checked (check_drives) before the engine"),
            epochs: epoch::Epochs::new(epochs),
            transitions: [None; 8],
            window_problem: None,
            finger_events: [None; N_FINGERS],
            settings,
            tape: None,
            built_us: now_us,
            built_epochs: epochs,
        }
    }

    /// Records every input from now on to `tape`, and every tick's frames (see `crate::tape`):
    /// call it right after construction, before anything else reaches the engine. Panics
    /// otherwise (the tape would not replay).
    pub fn record_to(&mut self, tape: Recorder) {
        assert!(
            self.counters.ticks == 0
                && self.epochs.all() == self.built_epochs
                && self.state() == DaemonState::Boot,
            "a tape starts with the engine"
        );
        self.tape = Some(tape);
        self.record(Entry::Built {
            at_us: self.built_us,
            epochs: self.built_epochs,
            model_id: self.settings.model_id,
        });
    }

    /// Starts every finger in `epochs` instead of fresh ones, right after construction (a
    /// replay takes a tape's).
    pub fn with_epochs(mut self, epochs: [u16; N_FINGERS]) -> Self {
        self.epochs = epoch::Epochs::new(epochs);
        self.built_epochs = epochs;
        self
    }

    fn record(&mut self, e: Entry) {
        if let Some(t) = &mut self.tape {
            t.put(e);
        }
    }

    /// The tape's recorder, if one is attached (its count of lost entries).
    pub fn tape(&self) -> Option<&Recorder> {
        self.tape.as_ref()
    }

    fn note(&mut self, t: Option<Transition>) {
        if let Some(t) = t {
            if t.to == DaemonState::Safe {
                self.epochs.next();
            }
            if let Some(slot) = self.transitions.iter_mut().find(|s| s.is_none()) {
                *slot = Some(t);
            }
        }
    }

    /// Starts setpoint epoch `epoch` for finger `f` (a replay takes the recorded one): the
    /// finger gets a SAFE_STOP of it before anything else.
    pub fn begin_epoch(&mut self, f: usize, epoch: u16) {
        self.record(Entry::BeganEpoch {
            finger: f as u8,
            epoch,
        });
        self.epochs.begin(f, epoch);
    }

    /// Starts every finger's next setpoint epoch: the daemon calls it when the bus comes back.
    pub fn new_epoch(&mut self) {
        self.record(Entry::NewEpoch);
        self.epochs.next();
        // The drives' NMT and CiA 402 states are unknown after a bus failure.
        if let Some(d) = &mut self.drives {
            d.bus_recovered();
        }
    }

    /// The setpoint epoch finger `f`'s frames carry now.
    pub fn epoch(&self, f: usize) -> u16 {
        self.epochs.current(f)
    }

    /// Every finger's setpoint epoch now.
    pub fn epochs(&self) -> [u16; N_FINGERS] {
        self.epochs.all()
    }

    /// Setpoint epochs finger `f` began since start, the first included.
    pub fn epochs_begun(&self, f: usize) -> u64 {
        self.epochs.begun(f)
    }

    /// Config, model and bus are validated: BOOT -> READY (SAFE at once without a model).
    pub fn validated(&mut self, now_us: u64) {
        self.record(Entry::Validated { at_us: now_us });
        let t = self.safety.validated(now_us);
        self.note(t);
        if self.predictor.is_none() {
            self.fault(now_us, Fault::NoModel);
        }
    }

    /// The latches a restart must keep (every latched fault but `no_model`, and the
    /// calibrating hold): the loop publishes them every tick (`crate::persist`). No allocation.
    pub fn latches(&self) -> crate::persist::Latches {
        crate::persist::Latches::of(self.safety.latched(), self.hold)
    }

    /// Takes over the latches a previous process left (`crate::persist::load`), after
    /// [`Engine::validated`]: SAFE with each of them latched, and the calibrating hold as it
    /// was, so `arm` (after a deploy, for the hold) is needed as before the restart.
    pub fn restore(&mut self, now_us: u64, latches: crate::persist::Latches) {
        self.record(Entry::Restored {
            at_us: now_us,
            faults: latches.faults,
            hold: latches.hold,
        });
        for f in latches.faults.iter() {
            self.fault(now_us, f);
        }
        self.hold = latches.hold;
        if latches.hold == Hold::Calibrating {
            self.fault(now_us, Fault::Calibrating);
        }
    }

    /// Report a fault found outside the engine (bus-off, interface down).
    pub fn raise(&mut self, now_us: u64, fault: Fault) {
        self.record(Entry::Raised {
            at_us: now_us,
            fault,
        });
        self.fault(now_us, fault);
    }

    /// A fault the engine found itself.
    fn fault(&mut self, now_us: u64, fault: Fault) {
        let t = self.safety.raise(now_us, fault);
        self.note(t);
    }

    /// Apply a technician's command (at the next tick's start, by the caller's ordering).
    pub fn command(&mut self, now_us: u64, cmd: Command) -> Result<(), crate::safety::ArmError> {
        let recorded = match cmd {
            Command::SetGains(f, g) if f < N_FINGERS => {
                self.settings.gains[f] = g;
                Some(Recorded::Gains(f as u8, g))
            }
            // Out of range: nothing happens, nothing to replay.
            Command::SetGains(..) => None,
            Command::Arm => {
                // A refused arm is on the tape too: the replay refuses it the same way.
                self.record(Entry::Command {
                    at_us: now_us,
                    command: Recorded::Arm,
                });
                return self.arm(now_us);
            }
            Command::Stop => {
                self.fault(now_us, Fault::StopRequested);
                Some(Recorded::Stop)
            }
            Command::Calibrating => {
                self.begin_hold(now_us);
                Some(Recorded::Calibrating)
            }
            Command::Swap(m) => {
                let model_id = m.model_id;
                let swapped = self.swap_model(now_us, m);
                Some(Recorded::Swap { model_id, swapped })
            }
        };
        if let Some(command) = recorded {
            self.record(Entry::Command {
                at_us: now_us,
                command,
            });
        }
        Ok(())
    }

    /// The tick due at `now_us` (its deadline), which actually started at `started_us`.
    /// Everything the tick decides is at its deadline, from the frames received by then (the
    /// loop holds later ones back for the next tick): so a late wake-up changes when the
    /// setpoints leave, never what they are, and a recording of the bus replays exactly.
    /// `started_us` only counts the lateness. Returns the frames to send, in order. No
    /// allocation.
    pub fn tick(&mut self, now_us: u64, started_us: u64) -> &[CanFrame] {
        self.record(Entry::Tick {
            deadline_us: now_us,
            started_us,
        });
        self.count_tick(now_us, started_us);
        let valid = self.evaluate_faults(now_us);
        self.run_model(now_us, valid);
        let t = self.safety.update(now_us, valid);
        self.note(t);
        self.update_watch(now_us);
        self.transmit(now_us);
        self.record_out()
    }

    /// The frames just built, put on the tape too.
    fn record_out(&mut self) -> &[CanFrame] {
        if let Some(tape) = &mut self.tape {
            for &frame in self.tx.frames() {
                tape.put(Entry::Out { frame });
            }
        }
        self.tx.frames()
    }

    fn count_tick(&mut self, now_us: u64, started_us: u64) {
        self.counters.ticks += 1;
        let late = started_us.saturating_sub(now_us);
        self.timing.lateness.record(late);
        if late > self.settings.deadline_slack_us {
            self.counters.deadline_misses += 1;
        }
    }

    /// The model, on the window ending at the newest sample, when samples came in since its
    /// last run: the setpoints never wait for the chain's next step.
    fn run_model(&mut self, now_us: u64, valid: bool) {
        let Some(predictor) = self.predictor.as_mut() else {
            return;
        };
        if !valid || self.emg.samples_in == self.samples_used {
            return;
        }
        self.samples_used = self.emg.samples_in;
        let y = predictor.run(self.emg.chain.features());
        if predictor.last_scale() < 1.0 {
            self.counters.beyond_calibration += 1;
        }
        // One channel standing alone, far above the next: a pressed, lifted or knocked
        // electrode, not an effort. The predictor gave rest; the hand stops while it lasts.
        if predictor.last_implausible() {
            self.counters.implausible += 1;
            self.fault(now_us, Fault::SignalQuality);
        }
        if y.iter().all(|v| v.is_finite()) {
            self.labels = y;
        } else {
            self.labels = [0.0; N_FINGERS];
            self.fault(now_us, Fault::NonFinite);
        }
    }

    /// The tick's frames were written at `written_us`, after `compute_us` of work: record the
    /// latency from the newest sample frame used.
    pub fn written(&mut self, written_us: u64, compute_us: u64) {
        self.record(Entry::Written {
            at_us: written_us,
            compute_us,
        });
        self.timing.compute.record(compute_us);
        // From the newest sample the tick had (the one its window ends at when the model ran),
        // whether or not the model ran: HAND_DIAG then says which samples each tick had.
        self.timing.last_newest_counter = self.emg.newest_counter;
        if let Some(rx) = self.emg.newest_rx_us {
            let lat = written_us.saturating_sub(rx);
            self.timing.latency.record(lat);
            self.timing.last_latency_us = lat;
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

    /// Why the last tick's window could not drive the fingers (None: it could).
    pub fn window_problem(&self) -> Option<WindowProblem> {
        self.window_problem
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
        &self.timing.latency
    }
    /// Compute-time histogram.
    pub fn compute(&self) -> &Histogram {
        &self.timing.compute
    }
    /// How late each tick started after its deadline.
    pub fn lateness(&self) -> &Histogram {
        &self.timing.lateness
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
        &self.inputs.reported_force
    }
    /// Joint angle each finger controller last reported, rad.
    pub fn reported_position(&self) -> &[f64; N_FINGERS] {
        &self.inputs.reported_position
    }
    /// What each finger controller last reported that the control law uses (the joint limit).
    pub fn feedback(&self) -> &[Feedback; N_FINGERS] {
        &self.inputs.feedback
    }
    /// What the amplifier's own status says is wrong with its samples (it raises
    /// `signal_quality` while it lasts), if anything.
    pub fn amp_problem(&self) -> Option<AmpProblem> {
        self.inputs.amp_problem
    }

    /// The amplifier's last lead-off and saturation masks.
    pub fn amp_masks(&self) -> (u16, u16) {
        self.inputs.amp_masks
    }
    /// EMG channels of the chain.
    pub fn n_channels(&self) -> usize {
        self.emg.chain.settings().n_channels()
    }
    /// Whether finger `f`'s last setpoint was ACTIVE mode (outputs on, finger not disabled).
    pub fn finger_active(&self, f: usize) -> bool {
        self.safety.outputs_enabled() && !self.watch.is_disabled(f)
    }
    /// Whether finger `f` is disabled.
    pub fn finger_disabled(&self, f: usize) -> bool {
        self.watch.is_disabled(f)
    }
    /// Finger `f`'s CiA 402 drive status (`None`: a native finger).
    pub fn drive_status(&self, f: usize) -> Option<hand_canopen::DriveStatus> {
        self.drives.as_ref().and_then(|d| d.status(f))
    }
    /// Finger `f`'s CiA 402 drive: its node id and status (`None`: a native finger).
    pub fn drive(&self, f: usize) -> Option<(u8, hand_canopen::DriveStatus)> {
        self.drives
            .as_ref()
            .and_then(|d| Some((d.node(f)?, d.status(f)?)))
    }
    /// Frames to send at once, outside the tick (a CiA 402 drive's start-up answered at bus
    /// speed), taken from the engine: the caller sends them right after the frame that made
    /// them. Put on the tape too.
    pub fn take_immediate(&mut self) -> &[CanFrame] {
        let Some(d) = &mut self.drives else {
            return &[];
        };
        let frames = d.take_immediate();
        if let Some(tape) = &mut self.tape {
            for &frame in frames {
                tape.put(Entry::Out { frame });
            }
        }
        frames
    }
    /// EMG samples pushed into the chain since start.
    pub fn samples_in(&self) -> u64 {
        self.emg.samples_in
    }
    /// Samples in ([`Engine::samples_in`]) when the model last ran: its window ended at that
    /// sample.
    pub fn samples_used(&self) -> u64 {
        self.samples_used
    }
    /// The features the model last ran on (zeros before its first run); what training's path
    /// computes for a window ending at [`Engine::samples_used`]. No computation.
    pub fn model_features(&self) -> &[f64] {
        self.emg.chain.last_features()
    }
    /// Gains in force.
    pub fn gains(&self) -> &[FingerGains; N_FINGERS] {
        &self.settings.gains
    }
}
