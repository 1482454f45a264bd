//! A technician's `handctl arm` in the drills, and when ACTIVE setpoints may come back after it.
//!
//! Arming clears the latched faults and restarts the recovery time: the hand moves only after
//! a full good period (500 ms) from the tick that applied the command. handd answers `arm` as
//! soon as the command is queued for its loop, so two instants bound that tick: the start of
//! `handctl` (it cannot be earlier) and handd's answer (it is at most one tick later). The bars
//! are measured from those two, so the time a process takes to start under emulation (which
//! varies with the host: a slower CI machine once took handctl's start past the old 900 ms bar
//! measured from the start) is not counted against the daemon.

use std::path::Path;

use handstack_tests::vcan::monitor::now_us;
use handstack_tests::vcan::procs::handctl;
use handstack_tests::vcan::stream_breaks::{
    stalled_within, GAP_LIMIT_US, MAX_EXCUSED_SILENCE_US, STALL_MIN_US,
};
use handstack_tests::vcan::{Seen, VcanEnv};

/// Arming restarts the recovery time, so ACTIVE setpoints come back no sooner than this after
/// `handctl arm` was started...
pub(super) const ARM_MIN_US: u64 = 500_000;
/// ... and no later than this after handd answered it: the tick that applies the command (at
/// most one 50 ms period, plus that tick's lateness under emulation), the 500 ms recovery
/// time, the tick that sees it complete and sends, and the setpoint's way to the monitor.
pub(super) const ARM_BAR_US: u64 = 750_000;

/// When one `handctl arm` ran.
#[derive(Debug, Clone, Copy)]
pub(super) struct Armed {
    /// Just before handctl was started.
    pub(super) sent_us: u64,
    /// Just after handctl exited with handd's answer.
    pub(super) answered_us: u64,
}

impl Armed {
    /// Runs `run` (a `handctl arm` that returns once handd answered) and times it.
    pub(super) fn time(run: impl FnOnce()) -> Self {
        let sent_us = now_us();
        run();
        Self {
            sent_us,
            answered_us: now_us(),
        }
    }

    /// `handctl arm --force-rest-mismatch` on `socket` (the sine patient moves from its first
    /// sample, never at rest: the rest check before arm is overridden, as a technician would,
    /// audited).
    pub(super) fn now(env: &VcanEnv, socket: &Path) -> Self {
        let sock = socket.display().to_string();
        Self::time(|| {
            handctl(env, &["arm", "--force-rest-mismatch", "--socket", &sock]);
        })
    }

    /// Asserts that the first ACTIVE setpoint after the arm (`resumed_us`) came by the recovery
    /// rule: not before the recovery time, not later than [`ARM_BAR_US`] after the answer.
    /// Prints both intervals under `what`.
    ///
    /// The bar counts the time the simulated world ran (`seen`, the bus): where the amplifier's
    /// frames stood still in between (the guest stalled: `stream_breaks`), that time is taken
    /// out, and a silence over the gap limit restarts the recovery time as handd must, so the
    /// bar then runs from its end. Both are printed.
    pub(super) fn check(&self, what: &str, resumed_us: u64, seen: &[Seen]) {
        let after_sent = resumed_us as i64 - self.sent_us as i64;
        let (silences, _) = stalled_within(seen, self.answered_us, resumed_us);
        let restart = silences
            .iter()
            .filter(|s| s.len_us() > GAP_LIMIT_US && s.len_us() <= MAX_EXCUSED_SILENCE_US)
            .map(|s| s.to_us)
            .max();
        let from = restart.unwrap_or(self.answered_us);
        let (_, stalled) = stalled_within(seen, from, resumed_us);
        let after_answer = resumed_us as i64 - from as i64 - stalled as i64;
        println!(
            "{what}: ACTIVE again {:.1} ms after `handctl arm` started, {:.1} ms after handd \
             answered it ({:.1} ms to answer); the amplifier's frames stood still {:.1} ms of it \
             ({} silences over {} ms{}), so {:.1} ms against the bar",
            after_sent as f64 * 1e-3,
            (resumed_us as i64 - self.answered_us as i64) as f64 * 1e-3,
            (self.answered_us - self.sent_us) as f64 * 1e-3,
            silences.iter().map(|s| s.len_us()).sum::<u64>() as f64 * 1e-3,
            silences.len(),
            STALL_MIN_US / 1000,
            restart.map_or(String::new(), |t| format!(
                "; one over the gap limit restarted the recovery, {:.1} ms after the answer",
                (t - self.answered_us) as f64 * 1e-3
            )),
            after_answer as f64 * 1e-3
        );
        assert!(
            after_sent >= ARM_MIN_US as i64,
            "{what}: ACTIVE {after_sent} us after `handctl arm` started: sooner than the \
             {ARM_MIN_US} us recovery time it restarts"
        );
        assert!(
            after_answer <= ARM_BAR_US as i64,
            "{what}: ACTIVE {after_answer} us after handd answered `handctl arm` (bar \
             {ARM_BAR_US} us)"
        );
    }
}
