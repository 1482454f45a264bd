//! handd's side of the setpoint epoch (hand.dbc, FINGER_SETPOINT's `Epoch`): no stale
//! setpoint can move a finger, and one finger's fault stays its own.
//!
//! Every setpoint carries its finger's current epoch: handd keeps one epoch per finger. The
//! engine starts every finger at a fresh, unpredictable epoch ([`fresh_epoch`]) and moves
//! *every* finger to its next one (+1, wrapping) on every change of state into SAFE, on every
//! bus recovery (the daemon calls [`super::Engine::new_epoch`] after a reopen) and in the last
//! round before exit ([`super::Engine::shutdown_frames`]), but only finger f
//! when finger f's controller reports that it braked by itself (FINGER_STATUS BRAKED with the
//! setpoint-timeout bit, on the report's rising edge): that controller retired its epoch, the
//! others did not, and they keep their force. In each of its epochs a finger gets a SAFE_STOP
//! before anything else: the controller opens an epoch only on a SAFE_STOP,
//! and ignores every setpoint of another epoch, so frames of an older epoch still queued in the
//! kernel or in a CAN controller's mailboxes cannot move the finger once the new epoch's
//! SAFE_STOP has reached it.

use std::hash::{BuildHasher, Hasher};

use hand_dbc::messages::FingerMode;

use crate::units::N_FINGERS;

/// An epoch no earlier run can predict: from the process's random hash keys (the standard
/// library seeds them from the operating system's random source) and the wall clock.
pub fn fresh_epoch() -> u16 {
    let mut h = std::collections::hash_map::RandomState::new().build_hasher();
    let now = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_nanos())
        .unwrap_or(0);
    h.write_u128(now);
    let x = h.finish();
    (x ^ (x >> 16) ^ (x >> 32) ^ (x >> 48)) as u16
}

/// Each finger's current epoch and whether it was opened.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Epochs {
    epoch: [u16; N_FINGERS],
    /// Finger f got a SAFE_STOP of its current epoch.
    opened: [bool; N_FINGERS],
    /// Finger f's last status said it braked by itself.
    self_braked: [bool; N_FINGERS],
    /// Epochs begun since start, per finger, the first included.
    begun: [u64; N_FINGERS],
}

impl Epochs {
    pub(super) fn new(epochs: [u16; N_FINGERS]) -> Self {
        Self {
            epoch: epochs,
            opened: [false; N_FINGERS],
            self_braked: [false; N_FINGERS],
            begun: [1; N_FINGERS],
        }
    }

    /// The epoch finger `f`'s setpoints carry now.
    pub(super) fn current(&self, f: usize) -> u16 {
        self.epoch[f]
    }

    /// Every finger's epoch now.
    pub(super) fn all(&self) -> [u16; N_FINGERS] {
        self.epoch
    }

    /// Epochs finger `f` began since start.
    pub(super) fn begun(&self, f: usize) -> u64 {
        self.begun[f]
    }

    /// Starts `epoch` for finger `f`: it has not had its SAFE_STOP yet.
    pub(super) fn begin(&mut self, f: usize, epoch: u16) {
        self.epoch[f] = epoch;
        self.opened[f] = false;
        self.begun[f] += 1;
    }

    /// Starts finger `f`'s next epoch.
    pub(super) fn next_for(&mut self, f: usize) {
        self.begin(f, self.epoch[f].wrapping_add(1));
    }

    /// Starts every finger's next epoch.
    pub(super) fn next(&mut self) {
        for f in 0..N_FINGERS {
            self.next_for(f);
        }
    }

    /// The mode to send finger `f` when the engine wants `wanted`: a SAFE_STOP in place of
    /// anything else until the finger got one in its epoch. DISABLED too: a controller that
    /// handd cannot hear may still hear handd, and it must leave its old epoch.
    /// And SAFE_STOP again while the finger's last status says it braked by itself: the
    /// SAFE_STOP that opened the epoch may have been lost on the way (the controller then stays
    /// braked and ignores everything else), so it is repeated until the controller reports
    /// that it took it.
    pub(super) fn mode(&mut self, f: usize, wanted: FingerMode) -> FingerMode {
        if self.opened[f] && !self.self_braked[f] {
            return wanted;
        }
        self.opened[f] = true;
        FingerMode::SafeStop
    }

    /// Finger `f` reported its state: true when it newly says it braked by itself, which
    /// calls for a new epoch for that finger (it retired its current one).
    pub(super) fn on_status(&mut self, f: usize, braked_by_itself: bool) -> bool {
        let rising = braked_by_itself && !self.self_braked[f];
        self.self_braked[f] = braked_by_itself;
        rising
    }
}

/// Five fresh epochs, one per finger.
pub fn fresh_epochs() -> [u16; N_FINGERS] {
    std::array::from_fn(|_| fresh_epoch())
}

#[cfg(test)]
mod tests {
    use super::*;
    use FingerMode::{Active, Disabled, Hold, SafeStop};

    #[test]
    fn each_epoch_opens_every_finger_with_a_safe_stop_first() {
        let mut e = Epochs::new([65535; N_FINGERS]);
        for f in 0..N_FINGERS {
            assert_eq!(
                e.mode(f, Active),
                SafeStop,
                "finger {f}: first frame of the epoch"
            );
            assert_eq!(e.mode(f, Active), Active);
            assert_eq!(e.mode(f, Hold), Hold);
        }
        e.next();
        assert_eq!(e.all(), [0; N_FINGERS], "wraps");
        assert_eq!(e.begun(3), 2);
        assert_eq!(
            e.mode(1, Disabled),
            SafeStop,
            "DISABLED opens with a stop too"
        );
        assert_eq!(e.mode(1, Disabled), Disabled);
        assert_eq!(e.mode(1, Hold), Hold);
        assert_eq!(e.mode(2, SafeStop), SafeStop);
        assert_eq!(
            e.mode(2, Active),
            Active,
            "opened by the stop the engine wanted"
        );
    }

    #[test]
    fn only_the_rising_edge_of_a_self_brake_report_calls_for_a_new_epoch() {
        let mut e = Epochs::new([3; N_FINGERS]);
        assert!(!e.on_status(0, false));
        assert!(e.on_status(0, true));
        assert!(!e.on_status(0, true), "the same brake, reported again");
        assert!(e.on_status(1, true), "another finger");
        assert!(!e.on_status(0, false));
        assert!(e.on_status(0, true), "a new brake");
    }

    #[test]
    fn a_fingers_own_epoch_moves_alone() {
        let mut e = Epochs::new([10, 20, 30, 40, 50]);
        for f in 0..N_FINGERS {
            e.mode(f, Active);
        }
        e.next_for(2);
        assert_eq!(e.all(), [10, 20, 31, 40, 50]);
        assert_eq!((e.begun(2), e.begun(1)), (2, 1));
        for f in [0, 1, 3, 4] {
            assert_eq!(e.mode(f, Active), Active, "finger {f} keeps its epoch open");
        }
        assert_eq!(e.mode(2, Active), SafeStop, "only finger 2 is reopened");
        assert_eq!(e.mode(2, Active), Active);
    }

    #[test]
    fn a_finger_that_still_reports_its_self_brake_keeps_getting_safe_stops() {
        let mut e = Epochs::new([7; N_FINGERS]);
        assert!(e.on_status(4, true));
        e.next_for(4);
        // The opening SAFE_STOP was lost: the controller still reports its self-brake.
        assert_eq!(e.mode(4, Active), SafeStop);
        assert!(!e.on_status(4, true));
        assert_eq!(e.mode(4, Active), SafeStop, "repeated while braked");
        // It took one: SAFE_STOP state, no longer braked by itself.
        assert!(!e.on_status(4, false));
        assert_eq!(e.mode(4, Active), Active);
    }

    #[test]
    fn fresh_epochs_differ_between_draws() {
        // 8 draws of 16 bits all equal by chance: probability 2^-112.
        let draws: Vec<u16> = (0..8).map(|_| fresh_epoch()).collect();
        assert!(draws.iter().any(|&d| d != draws[0]), "{draws:?}");
    }
}
