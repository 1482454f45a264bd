//! The motor controller's setpoint-epoch rule (hand.dbc, FINGER_SETPOINT's `Epoch`): no stale
//! setpoint can move a finger.
//!
//! The controller is bound to at most one epoch and remembers the last one it left (the
//! retired epoch). For every setpoint that passed the E2E check:
//!
//! - a SAFE_STOP of the bound epoch is followed; a SAFE_STOP of any other epoch that is not the
//!   retired one is followed and binds the controller to its epoch, retiring the bound one;
//! - every other mode (ACTIVE, HOLD, DISABLED) is followed only in the bound epoch;
//! - everything else (any setpoint of the retired epoch, a non-stop setpoint of an epoch other
//!   than the bound one, anything before the first SAFE_STOP) is ignored and counted: it does
//!   not change the command nor feed the setpoint watchdog.
//!
//! At power-up the controller is bound to none and has retired none. When it brakes by itself
//! (setpoint timeout) or on a HAND_ESTOP STOP it retires its epoch and is bound to none: it moves again only after a
//! SAFE_STOP of a new epoch. Epochs are compared for equality only, so their counter wraps
//! freely (handd steps it by one modulo 2^16).

use hand_dbc::messages::FingerMode;

/// What the gate says of one setpoint.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Verdict {
    /// Follow it (and the controller is now bound to its epoch).
    Follow,
    /// Ignore it: stale, or not yet opened by a SAFE_STOP.
    Ignore,
}

/// The epoch state of one motor controller.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct EpochGate {
    bound: Option<u16>,
    retired: Option<u16>,
    ignored: u64,
}

impl EpochGate {
    /// A controller at power-up: bound to no epoch.
    pub fn new() -> Self {
        Self::default()
    }

    /// The epoch the controller follows, if any.
    pub fn bound(&self) -> Option<u16> {
        self.bound
    }

    /// The epoch it left last, whose setpoints it ignores.
    pub fn retired(&self) -> Option<u16> {
        self.retired
    }

    /// Setpoints ignored by the rule so far.
    pub fn ignored(&self) -> u64 {
        self.ignored
    }

    /// Judges a setpoint (already E2E-checked) of `mode` in `epoch`, binding on a SAFE_STOP of
    /// a new epoch.
    pub fn admit(&mut self, mode: FingerMode, epoch: u16) -> Verdict {
        let follow = if self.bound == Some(epoch) {
            true
        } else if mode == FingerMode::SafeStop && self.retired != Some(epoch) {
            if self.bound.is_some() {
                self.retired = self.bound;
            }
            self.bound = Some(epoch);
            true
        } else {
            false
        };
        if follow {
            Verdict::Follow
        } else {
            self.ignored += 1;
            Verdict::Ignore
        }
    }

    /// The controller braked by itself (setpoint timeout) or on a HAND_ESTOP STOP: its epoch
    /// is retired and it is bound to none.
    pub fn braked_by_itself(&mut self) {
        if self.bound.is_some() {
            self.retired = self.bound.take();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use FingerMode::{Active, Disabled, Hold, SafeStop};

    #[test]
    fn nothing_but_a_safe_stop_opens_an_epoch_at_power_up() {
        let mut g = EpochGate::new();
        for m in [Active, Hold, Disabled] {
            assert_eq!(g.admit(m, 7), Verdict::Ignore, "{m:?} before any SAFE_STOP");
        }
        assert_eq!(g.admit(SafeStop, 7), Verdict::Follow);
        assert_eq!(g.bound(), Some(7));
        for m in [Active, Hold, Disabled, SafeStop] {
            assert_eq!(g.admit(m, 7), Verdict::Follow, "{m:?} of the bound epoch");
        }
        assert_eq!(g.ignored(), 3);
    }

    #[test]
    fn a_new_epoch_retires_the_old_one_for_good() {
        let mut g = EpochGate::new();
        g.admit(SafeStop, 1);
        assert_eq!(
            g.admit(Active, 2),
            Verdict::Ignore,
            "ACTIVE cannot switch epoch"
        );
        assert_eq!(g.bound(), Some(1));
        assert_eq!(g.admit(SafeStop, 2), Verdict::Follow);
        assert_eq!((g.bound(), g.retired()), (Some(2), Some(1)));
        for m in [Active, Hold, Disabled, SafeStop] {
            assert_eq!(g.admit(m, 1), Verdict::Ignore, "{m:?} of the retired epoch");
        }
        assert_eq!(g.bound(), Some(2), "a stale SAFE_STOP does not rebind");
    }

    #[test]
    fn after_braking_by_itself_only_a_safe_stop_of_a_new_epoch_reopens() {
        let mut g = EpochGate::new();
        g.admit(SafeStop, 65535);
        g.braked_by_itself();
        assert_eq!((g.bound(), g.retired()), (None, Some(65535)));
        assert_eq!(g.admit(Active, 65535), Verdict::Ignore);
        assert_eq!(
            g.admit(SafeStop, 65535),
            Verdict::Ignore,
            "its own epoch is retired"
        );
        // handd's next epoch after 65535 wraps to 0: equality only, so it is simply new.
        assert_eq!(g.admit(Active, 0), Verdict::Ignore);
        assert_eq!(g.admit(SafeStop, 0), Verdict::Follow);
        assert_eq!(g.admit(Active, 0), Verdict::Follow);
    }

    /// One step of a random trace: a setpoint, or the controller braking by itself.
    #[derive(Debug, Clone, Copy)]
    enum Step {
        Frame(FingerMode, u16),
        Timeout,
    }

    /// Properties over random traces (few epochs, so they collide): stated on the trace's
    /// history, not on the gate's fields.
    #[test]
    fn on_random_traces_only_an_opened_epoch_moves_and_a_left_one_never_reopens() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(16);
        for _ in 0..200 {
            let mut g = EpochGate::new();
            // (step, followed) so far.
            let mut trace: Vec<(Step, bool)> = Vec::new();
            for _ in 0..60 {
                let step = if rng.gen_bool(0.1) {
                    Step::Timeout
                } else {
                    let mode = FingerMode::ALL[rng.gen_range(0..4)];
                    Step::Frame(mode, rng.gen_range(0..4))
                };
                let followed = match step {
                    Step::Timeout => {
                        g.braked_by_itself();
                        false
                    }
                    Step::Frame(m, e) => g.admit(m, e) == Verdict::Follow,
                };
                // The last binding event before this step: a followed SAFE_STOP or a timeout.
                let last_bind = trace.iter().rev().find_map(|(s, f)| match s {
                    Step::Timeout => Some(None),
                    Step::Frame(SafeStop, e) if *f => Some(Some(*e)),
                    _ => None,
                });
                let bound = last_bind.flatten();
                // The epoch left last: bound before a timeout or before another epoch's stop.
                let mut left = None;
                let mut cur = None;
                for (s, f) in &trace {
                    match s {
                        Step::Timeout => left = cur.take().or(left),
                        Step::Frame(SafeStop, e) if *f && cur != Some(*e) => {
                            left = cur.or(left);
                            cur = Some(*e);
                        }
                        _ => {}
                    }
                }
                if let Step::Frame(m, e) = step {
                    let expected = if m == SafeStop {
                        bound == Some(e) || left != Some(e)
                    } else {
                        bound == Some(e)
                    };
                    assert_eq!(followed, expected, "{step:?} after {trace:?}");
                }
                trace.push((step, followed));
            }
        }
    }
}
