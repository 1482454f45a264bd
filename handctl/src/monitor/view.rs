//! The technician's view of the state: which finger is plotted, frozen or not, and the
//! counters' baseline; changed by keys.

use hand_dbc::hand::N_FINGERS;

use super::state::MonitorState;
use super::widgets::Baseline;

/// What the keys change.
#[derive(Debug, Clone, Default)]
pub struct View {
    /// The finger plotted and marked (0 thumb .. 4 pinky).
    pub finger: usize,
    /// The screen keeps showing this state while frozen.
    pub frozen_state: Option<MonitorState>,
    /// Frozen.
    pub frozen: bool,
    /// Counters at the last reset.
    pub baseline: Baseline,
}

/// A key's meaning.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Action {
    /// Next finger.
    NextFinger,
    /// Previous finger.
    PrevFinger,
    /// Finger by number key (1 thumb .. 5 pinky).
    Finger(usize),
    /// Freeze or unfreeze the screen.
    Freeze,
    /// Counters from zero.
    Reset,
    /// Leave.
    Quit,
}

impl View {
    /// A view with `finger` selected.
    pub fn with_finger(finger: usize) -> Self {
        Self {
            finger: finger.min(N_FINGERS - 1),
            ..Self::default()
        }
    }

    /// Applies an action; returns false on quit.
    pub fn apply(&mut self, a: Action, live: &MonitorState) -> bool {
        match a {
            Action::NextFinger => self.finger = (self.finger + 1) % N_FINGERS,
            Action::PrevFinger => self.finger = (self.finger + N_FINGERS - 1) % N_FINGERS,
            Action::Finger(f) => self.finger = f.min(N_FINGERS - 1),
            Action::Freeze => {
                self.frozen = !self.frozen;
                self.frozen_state = self.frozen.then(|| live.clone());
            }
            Action::Reset => self.baseline = Baseline::of(&live.daemon),
            Action::Quit => return false,
        }
        true
    }

    /// The state to draw: the frozen one, or the live one.
    pub fn shown<'a>(&'a self, live: &'a MonitorState) -> &'a MonitorState {
        self.frozen_state.as_ref().unwrap_or(live)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_select_freeze_and_reset() {
        let mut live = MonitorState::new("t", 2);
        let mut v = View::default();
        assert!(v.apply(Action::PrevFinger, &live));
        assert_eq!(v.finger, 4);
        v.apply(Action::NextFinger, &live);
        assert_eq!(v.finger, 0);
        v.apply(Action::Finger(2), &live);
        assert_eq!(v.finger, 2);
        live.daemon.deadline_misses = 5;
        v.apply(Action::Reset, &live);
        assert_eq!(v.baseline.deadline_misses, 5);
        v.apply(Action::Freeze, &live);
        live.t_us = 99;
        assert_eq!(v.shown(&live).t_us, 0, "frozen");
        v.apply(Action::Freeze, &live);
        assert_eq!(v.shown(&live).t_us, 99, "live again");
        assert!(!v.apply(Action::Quit, &live));
    }
}
