//! How a person's intent follows an instruction: each change of aim takes effect after a
//! reaction delay, then the contraction builds up over `rise_us` and lets go more slowly, over
//! `relax_us` (muscles relax slower than they contract).

use super::intent::Intent;
use crate::finger::N_FINGERS;

/// Changes of aim waiting for their reaction delay; more than this (instructions a few ms
/// apart) and the newest replaces the last one waiting, as a person skips a flicker.
const PENDING: usize = 8;

/// Delayed, slew-limited intent. No allocation: the waiting changes are a fixed ring.
#[derive(Debug, Clone)]
pub struct Reaction {
    rise_us: u64,
    relax_us: u64,
    pending: [(u64, Intent); PENDING],
    head: usize,
    len: usize,
    aim: Intent,
    intent: Intent,
    last_t: Option<u64>,
}

impl Reaction {
    /// At rest, full scale (0 to ±1) reached in `rise_us` when contracting and in `relax_us`
    /// when letting go (both at least 1 µs).
    pub fn new(rise_us: u64, relax_us: u64) -> Self {
        Self {
            rise_us: rise_us.max(1),
            relax_us: relax_us.max(1),
            pending: [(0, Intent::REST); PENDING],
            head: 0,
            len: 0,
            aim: Intent::REST,
            intent: Intent::REST,
            last_t: None,
        }
    }

    /// From `at_us` on, aim at `aim`. Changes take effect in the order they were scheduled: one
    /// scheduled earlier than a change still waiting is moved to that change's time.
    pub fn schedule(&mut self, at_us: u64, aim: Intent) {
        let at_us = match self.last_pending() {
            Some(t) => at_us.max(t),
            None => at_us,
        };
        if self.len == PENDING {
            let last = (self.head + PENDING - 1) % PENDING;
            self.pending[last] = (at_us, aim);
            return;
        }
        self.pending[(self.head + self.len) % PENDING] = (at_us, aim);
        self.len += 1;
    }

    /// The aim in effect (after its reaction delay), which the intent moves toward.
    pub fn aim(&self) -> Intent {
        self.aim
    }

    /// The intent at the last [`Self::advance`].
    pub fn intent(&self) -> Intent {
        self.intent
    }

    /// Advances to `t_us` (non-decreasing) and returns the intent. A change due between two
    /// calls takes effect at its own time, however long the step.
    pub fn advance(&mut self, t_us: u64) -> Intent {
        let mut now = self.last_t.unwrap_or(t_us).min(t_us);
        while self.len > 0 && self.pending[self.head].0 <= t_us {
            let (at, aim) = self.pending[self.head];
            let at = at.max(now);
            self.slew_all(at - now);
            now = at;
            self.aim = aim;
            self.head = (self.head + 1) % PENDING;
            self.len -= 1;
        }
        self.slew_all(t_us - now);
        self.last_t = Some(t_us);
        self.intent
    }

    fn slew_all(&mut self, dt_us: u64) {
        for f in 0..N_FINGERS {
            self.intent.0[f] = self.slew(self.intent.0[f], self.aim.0[f], dt_us);
        }
    }

    fn last_pending(&self) -> Option<u64> {
        (self.len > 0).then(|| self.pending[(self.head + self.len - 1) % PENDING].0)
    }

    /// One finger one step toward its aim: away from rest at the rise rate, toward it (or
    /// across it) at the slower relax rate.
    fn slew(&self, x: f64, aim: f64, dt_us: u64) -> f64 {
        let contracting = aim.abs() > x.abs() && aim * x >= 0.0;
        let span_us = if contracting {
            self.rise_us
        } else {
            self.relax_us
        };
        let step = dt_us as f64 / span_us as f64;
        if (aim - x).abs() <= step {
            aim
        } else {
            x + step * (aim - x).signum()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn delayed_then_ramped_and_relaxed_slower() {
        let mut r = Reaction::new(200_000, 500_000);
        r.schedule(300_000, Intent::finger(1, 1.0));
        r.schedule(1_000_000, Intent::REST);
        let at = |r: &mut Reaction, t: u64| r.advance(t).0[1];
        assert_eq!(at(&mut r, 0), 0.0);
        assert_eq!(
            at(&mut r, 299_000),
            0.0,
            "nothing before the reaction delay"
        );
        assert!(
            (at(&mut r, 400_000) - 0.5).abs() < 1e-9,
            "half way up after 100 ms"
        );
        assert_eq!(at(&mut r, 600_000), 1.0);
        assert_eq!(at(&mut r, 1_000_000), 1.0);
        assert!(
            (at(&mut r, 1_250_000) - 0.5).abs() < 1e-9,
            "relaxes at 1/500 ms"
        );
        assert_eq!(at(&mut r, 1_600_000), 0.0);
    }

    #[test]
    fn a_change_never_overtakes_an_earlier_one() {
        let mut r = Reaction::new(1, 1);
        r.schedule(450, Intent::all(1.0));
        r.schedule(350, Intent::all(-1.0)); // scheduled later with a shorter delay
        assert_eq!(r.advance(400).0, Intent::REST.0);
        r.advance(449);
        assert_eq!(r.aim(), Intent::REST);
        r.advance(450);
        assert_eq!(
            r.aim(),
            Intent::all(-1.0),
            "both due at 450: the later one wins"
        );
        for k in 0..20u64 {
            r.schedule(1_000 + k, Intent::finger(0, k as f64 / 20.0));
        }
        r.advance(2_000);
        assert_eq!(
            r.aim(),
            Intent::finger(0, 19.0 / 20.0),
            "a full ring keeps the newest"
        );
    }
}
