//! The transmit side: the frames one tick (or a safe stop) sends, built into a fixed buffer.

use hand_dbc::e2e::E2eProtector;
use hand_dbc::messages::{
    DaemonState as BusState, FingerMode, FingerSetpoint, HandDiag, HandHeartbeat,
};
use hand_dbc::CanFrame;

use super::{Engine, MAX_TX_PER_TICK};
use crate::conditioner::Setpoint;
use crate::safety::DaemonState;
use crate::tape::Entry;
use crate::units::N_FINGERS;

/// The outgoing frames and the E2E state of the protected ones.
#[derive(Clone)]
pub(super) struct Tx {
    setpoint: [E2eProtector; N_FINGERS],
    heartbeat: E2eProtector,
    frames: [CanFrame; MAX_TX_PER_TICK],
    len: usize,
}

impl Tx {
    pub(super) fn new() -> Self {
        Self {
            setpoint: FingerSetpoint::E2E.map(E2eProtector::new),
            heartbeat: E2eProtector::new(HandHeartbeat::E2E),
            frames: [CanFrame::new_standard(0, &[]).expect("an empty frame is valid");
                MAX_TX_PER_TICK],
            len: 0,
        }
    }

    fn clear(&mut self) {
        self.len = 0;
    }

    fn push(&mut self, frame: Option<CanFrame>) {
        if let Some(frame) = frame {
            // MAX_TX_PER_TICK covers every tick; never a panic on the tick path.
            if self.len < MAX_TX_PER_TICK {
                self.frames[self.len] = frame;
                self.len += 1;
            }
        }
    }

    /// The frames built since the last clear.
    pub(super) fn frames(&self) -> &[CanFrame] {
        &self.frames[..self.len]
    }

    /// The one setpoint-frame builder: finger `f`'s setpoint in `mode` and `epoch`,
    /// E2E-protected; a setpoint the codec refuses becomes a safe stop (never happens with a
    /// validated config).
    fn setpoint(&mut self, f: usize, mode: FingerMode, sp: &Setpoint, epoch: u16) {
        let frame = FingerSetpoint::new(f, mode, sp.force.0, sp.velocity.0, epoch)
            .or_else(|_| FingerSetpoint::new(f, FingerMode::SafeStop, 0.0, 0.0, epoch))
            .ok()
            .and_then(|m| self.setpoint[f].protect_message(&m).ok());
        self.push(frame);
    }
}

/// A total since start as HAND_DIAG carries it: modulo 256, a wrapping total (see hand.dbc),
/// so a tool sees every increment by differencing, even across lost HAND_DIAG frames.
fn wrapping_u8(total: u64) -> u8 {
    (total % 256) as u8
}

impl Engine {
    /// Conditions the labels into setpoints (or stops the fingers) and builds their frames,
    /// each in its finger's epoch: a finger not yet sent a SAFE_STOP in it gets one first.
    ///
    /// A finger that is not driven gets SAFE_STOP (zero force, zero velocity, brake), whether
    /// the outputs are off or its controller fell silent: never DISABLED, which hand.dbc
    /// defines as motor off without a brake (a finger that handd cannot hear may still hear it,
    /// and must brake, not go limp).
    pub(super) fn build_setpoints(&mut self, running: bool) {
        let dt_s = self.settings.tick_us as f64 * 1e-6;
        for f in 0..N_FINGERS {
            if self.drives.as_ref().is_some_and(|d| d.has(f)) {
                self.build_drive_setpoint(f, running, dt_s);
                continue;
            }
            let wanted = if running && !self.watch.is_disabled(f) {
                FingerMode::Active
            } else {
                FingerMode::SafeStop
            };
            let mode = self.epochs.mode(f, wanted);
            if mode == FingerMode::Active {
                let gains = &self.settings.gains[f];
                let feedback = self.inputs.feedback[f];
                self.setpoints[f] =
                    self.conditioners[f].step(self.labels[f], gains, dt_s, feedback);
            } else {
                self.conditioners[f].reset();
                self.setpoints[f] = Setpoint::default();
            }
            self.tx
                .setpoint(f, mode, &self.setpoints[f], self.epochs.current(f));
        }
    }

    /// A CiA 402 finger's setpoint, as its drive's target (its RPDO1 leaves with the bank's
    /// frames). It is conditioned only while the drive follows its target, so a drive walked
    /// back to Operation enabled starts from rest; until then its target is 0.
    fn build_drive_setpoint(&mut self, f: usize, running: bool, dt_s: f64) {
        let Some(d) = self.drives.as_mut() else {
            return;
        };
        if running && d.ready(f) {
            if d.enabled(f) {
                let gains = &self.settings.gains[f];
                let feedback = crate::conditioner::Feedback {
                    at_joint_limit: d.at_limit(f),
                };
                self.setpoints[f] =
                    self.conditioners[f].step(self.labels[f], gains, dt_s, feedback);
            } else {
                self.conditioners[f].reset();
                self.setpoints[f] = Setpoint::default();
            }
            d.set_target(f, Some(&self.setpoints[f]));
        } else {
            self.conditioners[f].reset();
            self.setpoints[f] = Setpoint::default();
            d.set_target(f, None);
        }
    }

    /// The CiA 402 drives' frames of the tick: RPDO1 per drive, SYNC, heartbeat.
    fn build_drive_frames(&mut self, now_us: u64) {
        if let Some(d) = &mut self.drives {
            let tx = &mut self.tx;
            d.tick(now_us, |f| tx.push(Some(f)));
        }
    }

    /// Every CiA 402 drive's quick stop with its target zeroed, and the SYNC that applies it.
    fn build_drive_stops(&mut self) {
        if let Some(d) = &mut self.drives {
            let tx = &mut self.tx;
            d.stop_frames(|f| tx.push(Some(f)));
        }
    }

    /// HAND_DIAG: latency, counters, the shown labels and the newest sample's counter.
    pub(super) fn build_diag(&mut self, running: bool) {
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
        let diag = HandDiag::new(
            self.timing.last_latency_us.min(u64::from(u16::MAX)) as u16,
            wrapping_u8(self.counters.deadline_misses),
            wrapping_u8(self.counters.samples_lost),
            shown(0),
            shown(1),
            shown(2),
            shown(3),
            shown(4),
            self.timing.last_newest_counter % 4,
        );
        self.tx.push(diag.ok().map(|d| d.to_frame()));
    }

    /// HAND_HEARTBEAT, every other tick: state, faults and model id.
    pub(super) fn build_heartbeat(&mut self) {
        if self.counters.ticks.is_multiple_of(2) {
            return;
        }
        let state = match self.safety.state() {
            DaemonState::Boot => BusState::Boot,
            DaemonState::Ready => BusState::Ready,
            DaemonState::Running => BusState::Running,
            DaemonState::Safe => BusState::Safe,
        };
        let frame = HandHeartbeat::new(state, self.safety.faults().0, self.settings.model_id)
            .ok()
            .and_then(|m| self.tx.heartbeat.protect_message(&m).ok());
        self.tx.push(frame);
    }

    /// The tick's frames, built anew: setpoints, HAND_DIAG, HAND_HEARTBEAT.
    pub(super) fn transmit(&mut self, now_us: u64) -> &[CanFrame] {
        self.tx.clear();
        let running = self.safety.outputs_enabled();
        self.build_setpoints(running);
        self.build_drive_frames(now_us);
        self.build_diag(running);
        self.build_heartbeat();
        self.tx.frames()
    }

    /// Safe-stop setpoints for every finger, E2E-protected, to
    /// send at once when the bus comes back after a failure rather than at the next tick. Only
    /// when the outputs are not enabled (a bus failure latches SAFE); otherwise nothing, as the
    /// next tick carries the running setpoints. No allocation.
    pub fn safe_stop_frames(&mut self) -> &[CanFrame] {
        self.record(Entry::SafeStops);
        self.tx.clear();
        if !self.safety.outputs_enabled() {
            self.build_setpoints(false);
            self.build_drive_stops();
        }
        self.record_out()
    }

    /// Safe-stop setpoints for every finger, each opening the finger's next epoch, whatever
    /// the state: the last round handd sends before it exits (SIGTERM), so no finger keeps an
    /// ACTIVE setpoint until its controller's own timeout. The new epoch retires the one the
    /// fingers ran in at once: until the next process's first SAFE_STOP, a stale ACTIVE
    /// setpoint of it (a queued frame, a replay) is ignored, where a safe stop in the running
    /// epoch would leave the controller bound to it for the rest of its 150 ms timeout.
    /// Changes no latch. No allocation.
    pub fn shutdown_frames(&mut self) -> &[CanFrame] {
        self.record(Entry::Shutdown);
        self.tx.clear();
        self.epochs.next();
        self.build_setpoints(false);
        self.build_drive_stops();
        self.record_out()
    }
}

#[cfg(test)]
mod tests {
    use hand_dbc::messages::HandDiag;
    use hand_dbc::CanFrame;

    use crate::engine::{Engine, EngineSettings};

    /// An engine in READY with a random model: no EMG ever comes, so the model never runs.
    fn engine() -> Engine {
        crate::engine::test_support::validated_engine(1)
    }

    fn diag(frames: &[CanFrame]) -> HandDiag {
        let frame = frames
            .iter()
            .find(|f| f.raw_id() == HandDiag::ID)
            .expect("every tick sends HAND_DIAG");
        HandDiag::decode(frame.data()).expect("HAND_DIAG decodes")
    }

    /// hand.dbc: DeadlineMisses and EmgSamplesLost are totals since start modulo 256.
    #[test]
    fn hand_diag_counters_are_totals_since_start_modulo_256() {
        let mut e = engine();
        let late = EngineSettings::default().deadline_slack_us + 1;
        for n in 1..=300u64 {
            let deadline = n * 50_000;
            let d = diag(e.tick(deadline, deadline + late));
            assert_eq!(
                u64::from(d.deadline_misses()),
                n % 256,
                "DeadlineMisses after {n} misses"
            );
        }
        let d = diag(e.tick(301 * 50_000, 301 * 50_000));
        assert_eq!(d.deadline_misses(), 44, "an on-time tick adds nothing");
        assert_eq!(e.counters().deadline_misses, 300, "the full count");

        // Losing samples takes an EMG stream with gaps; the counter it feeds is set directly.
        for (lost, expected) in [(255, 255), (256, 0), (511, 255), (600, 88)] {
            e.counters.samples_lost = lost;
            let d = diag(e.transmit(0));
            assert_eq!(d.emg_samples_lost(), expected, "{lost} samples lost");
        }
    }
}
