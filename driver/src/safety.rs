//! The daemon's safety state machine: BOOT -> READY -> RUNNING, and SAFE on a fault.
//!
//! Transient faults (EMG silence, sporadic E2E errors, an invalid window, non-finite values in
//! the chain, a saturated or lead-off channel) leave SAFE by themselves once no transient fault has been raised for the recovery
//! time (500 ms by default). Latched faults (E-stop, bus-off or interface down, repeated E2E
//! failure, model error, a technician's stop, a second master on the bus) stay until an
//! explicit `arm`. Sporadic E2E errors
//! become a latched fault when `e2e_latch_count` of them fall within `e2e_latch_window_us`.
//!
//! Every change of state is returned as a [`Transition`] with its cause, for the caller to log.
//! The machine does no I/O and reads no clock: time comes in as microseconds.

use std::fmt;

/// The daemon's state.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DaemonState {
    /// Starting: config, model and bus not yet validated.
    Boot,
    /// Validated; waiting for the first valid window.
    Ready,
    /// Setpoints follow the model.
    Running,
    /// Every setpoint is safe-stop (zero force, zero velocity), still sent every tick.
    Safe,
}

impl DaemonState {
    /// The code HAND_HEARTBEAT carries for this state.
    pub fn code(self) -> u8 {
        match self {
            DaemonState::Boot => 0,
            DaemonState::Ready => 1,
            DaemonState::Running => 2,
            DaemonState::Safe => 3,
        }
    }
}

impl fmt::Display for DaemonState {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            DaemonState::Boot => "BOOT",
            DaemonState::Ready => "READY",
            DaemonState::Running => "RUNNING",
            DaemonState::Safe => "SAFE",
        })
    }
}

/// A fault the daemon can detect.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Fault {
    /// No EMG frame for longer than the silence timeout.
    EmgSilence,
    /// A frame failed its E2E check (CRC, counter).
    E2eError,
    /// The window had a gap over 20 ms or too few samples.
    InvalidWindow,
    /// NaN or infinity in the chain or the model output.
    NonFinite,
    /// A channel at the ADC rail (saturation, or lead-off picking up mains), from the samples
    /// themselves or from EMG_STATUS; or the amplifier's own status says its samples cannot
    /// drive the hand: not RUNNING, at another rate than the chain, a fault bit, or no
    /// EMG_STATUS for 300 ms (the log names which).
    SignalQuality,
    /// A HAND_ESTOP frame arrived.
    EStop,
    /// The controller went bus-off (error-passive is [`Fault::BusDegraded`]).
    BusOff,
    /// The CAN interface is down or could not be opened.
    InterfaceDown,
    /// E2E errors repeated beyond the latch threshold.
    RepeatedE2e,
    /// The model failed or produced an invalid result.
    ModelError,
    /// A technician asked for a stop.
    StopRequested,
    /// A calibration is under way (`handctl calibrate`, or the `calibrating` request): the hand
    /// is held in safe stop until a model is deployed (or rolled back) and then armed.
    Calibrating,
    /// The daemon started without a model file: nothing drives the hand until `handctl deploy`.
    NoModel,
    /// A model was swapped in (a deploy or a rollback): the hand waits in SAFE, every finger
    /// from rest, until `arm` hands it to the new model.
    ModelSwapped,
    /// Another node drives the fingers: handd received a FINGER_SETPOINT frame (SocketCAN does
    /// not loop a socket's own frames back to it, so any it reads was sent by someone else), or
    /// a finger controller reported ignoring a setpoint of a stale epoch long after handd's
    /// current epoch was opened. Latched: a second master is not a transient.
    SecondMaster,
    /// The bus works but not well enough to trust: the CAN controller is error-passive (its
    /// frames may go unacknowledged), or the transmit queue stayed full for longer than the
    /// finger controllers' own setpoint timeout. Transient: it clears when the controller is
    /// error-active and the queue takes frames again.
    BusDegraded,
}

impl Fault {
    /// All faults, in bit order.
    pub const ALL: [Fault; 16] = [
        Fault::EmgSilence,
        Fault::E2eError,
        Fault::InvalidWindow,
        Fault::NonFinite,
        Fault::SignalQuality,
        Fault::EStop,
        Fault::BusOff,
        Fault::InterfaceDown,
        Fault::RepeatedE2e,
        Fault::ModelError,
        Fault::StopRequested,
        Fault::Calibrating,
        Fault::NoModel,
        Fault::ModelSwapped,
        Fault::SecondMaster,
        Fault::BusDegraded,
    ];

    /// Whether the fault stays until `handctl arm`.
    pub fn is_latched(self) -> bool {
        matches!(
            self,
            Fault::EStop
                | Fault::BusOff
                | Fault::InterfaceDown
                | Fault::RepeatedE2e
                | Fault::ModelError
                | Fault::StopRequested
                | Fault::Calibrating
                | Fault::NoModel
                | Fault::ModelSwapped
                | Fault::SecondMaster
        )
    }

    /// The fault's bit in a [`FaultSet`] (and in HAND_HEARTBEAT's fault mask).
    pub fn bit(self) -> u16 {
        1 << Fault::ALL.iter().position(|f| *f == self).unwrap_or(0)
    }

    /// A stable lower-case name for logs and `handctl status`.
    pub fn name(self) -> &'static str {
        match self {
            Fault::EmgSilence => "emg_silence",
            Fault::E2eError => "e2e_error",
            Fault::InvalidWindow => "invalid_window",
            Fault::NonFinite => "non_finite",
            Fault::SignalQuality => "signal_quality",
            Fault::EStop => "estop",
            Fault::BusOff => "bus_off",
            Fault::InterfaceDown => "interface_down",
            Fault::RepeatedE2e => "repeated_e2e",
            Fault::ModelError => "model_error",
            Fault::StopRequested => "stop_requested",
            Fault::Calibrating => "calibrating",
            Fault::NoModel => "no_model",
            Fault::ModelSwapped => "model_swapped",
            Fault::SecondMaster => "second_master",
            Fault::BusDegraded => "bus_degraded",
        }
    }
}

/// A set of faults, as a bit mask.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct FaultSet(pub u16);

impl FaultSet {
    /// Add a fault.
    pub fn insert(&mut self, f: Fault) {
        self.0 |= f.bit();
    }
    /// Whether the set holds the fault.
    pub fn contains(self, f: Fault) -> bool {
        self.0 & f.bit() != 0
    }
    /// Whether the set is empty.
    pub fn is_empty(self) -> bool {
        self.0 == 0
    }
    /// The faults in the set.
    pub fn iter(self) -> impl Iterator<Item = Fault> {
        Fault::ALL.into_iter().filter(move |f| self.contains(*f))
    }
}

impl fmt::Display for FaultSet {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.is_empty() {
            return f.write_str("none");
        }
        for (i, fault) in self.iter().enumerate() {
            if i > 0 {
                f.write_str(",")?;
            }
            f.write_str(fault.name())?;
        }
        Ok(())
    }
}

/// Why the state changed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Cause {
    /// Config, model and bus were validated.
    Validated,
    /// The first valid window arrived.
    FirstValidWindow,
    /// A fault was raised.
    Fault(Fault),
    /// No transient fault for the recovery time.
    Recovered,
    /// A technician armed the daemon.
    Armed,
}

impl fmt::Display for Cause {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Cause::Validated => f.write_str("config, model and bus validated"),
            Cause::FirstValidWindow => f.write_str("first valid window"),
            Cause::Fault(x) => write!(f, "fault {}", x.name()),
            Cause::Recovered => f.write_str("signal good for the recovery time"),
            Cause::Armed => f.write_str("armed by a technician"),
        }
    }
}

/// A change of state, for the log.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Transition {
    /// State before.
    pub from: DaemonState,
    /// State after.
    pub to: DaemonState,
    /// Why.
    pub cause: Cause,
    /// When, µs.
    pub at_us: u64,
}

/// Timing of the recovery and latch rules.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SafetyTiming {
    /// Time without a transient fault before SAFE is left by itself, µs.
    pub recovery_us: u64,
    /// This many E2E errors within `e2e_latch_window_us` latch [`Fault::RepeatedE2e`].
    pub e2e_latch_count: usize,
    /// See `e2e_latch_count`, µs.
    pub e2e_latch_window_us: u64,
}

impl Default for SafetyTiming {
    fn default() -> Self {
        Self {
            recovery_us: 500_000,
            e2e_latch_count: 5,
            e2e_latch_window_us: 1_000_000,
        }
    }
}

const MAX_E2E_HISTORY: usize = 32;

/// Why `arm` was refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum ArmError {
    /// Arming before validation makes no sense.
    #[error("the daemon is still booting")]
    Booting,
    /// A calibration holds the hand until a model is deployed or rolled back.
    #[error("calibrating: the hand stays held until a model is deployed (`handctl deploy MODEL`) or rolled back (`handctl rollback`); then arm")]
    Calibrating,
    /// No model runs yet.
    #[error("no model: deploy one first (`handctl deploy MODEL`)")]
    NoModel,
}

/// The state machine.
#[derive(Debug, Clone)]
pub struct Safety {
    timing: SafetyTiming,
    state: DaemonState,
    latched: FaultSet,
    transient: FaultSet,
    last_transient_us: Option<u64>,
    e2e_times: [u64; MAX_E2E_HISTORY],
    e2e_len: usize,
}

impl Safety {
    /// A machine in BOOT. `e2e_latch_count` is capped at the history it keeps (32).
    pub fn new(mut timing: SafetyTiming) -> Self {
        timing.e2e_latch_count = timing.e2e_latch_count.clamp(1, MAX_E2E_HISTORY);
        Self {
            timing,
            state: DaemonState::Boot,
            latched: FaultSet::default(),
            transient: FaultSet::default(),
            last_transient_us: None,
            e2e_times: [0; MAX_E2E_HISTORY],
            e2e_len: 0,
        }
    }

    /// The current state.
    pub fn state(&self) -> DaemonState {
        self.state
    }

    /// Latched faults (cleared only by `arm`).
    pub fn latched(&self) -> FaultSet {
        self.latched
    }

    /// Transient faults raised since the last recovery.
    pub fn transient(&self) -> FaultSet {
        self.transient
    }

    /// All faults in force.
    pub fn faults(&self) -> FaultSet {
        FaultSet(self.latched.0 | self.transient.0)
    }

    /// Whether setpoints may follow the model.
    pub fn outputs_enabled(&self) -> bool {
        self.state == DaemonState::Running
    }

    fn go(&mut self, to: DaemonState, cause: Cause, at_us: u64) -> Option<Transition> {
        if self.state == to {
            return None;
        }
        let t = Transition {
            from: self.state,
            to,
            cause,
            at_us,
        };
        self.state = to;
        Some(t)
    }

    /// BOOT -> READY, once config, model and bus are validated.
    pub fn validated(&mut self, now_us: u64) -> Option<Transition> {
        if self.state == DaemonState::Boot {
            self.go(DaemonState::Ready, Cause::Validated, now_us)
        } else {
            None
        }
    }

    /// Report a fault seen now. Transient faults restart the recovery timer each time they are
    /// raised, so a condition that persists is raised on every tick it holds.
    pub fn raise(&mut self, now_us: u64, fault: Fault) -> Option<Transition> {
        let mut fault = fault;
        if fault == Fault::E2eError && self.note_e2e_error(now_us) {
            self.transient.insert(Fault::E2eError);
            fault = Fault::RepeatedE2e;
        }
        if fault.is_latched() {
            self.latched.insert(fault);
        } else {
            self.transient.insert(fault);
            self.last_transient_us = Some(now_us);
        }
        if self.state == DaemonState::Boot {
            return None;
        }
        self.go(DaemonState::Safe, Cause::Fault(fault), now_us)
    }

    /// Records an E2E error and tells whether the latch threshold is now reached.
    fn note_e2e_error(&mut self, now_us: u64) -> bool {
        let window = self.timing.e2e_latch_window_us;
        let mut kept = 0;
        for i in 0..self.e2e_len {
            let t = self.e2e_times[i];
            if now_us.saturating_sub(t) < window {
                self.e2e_times[kept] = t;
                kept += 1;
            }
        }
        if kept == MAX_E2E_HISTORY {
            self.e2e_times.copy_within(1.., 0);
            kept -= 1;
        }
        self.e2e_times[kept] = now_us;
        self.e2e_len = kept + 1;
        self.e2e_len >= self.timing.e2e_latch_count
    }

    /// Called every tick after the faults of the tick were raised: READY -> RUNNING on the
    /// first valid window, SAFE -> RUNNING after the recovery time without transient faults
    /// (and no latched fault).
    pub fn update(&mut self, now_us: u64, window_valid: bool) -> Option<Transition> {
        match self.state {
            DaemonState::Ready if window_valid && self.faults().is_empty() => {
                self.go(DaemonState::Running, Cause::FirstValidWindow, now_us)
            }
            DaemonState::Safe if self.latched.is_empty() && window_valid => {
                let quiet = self
                    .last_transient_us
                    .is_none_or(|t| now_us.saturating_sub(t) >= self.timing.recovery_us);
                if quiet {
                    self.transient = FaultSet::default();
                    self.go(DaemonState::Running, Cause::Recovered, now_us)
                } else {
                    None
                }
            }
            _ => None,
        }
    }

    /// A technician's `arm`: clears latched faults. The machine then leaves SAFE by the
    /// ordinary recovery rule, so a fault still present keeps the hand safe.
    pub fn arm(&mut self, now_us: u64) -> Result<(), ArmError> {
        if self.state == DaemonState::Boot {
            return Err(ArmError::Booting);
        }
        self.latched = FaultSet::default();
        self.e2e_len = 0;
        // Arming restarts the recovery time: the hand moves only after a full good period.
        self.last_transient_us = Some(now_us);
        Ok(())
    }
}

/// Watches each finger controller's FINGER_STATUS: a finger silent for longer than the timeout
/// is disabled alone; it comes back after reporting again for the recovery time.
#[derive(Debug, Clone)]
pub struct FingerWatch<const N: usize> {
    timeout_us: u64,
    recovery_us: u64,
    last_seen: [Option<u64>; N],
    back_since: [Option<u64>; N],
    disabled: [bool; N],
}

/// A finger's change of availability.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FingerEvent {
    /// The finger's controller fell silent: disabled.
    Disabled(usize),
    /// The finger's controller reported again for the recovery time: enabled.
    Enabled(usize),
}

impl<const N: usize> FingerWatch<N> {
    /// All fingers enabled, none heard yet; the timeout counts from `now_us`.
    pub fn new(now_us: u64, timeout_us: u64, recovery_us: u64) -> Self {
        Self {
            timeout_us,
            recovery_us,
            last_seen: [Some(now_us); N],
            back_since: [None; N],
            disabled: [false; N],
        }
    }

    /// A valid FINGER_STATUS from finger `f` arrived at `now_us`.
    pub fn heard(&mut self, f: usize, now_us: u64) {
        if f >= N {
            return;
        }
        let gap = self.last_seen[f].is_none_or(|t| now_us.saturating_sub(t) > self.timeout_us);
        if self.disabled[f] && (gap || self.back_since[f].is_none()) {
            self.back_since[f] = Some(now_us);
        }
        self.last_seen[f] = Some(now_us);
    }

    /// Evaluate timeouts; calls `on_event` for each change.
    pub fn update(&mut self, now_us: u64, mut on_event: impl FnMut(FingerEvent)) {
        for f in 0..N {
            let silent =
                self.last_seen[f].is_none_or(|t| now_us.saturating_sub(t) > self.timeout_us);
            if silent {
                self.back_since[f] = None;
                if !self.disabled[f] {
                    self.disabled[f] = true;
                    on_event(FingerEvent::Disabled(f));
                }
            } else if self.disabled[f]
                && self.back_since[f].is_some_and(|t| now_us.saturating_sub(t) >= self.recovery_us)
            {
                self.disabled[f] = false;
                self.back_since[f] = None;
                on_event(FingerEvent::Enabled(f));
            }
        }
    }

    /// Whether finger `f` is disabled.
    pub fn is_disabled(&self, f: usize) -> bool {
        self.disabled.get(f).copied().unwrap_or(true)
    }
}

#[cfg(test)]
mod tests {
    /// hand.dbc's FaultMask comment names every fault at its bit, in handd's order.
    #[test]
    fn the_dbc_names_every_fault_bit() {
        let dbc = include_str!("../../can-dbc/hand.dbc");
        let line = dbc
            .lines()
            .find(|l| l.starts_with("CM_ SG_ 768 FaultMask"))
            .expect("FaultMask's comment in hand.dbc");
        for (bit, f) in Fault::ALL.iter().enumerate() {
            let named = format!("bit {bit} {},", f.name());
            let last = format!("bit {bit} {};", f.name());
            assert!(
                line.contains(&named) || line.contains(&last),
                "hand.dbc's FaultMask comment does not say {named:?}: {line}"
            );
            assert_eq!(f.bit(), 1 << bit);
        }
    }

    use super::*;

    fn running() -> Safety {
        let mut s = Safety::new(SafetyTiming::default());
        assert!(s.validated(0).is_some());
        assert_eq!(
            s.update(50_000, true).map(|t| t.to),
            Some(DaemonState::Running)
        );
        s
    }

    #[test]
    fn boot_ready_running() {
        let mut s = Safety::new(SafetyTiming::default());
        assert_eq!(s.state(), DaemonState::Boot);
        assert_eq!(s.update(0, true), None, "no running before validation");
        let t = s.validated(10).unwrap();
        assert_eq!(
            (t.from, t.to, t.cause),
            (DaemonState::Boot, DaemonState::Ready, Cause::Validated)
        );
        assert_eq!(s.update(20, false), None, "an invalid window keeps READY");
        assert_eq!(s.update(30, true).unwrap().to, DaemonState::Running);
        assert!(s.outputs_enabled());
    }

    #[test]
    fn transient_fault_recovers_after_500ms_of_good_signal() {
        let mut s = running();
        let t = s.raise(100_000, Fault::EmgSilence).unwrap();
        assert_eq!(
            (t.to, t.cause),
            (DaemonState::Safe, Cause::Fault(Fault::EmgSilence))
        );
        // Still silent: raised again every tick.
        assert_eq!(s.raise(150_000, Fault::EmgSilence), None);
        assert_eq!(s.update(150_000, false), None);
        // Good from 200 ms on: recovery at 150 ms + 500 ms.
        for now in (200_000..650_000).step_by(50_000) {
            assert_eq!(s.update(now, true), None, "too early at {now}");
        }
        let t = s.update(650_000, true).unwrap();
        assert_eq!((t.to, t.cause), (DaemonState::Running, Cause::Recovered));
        assert!(s.faults().is_empty());
    }

    #[test]
    fn latched_fault_needs_arm() {
        let mut s = running();
        assert_eq!(
            s.raise(100_000, Fault::EStop).unwrap().to,
            DaemonState::Safe
        );
        assert_eq!(
            s.update(10_000_000, true),
            None,
            "latched: no recovery by itself"
        );
        assert!(s.latched().contains(Fault::EStop));
        s.arm(10_000_000).unwrap();
        assert_eq!(
            s.update(10_400_000, true),
            None,
            "arm restarts the recovery time"
        );
        assert_eq!(s.update(10_500_000, true).unwrap().to, DaemonState::Running);
    }

    #[test]
    fn sporadic_e2e_errors_are_transient_repeated_ones_latch() {
        let mut s = running();
        s.raise(0, Fault::E2eError);
        assert!(!s.latched().contains(Fault::RepeatedE2e));
        assert!(s.update(600_000, true).is_some(), "one error recovers");
        // Five errors within a second latch.
        for i in 0..5u64 {
            s.raise(2_000_000 + i * 100_000, Fault::E2eError);
        }
        assert!(s.latched().contains(Fault::RepeatedE2e));
        assert_eq!(s.update(9_000_000, true), None);
        // Errors spread wider than the window do not latch.
        let mut s = running();
        for i in 0..10u64 {
            s.raise(i * 300_000, Fault::E2eError);
        }
        assert!(!s.latched().contains(Fault::RepeatedE2e), "{}", s.faults());
    }

    #[test]
    fn arm_before_validation_is_refused() {
        let mut s = Safety::new(SafetyTiming::default());
        assert_eq!(s.arm(0), Err(ArmError::Booting));
    }

    #[test]
    fn fault_set_names_and_bits_are_distinct() {
        let mut set = FaultSet::default();
        for f in Fault::ALL {
            assert!(!set.contains(f));
            set.insert(f);
        }
        assert_eq!(set.0.count_ones() as usize, Fault::ALL.len());
        assert_eq!(
            FaultSet(Fault::EStop.bit() | Fault::BusOff.bit()).to_string(),
            "estop,bus_off"
        );
    }

    #[test]
    fn silent_finger_is_disabled_alone_and_comes_back() {
        let mut w = FingerWatch::<5>::new(0, 100_000, 500_000);
        let mut events = Vec::new();
        for now in (0..=200_000u64).step_by(20_000) {
            for f in 0..5 {
                if f != 2 || now < 60_000 {
                    w.heard(f, now);
                }
            }
            w.update(now, |e| events.push((now, e)));
        }
        // Last heard at 40 ms: silent for more than 100 ms at 160 ms.
        assert_eq!(events, vec![(160_000, FingerEvent::Disabled(2))]);
        assert!(w.is_disabled(2) && !w.is_disabled(1));
        events.clear();
        for now in (220_000..=800_000u64).step_by(20_000) {
            for f in 0..5 {
                w.heard(f, now);
            }
            w.update(now, |e| events.push((now, e)));
        }
        assert_eq!(events, vec![(720_000, FingerEvent::Enabled(2))]);
    }
}
