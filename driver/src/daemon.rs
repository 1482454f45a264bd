//! The daemon's loop around the [`Engine`]: absolute deadlines every tick, every frame
//! received up to a tick's deadline read at that tick (later ones wait for the next, so a late
//! wake-up never changes what a tick computes), technicians' commands applied at the tick,
//! the bus's health handled (stop sending, drop queued frames, reopen with backoff and send
//! safe stops at once, stay SAFE), and a status snapshot published for `handctl status`.
//!
//! The latches a restart must keep are published after every tick to the writer thread
//! ([`crate::persist`]: a store into an atomic word and a `try_send`, no file I/O in the
//! tick). A bus that is down when handd starts ([`Runner::with_bus_down`]) is waited for: SAFE
//! (EMG silence: nothing is heard), reopened with the same backoff, and once it carries
//! frames the hand recovers by the ordinary rule, with no `arm` (the hand never moved in this
//! process, so nothing is undone). [`Runner::shutdown`] sends the last round of safe stops on
//! SIGTERM and saves the latches.
//!
//! [`Runner::step`] does one tick at a given time, so tests drive it on a virtual clock;
//! [`Runner::run_realtime`] sleeps to each absolute deadline on the system clock.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::Receiver;
use std::sync::{Arc, Mutex, TryLockError};

use hand_clock::Clock;
use hand_dbc::CanFrame;

use crate::bus_load::BusLoad;
use crate::conditioner::{FingerGains, Setpoint};
use crate::engine::{AmpProblem, Command, Counters, Engine};
use crate::protocol::{LateTick, LATE_TICKS_KEPT};
use crate::safety::{Cause, DaemonState, Fault, FaultSet, FingerEvent};
use crate::stats::Percentiles;
use crate::transport::{BusHealth, ControllerState, Transport, TransportError};
use crate::units::{FINGER_NAMES, N_FINGERS};

/// EMG channels a snapshot holds (the bus's).
pub const SNAPSHOT_CHANNELS: usize = hand_dbc::emg::EMG_CHANNELS;
/// Ticks of per-channel RMS a snapshot keeps (one second at 50 ms a tick).
pub const RMS_HISTORY: usize = 20;

/// What `handctl status` and the live subscription show, copied out of the loop every tick
/// without allocating.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Snapshot {
    /// The tick's deadline, µs on the daemon's clock.
    pub t_us: u64,
    /// State.
    pub state: DaemonState,
    /// Faults in force.
    pub faults: FaultSet,
    /// Why the window could not drive the fingers at this tick (None: it could).
    pub window: Option<crate::engine::WindowProblem>,
    /// Counters since start.
    pub counters: Counters,
    /// Newest sample frame -> setpoints written.
    pub latency: Percentiles,
    /// Compute time per tick.
    pub compute: Percentiles,
    /// How late ticks started after their deadlines.
    pub lateness: Percentiles,
    /// Raw model labels.
    pub labels: [f64; N_FINGERS],
    /// Setpoints sent.
    pub setpoints: [Setpoint; N_FINGERS],
    /// Forces the controllers report.
    pub reported_force: [f64; N_FINGERS],
    /// Disabled fingers.
    pub disabled: [bool; N_FINGERS],
    /// Gains in force.
    pub gains: [FingerGains; N_FINGERS],
    /// Whether the bus is usable.
    pub bus_ok: bool,
    /// Joint angles the controllers report, rad.
    pub reported_position: [f64; N_FINGERS],
    /// Whether each finger's setpoint was ACTIVE mode.
    pub active: [bool; N_FINGERS],
    /// EMG channels in use (the first entries of `channel_rms_uv`).
    pub channels: usize,
    /// Per channel, the RMS feature the model last ran on, µV.
    pub channel_rms_uv: [f64; SNAPSHOT_CHANNELS],
    /// `channel_rms_uv` of the last [`RMS_HISTORY`] ticks (a ring, in no particular order):
    /// `arm` takes the live rest level from it ([`crate::rest_check`]) without waiting.
    pub rms_history: [[f64; SNAPSHOT_CHANNELS]; RMS_HISTORY],
    /// Entries of `rms_history` filled so far (at most [`RMS_HISTORY`]).
    pub rms_history_len: usize,
    /// The amplifier's last lead-off mask (bit c = channel c).
    pub lead_off_mask: u16,
    /// The amplifier's last saturation mask.
    pub saturation_mask: u16,
    /// Frames read from the bus since start.
    pub frames_rx: u64,
    /// Frames sent since start.
    pub frames_tx: u64,
    /// Worst-case bus load over the last second, fraction of the bit rate.
    pub bus_load: f64,
    /// Ticks whose snapshot was not published because a reader held it (the tick never
    /// waits for one): a measure of reader contention.
    pub publish_skips: u64,
    /// The CAN controller's error state and every bus error class, counted.
    pub bus: BusHealth,
    /// Each CiA 402 finger's drive: its node id and status (`None`: a native finger).
    pub drives: [Option<(u8, hand_canopen::DriveStatus)>; N_FINGERS],
    /// The last late ticks (a ring: entry `i % LATE_TICKS_KEPT` is the i-th late tick).
    pub late: [LateTick; LATE_TICKS_KEPT],
    /// Late ticks since start.
    pub late_count: u64,
}

impl Snapshot {
    /// The late ticks the ring holds, oldest first.
    pub fn late_ticks(&self) -> impl Iterator<Item = LateTick> + '_ {
        let kept = self.late_count.min(LATE_TICKS_KEPT as u64);
        (self.late_count - kept..self.late_count)
            .map(|i| self.late[(i % LATE_TICKS_KEPT as u64) as usize])
    }
}

impl Default for Snapshot {
    fn default() -> Self {
        Self {
            state: DaemonState::Boot,
            faults: FaultSet::default(),
            window: None,
            counters: Counters::default(),
            latency: Percentiles::default(),
            compute: Percentiles::default(),
            lateness: Percentiles::default(),
            labels: [0.0; N_FINGERS],
            setpoints: [Setpoint::default(); N_FINGERS],
            reported_force: [0.0; N_FINGERS],
            disabled: [false; N_FINGERS],
            gains: [FingerGains::default(); N_FINGERS],
            bus_ok: true,
            t_us: 0,
            reported_position: [0.0; N_FINGERS],
            active: [false; N_FINGERS],
            channels: 0,
            channel_rms_uv: [0.0; SNAPSHOT_CHANNELS],
            rms_history: [[0.0; SNAPSHOT_CHANNELS]; RMS_HISTORY],
            rms_history_len: 0,
            lead_off_mask: 0,
            saturation_mask: 0,
            frames_rx: 0,
            frames_tx: 0,
            bus_load: 0.0,
            publish_skips: 0,
            bus: BusHealth::default(),
            drives: [None; N_FINGERS],
            late: [LateTick::default(); LATE_TICKS_KEPT],
            late_count: 0,
        }
    }
}

/// The snapshot shared with the control threads. The tick only ever `try_lock`s it (a
/// reader holds it for a copy); readers copy it out and release it at once.
pub type SharedSnapshot = Arc<Mutex<Snapshot>>;

/// Most technicians' commands one tick applies; the rest wait for the next tick (the
/// control side's queue is bounded too, so a flood of commands cannot lengthen a tick).
pub const MAX_COMMANDS_PER_TICK: usize = 8;

/// First and longest wait between attempts to reopen a failed bus, µs. Short, because the
/// first frames after a reopen are the safe stops the finger controllers need within 100 ms;
/// capped at one 50 ms tick, because a failed attempt costs only a check of the interface.
pub const REOPEN_BACKOFF_US: (u64, u64) = (10_000, 50_000);

/// Longest wait before reopening a bus that failed again after a reopen before it took a
/// frame of ours (a controller still bus-off, or no one to ACK), µs. Such a loop would
/// otherwise spin, logging and starting a new setpoint epoch every 10 ms; this wait doubles
/// from [`REOPEN_BACKOFF_US`]'s first one at every such failure, up to this, and resets once
/// the bus has taken a tick's frames again (the safe stops sent at the reopen do not count:
/// the first of them is what fails on a controller that is still bus-off).
pub const SPIN_BACKOFF_MAX_US: u64 = 1_000_000;

/// A transmit queue that stays full this long raises [`Fault::BusDegraded`], µs: the finger
/// controllers brake by themselves after 150 ms without a setpoint anyway.
pub const QUEUE_FULL_FAULT_US: u64 = 150_000;

/// Between ticks the loop reads what the bus has brought this often, µs, so the read at a
/// tick's deadline finds at most this much of the bus instead of a whole period. Frames read
/// early go into the engine as they would at the deadline (each with its receive time, in
/// order; the tape records them in the same order), so what a tick computes is unchanged:
/// only when the reading is done moves. Issue 29: under the vcan flood drill (about 7,000
/// frames/s) a tick read 350 frames at its deadline, and under the emulator one tick started
/// 24.8 ms late of the drill's 25 ms slack.
pub const READ_EVERY_US: u64 = 10_000;

/// Repeated bus log lines (a failure, a reopen) are written at most once per this time, µs,
/// with the count of the ones left out: the log goes to an SD card, from the real-time loop.
pub const BUS_LOG_EVERY_US: u64 = 10_000_000;

/// Rate limit of a repeated log line.
#[derive(Debug, Clone, Copy, Default)]
struct LogLimit {
    last_us: Option<u64>,
    suppressed: u64,
}

impl LogLimit {
    /// `Some(left out since the last line)` when a line may be written now.
    fn allow(&mut self, now_us: u64) -> Option<u64> {
        if self.last_us.is_some_and(|l| now_us < l + BUS_LOG_EVERY_US) {
            self.suppressed += 1;
            return None;
        }
        self.last_us = Some(now_us);
        Some(std::mem::take(&mut self.suppressed))
    }
}

/// The loop.
pub struct Runner<T: Transport, K: Clock> {
    engine: Engine,
    transport: T,
    clock: K,
    tick_us: u64,
    next_deadline_us: u64,
    bus_ok: bool,
    backoff_us: u64,
    next_reopen_us: u64,
    /// When the loop next reads the bus between ticks ([`READ_EVERY_US`]).
    next_read_us: u64,
    commands: Option<Receiver<Command>>,
    snapshot: SharedSnapshot,
    last_tick_on_time: bool,
    /// A frame received after the deadline of the tick that read it, for the next tick.
    held: Option<(CanFrame, u64)>,
    frames_rx: u64,
    frames_tx: u64,
    bus_load: BusLoad,
    publish_skips: u64,
    /// Since when sends have been refused with a full queue (none since).
    queue_full_since: Option<u64>,
    /// Frames the transmit queue refused.
    tx_queue_full: u64,
    /// Reopen attempts that failed.
    reopen_failures: u64,
    /// A tick's frames were all taken since the last reopen (the bus carries our frames).
    carried: bool,
    /// The wait after a reopen that failed before it carried a frame (0: none such).
    spin_us: u64,
    failure_log: LogLimit,
    reopen_log: LogLimit,
    /// The amplifier's status problem last logged.
    amp_problem: Option<AmpProblem>,
    latches: Option<crate::persist::LatchPublisher>,
    /// The bus has not been open yet in this process (started with it down).
    never_opened: bool,
    /// The last ticks' per-channel RMS, for the snapshot ([`Snapshot::rms_history`]).
    rms_history: [[f64; SNAPSHOT_CHANNELS]; RMS_HISTORY],
    /// Ticks written into `rms_history` (its next slot is this modulo [`RMS_HISTORY`]).
    rms_ticks: usize,
    /// The last late ticks ([`Snapshot::late`]) and how many there were.
    late: [LateTick; LATE_TICKS_KEPT],
    late_count: u64,
    late_log: LogLimit,
    /// When the loop's last sleep ended (daemon clock, µs) and what the loop thread had used
    /// then: where a late tick's time went ([`LateTick::asleep_us`], [`LateTick::ran_us`],
    /// [`LateTick::waited`]). Zero outside [`Runner::run_realtime`].
    woke_us: u64,
    woke_usage: crate::rt::ThreadUsage,
}

impl<T: Transport, K: Clock> Runner<T, K> {
    /// A loop whose first tick is due one period from now.
    pub fn new(engine: Engine, transport: T, clock: K, tick_us: u64) -> Self {
        let now = clock.now_us();
        Self {
            engine,
            transport,
            clock,
            tick_us,
            next_deadline_us: now + tick_us,
            bus_ok: true,
            backoff_us: REOPEN_BACKOFF_US.0,
            next_reopen_us: 0,
            next_read_us: 0,
            commands: None,
            snapshot: Arc::new(Mutex::new(Snapshot::default())),
            last_tick_on_time: true,
            held: None,
            frames_rx: 0,
            frames_tx: 0,
            bus_load: BusLoad::new(tick_us),
            publish_skips: 0,
            queue_full_since: None,
            tx_queue_full: 0,
            reopen_failures: 0,
            carried: true,
            spin_us: 0,
            failure_log: LogLimit::default(),
            rms_history: [[0.0; SNAPSHOT_CHANNELS]; RMS_HISTORY],
            rms_ticks: 0,
            reopen_log: LogLimit::default(),
            amp_problem: None,
            latches: None,
            never_opened: false,
            late: [LateTick::default(); LATE_TICKS_KEPT],
            late_count: 0,
            woke_us: 0,
            woke_usage: crate::rt::ThreadUsage::default(),
            late_log: LogLimit::default(),
        }
    }

    /// The loop for a bus that could not be opened at start: SAFE at once (the engine hears
    /// no EMG), a reopen attempt at once and then with backoff. Nothing latches: once the bus
    /// carries frames the hand recovers after the usual recovery time.
    pub fn with_bus_down(mut self) -> Self {
        let now = self.clock.now_us();
        self.bus_ok = false;
        self.never_opened = true;
        self.next_reopen_us = now;
        self.engine.raise(now, Fault::EmgSilence);
        self
    }

    /// The latches are published to `publisher` after every tick (see [`crate::persist`]).
    pub fn with_latches(mut self, publisher: crate::persist::LatchPublisher) -> Self {
        self.latches = Some(publisher);
        self
    }

    /// Whether the bus is usable now.
    pub fn bus_ok(&self) -> bool {
        self.bus_ok
    }

    /// The last round before exit (SIGTERM): safe stops for every finger, each opening the
    /// finger's next epoch (so its controller retires the one it ran in), whatever the state, then the latches published and waited for on disk (up to
    /// `save_wait`). Returns the safe stops sent and whether the latches are saved (true when
    /// there is no latch file).
    pub fn shutdown(&mut self, save_wait: std::time::Duration) -> (usize, bool) {
        let mut sent = 0;
        if self.bus_ok {
            for f in self.engine.shutdown_frames() {
                match self.transport.send(f) {
                    Ok(()) => sent += 1,
                    Err(e) => {
                        tracing::warn!(error = %e, "shutdown: safe stops not all sent");
                        break;
                    }
                }
            }
            self.frames_tx += sent as u64;
        }
        let saved = match &mut self.latches {
            Some(p) => {
                p.publish(self.engine.latches());
                p.flush(save_wait)
            }
            None => true,
        };
        (sent, saved)
    }

    /// Commands from the control thread.
    pub fn with_commands(mut self, rx: Receiver<Command>) -> Self {
        self.set_commands(rx);
        self
    }

    /// Commands from the control thread (replacing any earlier channel).
    pub fn set_commands(&mut self, rx: Receiver<Command>) {
        self.commands = Some(rx);
    }

    /// The snapshot the loop publishes.
    pub fn snapshot(&self) -> SharedSnapshot {
        Arc::clone(&self.snapshot)
    }

    /// The engine (tests and the demo read it).
    pub fn engine(&self) -> &Engine {
        &self.engine
    }

    /// The transport (the long run reads the in-memory bus's overflow count).
    pub fn transport(&self) -> &T {
        &self.transport
    }

    /// Mutable access to the engine (to mark it validated, or to inject a fault in tests).
    pub fn engine_mut(&mut self) -> &mut Engine {
        &mut self.engine
    }

    /// When the next tick is due, µs.
    pub fn next_deadline_us(&self) -> u64 {
        self.next_deadline_us
    }

    /// Whether the last tick started on time (the watchdog is fed only then).
    pub fn last_tick_on_time(&self) -> bool {
        self.last_tick_on_time
    }

    /// The bus's health with the daemon's own counts.
    pub fn bus_health(&self) -> BusHealth {
        let mut h = self.transport.health();
        h.counters.tx_queue_full = self.tx_queue_full;
        h.counters.reopen_failures = self.reopen_failures;
        h
    }

    fn bus_failed(&mut self, now_us: u64, e: &TransportError) {
        let fault = match e {
            TransportError::BusOff => Fault::BusOff,
            _ => Fault::InterfaceDown,
        };
        if self.bus_ok {
            if let Some(left_out) = self.failure_log.allow(now_us) {
                tracing::error!(
                    error = %e,
                    left_out,
                    "bus failed: sending stops, queued setpoints dropped"
                );
            }
        }
        self.engine.raise(now_us, fault);
        self.transport.drop_queued();
        self.held = None;
        self.queue_full_since = None;
        if self.bus_ok {
            self.bus_ok = false;
            // A bus that failed again before it carried a frame since the last reopen: wait
            // longer before the next attempt (see SPIN_BACKOFF_MAX_US).
            self.spin_us = if self.carried {
                0
            } else {
                (self.spin_us * 2).clamp(REOPEN_BACKOFF_US.0, SPIN_BACKOFF_MAX_US)
            };
            self.backoff_us = REOPEN_BACKOFF_US.0;
            self.next_reopen_us = now_us + self.backoff_us.max(self.spin_us);
        }
    }

    /// A send the queue refused: counted; the next tick's setpoints replace it. Only a queue
    /// full for [`QUEUE_FULL_FAULT_US`] is a fault, and a transient one.
    fn queue_full(&mut self, now_us: u64) {
        self.tx_queue_full += 1;
        let since = *self.queue_full_since.get_or_insert(now_us);
        if now_us.saturating_sub(since) >= QUEUE_FULL_FAULT_US {
            self.engine.raise(now_us, Fault::BusDegraded);
        }
    }

    /// Reopen the bus if it failed and its backoff is over; true if it was reopened now.
    fn try_reopen(&mut self, now_us: u64) -> bool {
        if self.bus_ok || now_us < self.next_reopen_us {
            return false;
        }
        match self.transport.reopen() {
            Ok(()) if self.never_opened => {
                self.never_opened = false;
                tracing::warn!(
                    "bus up: the hand leaves SAFE once the signal is good for the recovery time"
                );
                self.bus_ok = true;
                true
            }
            Ok(()) => {
                // Frames of the old epoch may still be queued where we cannot purge them.
                self.engine.new_epoch();
                if let Some(left_out) = self.reopen_log.allow(now_us) {
                    tracing::warn!(
                        epochs = ?self.engine.epochs(),
                        left_out,
                        "bus reopened in a new setpoint epoch; the daemon stays SAFE until `handctl arm`"
                    );
                }
                self.bus_ok = true;
                self.carried = false;
                true
            }
            Err(e) => {
                self.reopen_failures += 1;
                self.backoff_us = (self.backoff_us * 2).min(REOPEN_BACKOFF_US.1);
                self.next_reopen_us = now_us + self.backoff_us;
                tracing::debug!(error = %e, retry_in_us = self.backoff_us, "bus reopen failed");
                false
            }
        }
    }

    /// When the loop must wake next: the next tick, an earlier read of the bus
    /// ([`READ_EVERY_US`]), or an earlier reopen attempt.
    pub fn next_wake_us(&self) -> u64 {
        if self.bus_ok {
            self.next_deadline_us.min(self.next_read_us)
        } else {
            self.next_deadline_us.min(self.next_reopen_us)
        }
    }

    /// Between ticks: read what the bus has brought so far ([`READ_EVERY_US`]); try to reopen
    /// a failed bus, and once it is back, send safe stops at once instead of waiting for the
    /// next tick (the finger controllers brake by themselves 150 ms after their last setpoint;
    /// this keeps the gap well inside that).
    pub fn service_bus(&mut self) {
        let now = self.clock.now_us();
        if self.bus_ok && now >= self.next_read_us && now < self.next_deadline_us {
            self.drain(now);
        }
        if !self.try_reopen(now) {
            return;
        }
        let mut failed = None;
        for f in self.engine.safe_stop_frames() {
            match self.transport.send(f) {
                Ok(()) => {}
                // The next tick sends them again.
                Err(TransportError::QueueFull) => {
                    self.tx_queue_full += 1;
                    break;
                }
                Err(e) => {
                    failed = Some(e);
                    break;
                }
            }
        }
        if let Some(e) = failed {
            let now = self.clock.now_us();
            self.bus_failed(now, &e);
        }
    }

    fn received(&mut self, frame: &CanFrame, rx_us: u64) {
        self.frames_rx += 1;
        self.bus_load.frame(frame);
        self.engine.on_frame(frame, rx_us);
        self.send_immediate();
    }

    /// What the engine answers at once (a CiA 402 drive's start-up, step by step at bus
    /// speed). A full queue drops the rest: that start-up step times out and names itself.
    fn send_immediate(&mut self) {
        let mut failed = None;
        for f in self.engine.take_immediate() {
            match self.transport.send(f) {
                Ok(()) => {
                    self.frames_tx += 1;
                    self.bus_load.frame(f);
                }
                Err(TransportError::QueueFull) => {
                    self.tx_queue_full += 1;
                    break;
                }
                Err(e) => {
                    failed = Some(e);
                    break;
                }
            }
        }
        if let Some(e) = failed {
            let now = self.clock.now_us();
            self.bus_failed(now, &e);
        }
    }

    /// Read every waiting frame received up to `until_us` (the tick's deadline; between ticks,
    /// now) into the engine. The first frame received after it is held back for the next
    /// tick, so what a tick computes depends on its deadline alone, not on how late it woke up.
    pub fn drain(&mut self, until_us: u64) {
        self.next_read_us = until_us + READ_EVERY_US;
        if !self.bus_ok {
            return;
        }
        if let Some((frame, rx_us)) = self.held {
            if rx_us > until_us {
                return;
            }
            self.held = None;
            self.received(&frame, rx_us);
        }
        loop {
            match self.transport.try_recv() {
                Ok(Some((frame, rx_us))) if rx_us > until_us => {
                    self.held = Some((frame, rx_us));
                    break;
                }
                Ok(Some((frame, rx_us))) => self.received(&frame, rx_us),
                Ok(None) => break,
                Err(e) => {
                    let now = self.clock.now_us();
                    self.bus_failed(now, &e);
                    break;
                }
            }
        }
    }

    /// A tick that starts a whole period or more after its deadline (the process was
    /// stopped, the board stalled) runs at the latest deadline that has passed, on
    /// everything received up to it, and the deadlines it missed are skipped. At its own
    /// deadline it would read a backlog that was fresh then and stale now, and send a force
    /// computed from the past as if it were current. At the latest deadline the window is
    /// what the bus carried up to now: complete and fresh, it drives the hand (a stall that
    /// lost nothing is no fault); with frames lost in the stall (the kernel's queue
    /// overflowed) or none received lately, it is invalid and the tick sends safe stops.
    fn skip_missed_deadlines(&mut self, now: u64) {
        if now >= self.next_deadline_us + self.tick_us {
            self.next_deadline_us += (now - self.next_deadline_us) / self.tick_us * self.tick_us;
        }
    }

    /// One tick: drain the bus, apply commands, run the engine, send its frames, publish the
    /// snapshot, and move the deadline on by one period (absolute, so there is no drift).
    pub fn step(&mut self) {
        let now = self.clock.now_us();
        self.skip_missed_deadlines(now);
        let deadline = self.next_deadline_us;
        let frames_before = self.frames_rx;
        self.try_reopen(now);
        self.drain(deadline);
        self.apply_commands(deadline);
        let t0 = self.clock.now_us();
        self.last_tick_on_time = self.engine.on_time(t0, deadline);
        if !self.last_tick_on_time {
            self.note_late(deadline, now, t0, self.frames_rx - frames_before);
        }
        // Error-passive: a transient fault while it lasts (the safe stops of this tick
        // already go out in SAFE).
        if self.bus_ok && self.transport.health().state == ControllerState::ErrorPassive {
            self.engine.raise(t0, Fault::BusDegraded);
        }
        let frames = self.engine.tick(deadline, t0);
        let mut failed = None;
        let mut refused = false;
        if self.bus_ok {
            for f in frames {
                match self.transport.send(f) {
                    Ok(()) => {
                        self.frames_tx += 1;
                        self.carried = true;
                        self.bus_load.frame(f);
                    }
                    // The queue is full: the rest of this tick's frames would be refused too.
                    Err(TransportError::QueueFull) => {
                        refused = true;
                        break;
                    }
                    Err(e) => {
                        failed = Some(e);
                        break;
                    }
                }
            }
        }
        self.bus_load.close_tick();
        let t1 = self.clock.now_us();
        if refused {
            self.queue_full(t1);
        } else if failed.is_none() {
            self.queue_full_since = None;
        }
        if let Some(e) = failed {
            self.bus_failed(t1, &e);
        }
        self.engine.written(t1, t1.saturating_sub(t0));
        self.log_events();
        self.log_amp_problem();
        self.publish(deadline);
        if let Some(p) = &mut self.latches {
            p.publish(self.engine.latches());
        }
        // A tick that ran past the next deadline: the next step skips what it missed.
        self.next_deadline_us += self.tick_us;
    }

    /// Logs the engine's state changes and finger events of this tick; an invalid window's
    /// reason is named on the state change it causes.
    fn log_events(&mut self) {
        let window = self.engine.window_problem();
        self.engine.drain_events(
            |t| match (t.cause, window) {
                (Cause::Fault(Fault::InvalidWindow), Some(w)) => tracing::info!(from = %t.from, to = %t.to, cause = %t.cause, window = %w, at_us = t.at_us, "state change"),
                _ => tracing::info!(from = %t.from, to = %t.to, cause = %t.cause, at_us = t.at_us, "state change"),
            },
            |e| match e {
                FingerEvent::Disabled(f) => tracing::warn!(finger = FINGER_NAMES[f], "finger controller silent: finger disabled"),
                FingerEvent::Enabled(f) => tracing::info!(finger = FINGER_NAMES[f], "finger controller back: finger enabled"),
            },
        );
    }

    /// Keeps where a late tick's time went (woken at `woke`, started at `started`, daemon
    /// clock), logged at most once per [`BUS_LOG_EVERY_US`] with the count left out.
    #[cold]
    fn note_late(&mut self, deadline: u64, woke: u64, started: u64, frames: u64) {
        let since_deadline = self.clock.now_us().saturating_sub(deadline);
        let lateness = started.saturating_sub(deadline);
        let used = if self.woke_us == 0 {
            crate::rt::ThreadUsage::default()
        } else {
            crate::rt::ThreadUsage::now().since(self.woke_usage)
        };
        let late = LateTick {
            deadline_mono_us: crate::rt::monotonic_us().saturating_sub(since_deadline),
            wake_us: woke.saturating_sub(deadline),
            read_us: started.saturating_sub(woke.max(deadline)),
            frames,
            cpu: crate::rt::current_cpu(),
            asleep_us: self.woke_us.saturating_sub(deadline).min(lateness),
            ran_us: used.cpu_us,
            waited: used.waited.min(u64::from(u32::MAX)) as u32,
            preempted: used.preempted.min(u64::from(u32::MAX)) as u32,
        };
        self.late[(self.late_count % LATE_TICKS_KEPT as u64) as usize] = late;
        self.late_count += 1;
        if let Some(left_out) = self.late_log.allow(started) {
            tracing::warn!(
                late_us = late.lateness_us(),
                woke_us = late.wake_us,
                read_us = late.read_us,
                asleep_us = late.asleep_us,
                ran_us = late.ran_us,
                waited = late.waited,
                preempted = late.preempted,
                frames,
                cpu = late.cpu,
                left_out,
                "tick started late: woke after its deadline, then read the bus"
            );
        }
    }

    /// Names a change of what the amplifier's status says (logged once per change, not per
    /// tick).
    fn log_amp_problem(&mut self) {
        let now = self.engine.amp_problem();
        if now == self.amp_problem {
            return;
        }
        match now {
            Some(p) => {
                tracing::warn!(problem = %p, "amplifier: its samples cannot drive the hand (signal_quality)")
            }
            None => tracing::info!("amplifier: status good again"),
        }
        self.amp_problem = now;
    }

    /// At most [`MAX_COMMANDS_PER_TICK`] waiting commands, at the tick's deadline.
    fn apply_commands(&mut self, deadline: u64) {
        let Some(rx) = &self.commands else { return };
        for _ in 0..MAX_COMMANDS_PER_TICK {
            let Ok(cmd) = rx.try_recv() else { break };
            if let Err(e) = self.engine.command(deadline, cmd) {
                tracing::warn!(error = %e, "command refused");
            }
        }
    }

    /// Copies the tick's figures into the shared snapshot, if no reader holds it (the tick
    /// never waits: a skipped tick is counted and the next one publishes).
    fn publish(&mut self, deadline: u64) {
        let e = &self.engine;
        let features = e.model_features();
        let per = decoder::dsp::FEATURES_PER_CHANNEL;
        let channels = e.n_channels().min(SNAPSHOT_CHANNELS);
        let (lead_off_mask, saturation_mask) = e.amp_masks();
        // RMS is the first feature of each channel (decoder::dsp::FEATURE_NAMES).
        let channel_rms_uv: [f64; SNAPSHOT_CHANNELS] = std::array::from_fn(|c| {
            if c < channels {
                features.get(c * per).copied().unwrap_or(0.0)
            } else {
                0.0
            }
        });
        self.rms_history[self.rms_ticks % RMS_HISTORY] = channel_rms_uv;
        self.rms_ticks = self.rms_ticks.wrapping_add(1);
        let snap = Snapshot {
            t_us: deadline,
            state: e.state(),
            faults: e.faults(),
            window: e.window_problem(),
            counters: e.counters(),
            latency: e.latency().summary(),
            compute: e.compute().summary(),
            lateness: e.lateness().summary(),
            labels: *e.labels(),
            setpoints: *e.setpoints(),
            reported_force: *e.reported_force(),
            disabled: std::array::from_fn(|f| e.finger_disabled(f)),
            gains: *e.gains(),
            bus_ok: self.bus_ok,
            reported_position: *e.reported_position(),
            active: std::array::from_fn(|f| e.finger_active(f)),
            channels,
            channel_rms_uv,
            rms_history: self.rms_history,
            rms_history_len: self.rms_ticks.min(RMS_HISTORY),
            lead_off_mask,
            saturation_mask,
            frames_rx: self.frames_rx,
            frames_tx: self.frames_tx,
            bus_load: self.bus_load.load(),
            publish_skips: self.publish_skips,
            bus: self.bus_health(),
            drives: std::array::from_fn(|f| e.drive(f)),
            late: self.late,
            late_count: self.late_count,
        };
        match self.snapshot.try_lock() {
            Ok(mut s) => *s = snap,
            // A reader that panicked cannot have left a half-written copy: take it over.
            Err(TryLockError::Poisoned(p)) => *p.into_inner() = snap,
            Err(TryLockError::WouldBlock) => self.publish_skips += 1,
        }
    }

    /// Run on the system clock until `stop` is set, sleeping to each absolute deadline; calls
    /// `on_tick` after every tick (the daemon feeds the systemd watchdog there).
    pub fn run_realtime(&mut self, stop: &AtomicBool, mut on_tick: impl FnMut(&Self)) {
        while !stop.load(Ordering::Relaxed) {
            let now = self.clock.now_us();
            let wake = self.next_wake_us();
            if wake > now {
                std::thread::sleep(std::time::Duration::from_micros(wake - now));
                self.woke_us = self.clock.now_us();
                self.woke_usage = crate::rt::ThreadUsage::now();
            }
            if self.clock.now_us() < self.next_deadline_us {
                self.service_bus();
                continue;
            }
            self.step();
            on_tick(self);
        }
    }
}
