//! The sequencer: a pure state machine over the caller's clock (it never sleeps or reads a
//! clock itself), so the same code runs on the real clock and on a test's virtual clock.
//!
//! Each trial goes PREPARE -> HOLD -> RELAX; when RELAX ends the sequencer asks for the trial's
//! check ([`Event::CheckDue`]) and waits: [`Sequencer::passed`] moves on to the next trial's
//! PREPARE (or DONE after the last), [`Sequencer::failed`] repeats the same trial at once with
//! the attempt counted up, until the protocol's `max_attempts` (then ABORTED).

use super::protocol::{Movement, Protocol};

/// The phase of the cue (hand.dbc's CuePhase, see [`super::cue`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Phase {
    /// Nothing running yet.
    Idle,
    /// Get ready: the movement is shown, with a countdown.
    Prepare,
    /// Do it now (or, for a rest trial, stay relaxed).
    Hold,
    /// Relax.
    Relax,
    /// Every trial done.
    Done,
    /// Stopped: interrupted, or a trial failed too often.
    Aborted,
}

/// What the cue says at one instant.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Cue {
    /// The phase.
    pub phase: Phase,
    /// Index of the trial in the protocol (None when done or idle).
    pub trial: Option<usize>,
    /// The movement asked for.
    pub movement: Option<Movement>,
    /// Repetition of this trial, 0-based.
    pub repetition: u32,
    /// Attempt of this trial, 0 = first.
    pub attempt: u32,
    /// Time left in this phase, µs.
    pub time_left_us: u64,
}

/// A trial's HOLD, on the caller's clock: when the check is due.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct HoldTimes {
    /// Index of the trial in the protocol.
    pub trial: usize,
    /// Its attempt, 0 = first.
    pub attempt: u32,
    /// When HOLD was cued, µs.
    pub hold_start_us: u64,
    /// When RELAX was cued, µs.
    pub hold_end_us: u64,
}

/// What changed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Event {
    /// A new phase began (the cue is sent at once).
    Phase(Cue),
    /// A trial's RELAX ended: check it, then call `passed` or `failed`.
    CheckDue(HoldTimes),
}

/// The sequencer (see the module docs).
#[derive(Debug, Clone)]
pub struct Sequencer {
    protocol: Protocol,
    trials: Vec<(Movement, u32)>,
    index: usize,
    attempt: u32,
    phase: Phase,
    phase_start_us: u64,
    hold_start_us: u64,
    awaiting_check: bool,
    /// While an earlier trial is redone: the trial to go on with after it.
    resume_at: Option<usize>,
}

impl Sequencer {
    /// Starts at trial `first` (0 for a new calibration, later when resuming) at `now_us`.
    pub fn new(protocol: &Protocol, first: usize, now_us: u64) -> Self {
        let trials = protocol.trials();
        let mut s = Sequencer {
            protocol: protocol.clone(),
            index: first,
            attempt: 0,
            phase: Phase::Idle,
            phase_start_us: now_us,
            hold_start_us: now_us,
            awaiting_check: false,
            resume_at: None,
            trials,
        };
        s.phase = if first < s.trials.len() {
            Phase::Prepare
        } else {
            Phase::Done
        };
        s
    }

    /// The trials in protocol order: (movement, repetition).
    pub fn trials(&self) -> &[(Movement, u32)] {
        &self.trials
    }

    /// The cue at `now_us`.
    pub fn cue(&self, now_us: u64) -> Cue {
        let running = matches!(self.phase, Phase::Prepare | Phase::Hold | Phase::Relax);
        let end = self.phase_start_us + self.duration();
        let (movement, repetition) = match self.trials.get(self.index) {
            Some(&(m, r)) if running => (Some(m), r),
            _ => (None, 0),
        };
        Cue {
            phase: self.phase,
            trial: running.then_some(self.index),
            movement,
            repetition,
            attempt: self.attempt,
            time_left_us: if running {
                end.saturating_sub(now_us)
            } else {
                0
            },
        }
    }

    /// True once DONE or ABORTED.
    pub fn finished(&self) -> bool {
        matches!(self.phase, Phase::Done | Phase::Aborted)
    }

    /// True while a check is due and not yet answered.
    pub fn awaiting_check(&self) -> bool {
        self.awaiting_check
    }

    fn duration(&self) -> u64 {
        let kind = self.trials.get(self.index).map(|(m, _)| m.kind);
        match (self.phase, kind) {
            (Phase::Prepare, _) => self.protocol.prepare_us,
            (Phase::Hold, Some(k)) => self.protocol.hold_of(k),
            (Phase::Relax, _) => self.protocol.relax_us,
            _ => 0,
        }
    }

    /// The next event due at `now_us`, if any; call until `None` (a late call catches up, each
    /// phase starting when the previous one was due to end).
    pub fn advance(&mut self, now_us: u64) -> Option<Event> {
        if self.finished() || self.awaiting_check {
            return None;
        }
        let end = self.phase_start_us + self.duration();
        if now_us < end {
            return None;
        }
        match self.phase {
            Phase::Prepare => {
                self.hold_start_us = end;
                self.enter(Phase::Hold, end)
            }
            Phase::Hold => self.enter(Phase::Relax, end),
            _ => {
                self.awaiting_check = true;
                self.phase_start_us = end;
                Some(Event::CheckDue(HoldTimes {
                    trial: self.index,
                    attempt: self.attempt,
                    hold_start_us: self.hold_start_us,
                    hold_end_us: self.hold_start_us + self.protocol.hold_of(self.kind()),
                }))
            }
        }
    }

    fn kind(&self) -> decoder::session::TrialKind {
        self.trials[self.index].0.kind
    }

    fn enter(&mut self, phase: Phase, at_us: u64) -> Option<Event> {
        self.phase = phase;
        self.phase_start_us = at_us;
        Some(Event::Phase(self.cue(at_us)))
    }

    /// The checked trial passed: the next trial's PREPARE at `now_us`, or DONE.
    pub fn passed(&mut self, now_us: u64) -> Event {
        self.awaiting_check = false;
        self.attempt = 0;
        self.index = self.resume_at.take().unwrap_or(self.index + 1);
        let next = if self.index < self.trials.len() {
            Phase::Prepare
        } else {
            Phase::Done
        };
        self.enter(next, now_us).expect("enter gives an event")
    }

    /// The checked trial failed: the same trial again at once (attempt + 1), or ABORTED when
    /// it has had `max_attempts`.
    pub fn failed(&mut self, now_us: u64) -> Event {
        self.awaiting_check = false;
        if self.attempt + 1 >= self.protocol.max_attempts {
            return self.abort(now_us);
        }
        self.attempt += 1;
        self.enter(Phase::Prepare, now_us)
            .expect("enter gives an event")
    }

    /// The checked trial passed, but showed that the earlier trial `earlier` (kept) was much
    /// weaker than it: redo `earlier` now (its next attempt), then go on after this one.
    pub fn passed_then_redo(&mut self, now_us: u64, earlier: usize) -> Event {
        self.awaiting_check = false;
        self.resume_at = Some(self.resume_at.unwrap_or(self.index + 1));
        self.index = earlier;
        self.attempt = 1;
        self.enter(Phase::Prepare, now_us)
            .expect("enter gives an event")
    }

    /// Stops (Ctrl-C, or too many attempts): ABORTED.
    pub fn abort(&mut self, now_us: u64) -> Event {
        self.awaiting_check = false;
        let cue = Cue {
            phase: Phase::Aborted,
            ..self.cue(now_us)
        };
        self.phase = Phase::Aborted;
        self.phase_start_us = now_us;
        Event::Phase(Cue {
            time_left_us: 0,
            ..cue
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `text`'s protocol with its flexions alone (a file must name both kinds; the sequencer
    /// itself runs any list).
    fn flexions(text: &str) -> Protocol {
        let mut p = Protocol::parse(text, "t").expect("valid");
        p.movements
            .retain(|m| m.kind == decoder::session::TrialKind::Flexion);
        p
    }

    fn short() -> Protocol {
        flexions(
            "repetitions = 1\nprepare_s = 1\nhold_s = 2\nrelax_s = 1\nfingers = [\"index\"]\nmax_attempts = 2",
        )
    }

    fn drain(s: &mut Sequencer, now: u64) -> Vec<Event> {
        std::iter::from_fn(|| s.advance(now)).collect()
    }

    #[test]
    fn phases_follow_the_clock_and_a_failed_trial_is_repeated_then_aborted() {
        let mut s = Sequencer::new(&short(), 0, 0);
        assert_eq!(s.cue(250_000).phase, Phase::Prepare);
        assert_eq!(s.cue(250_000).time_left_us, 750_000);
        assert!(drain(&mut s, 999_999).is_empty());
        // A late call catches up on every phase in order, on the schedule.
        let ev = drain(&mut s, 10_000_000);
        assert_eq!(ev.len(), 3, "{ev:?}");
        let Event::CheckDue(h) = ev[2] else {
            panic!("{ev:?}")
        };
        assert_eq!(
            (h.trial, h.hold_start_us, h.hold_end_us),
            (0, 1_000_000, 3_000_000)
        );
        assert!(s.awaiting_check() && drain(&mut s, 20_000_000).is_empty());
        let Event::Phase(c) = s.passed(10_000_000) else {
            panic!()
        };
        assert_eq!((c.phase, c.trial, c.attempt), (Phase::Prepare, Some(1), 0));
        drain(&mut s, 20_000_000);
        let Event::Phase(c) = s.failed(20_000_000) else {
            panic!()
        };
        assert_eq!((c.phase, c.trial, c.attempt), (Phase::Prepare, Some(1), 1));
        drain(&mut s, 30_000_000);
        let Event::Phase(c) = s.failed(30_000_000) else {
            panic!()
        };
        assert_eq!(c.phase, Phase::Aborted);
        assert!(s.finished());
    }

    #[test]
    fn an_earlier_trial_is_redone_then_the_protocol_goes_on() {
        let p = flexions("repetitions = 2\nfingers = [\"index\"]");
        let mut s = Sequencer::new(&p, 0, 0);
        let mut now = 0;
        let mut run = |s: &mut Sequencer| {
            now += 100_000_000;
            drain(s, now);
            now
        };
        let t = run(&mut s);
        s.passed(t);
        let t = run(&mut s);
        s.passed(t);
        let t = run(&mut s);
        // Trial 3 (round 2's rest) passed, and showed trial 1 weak: trial 1 again, attempt 2.
        let Event::Phase(c) = s.passed_then_redo(t, 1) else {
            panic!()
        };
        assert_eq!((c.trial, c.attempt), (Some(1), 1));
        let t = run(&mut s);
        let Event::Phase(c) = s.passed(t) else {
            panic!()
        };
        assert_eq!((c.trial, c.attempt), (Some(3), 0));
    }
}
