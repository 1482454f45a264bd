//! The deciding side's first half: which faults hold at this tick, and whether the window may
//! drive the fingers.

use super::rx::{AmpProblem, AMP_STATUS_SILENCE_US};
use super::Engine;
use crate::safety::{DaemonState, Fault};
use crate::units::N_FINGERS;

/// Railed channel values per tick (all channels) that make the signal unusable: a clipped
/// channel puts one per sample, so 50 ms of one clipped channel gives about 50.
const RAIL_LIMIT: u64 = 5;

impl Engine {
    /// Raises the faults of the tick at `now_us` (EMG silence, signal quality, non-finite
    /// samples, an invalid window) and returns whether the window is valid.
    pub(super) fn evaluate_faults(&mut self, now_us: u64) -> bool {
        if now_us.saturating_sub(self.emg.last_emg_us) > self.settings.emg_silence_us {
            self.fault(now_us, Fault::EmgSilence);
        }
        // The amplifier's status fell silent: its last lead-off and saturation flags are stale,
        // and nothing says the amplifier still runs as the chain expects.
        if now_us.saturating_sub(self.inputs.last_amp_status_us) > AMP_STATUS_SILENCE_US {
            self.inputs.amp_problem = Some(AmpProblem::Silent);
            self.inputs.amp_reports_bad = true;
        }
        if self.emg.take_railed() >= RAIL_LIMIT || self.inputs.amp_reports_bad {
            self.fault(now_us, Fault::SignalQuality);
        }
        let check = self
            .emg
            .window_check(now_us, self.settings.tick_us, self.settings.max_gap_us);
        self.window_problem = check.err();
        let valid = check.is_ok();
        if self.emg.chain.faults().any_in_window() {
            self.fault(now_us, Fault::NonFinite);
        } else if !valid
            && matches!(
                self.safety.state(),
                DaemonState::Running | DaemonState::Safe
            )
        {
            // Raised in SAFE too: the recovery time counts from the first valid window.
            self.fault(now_us, Fault::InvalidWindow);
        }
        valid
    }

    /// The finger watchdog at `now_us`; its events are kept for [`Engine::drain_events`].
    pub(super) fn update_watch(&mut self, now_us: u64) {
        // A CiA 402 finger is heard while its drive runs with no latched fault; its force is
        // the drive's torque actual, scaled back.
        if let Some(d) = &self.drives {
            for f in 0..N_FINGERS {
                if !d.has(f) {
                    continue;
                }
                if d.ready(f) {
                    self.watch.heard(f, now_us);
                }
                self.inputs.reported_force[f] = d.force_n(f).unwrap_or(0.0);
            }
        }
        let mut events = [None; N_FINGERS];
        let mut k = 0;
        self.watch.update(now_us, |e| {
            events[k] = Some(e);
            k += 1;
        });
        self.finger_events = events;
    }
}
