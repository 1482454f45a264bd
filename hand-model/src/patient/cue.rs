//! What a person makes of one CALIBRATION_CUE (hand.dbc): the intent it asks for.

use hand_dbc::messages::{CalibrationCue, CueKind, CuePhase};

use super::intent::Intent;
use crate::finger::N_FINGERS;

/// `Finger` of a cue for the whole hand (hand.dbc: 0..4 one finger, 5 all, 15 none).
pub const WHOLE_HAND: u8 = 5;

/// The fields of a cue that say what to do, without the countdown (`TimeLeft`) and the E2E
/// fields: two frames with the same `CueKey` are the same instruction, so a person reacts once
/// to it however often it is repeated on the bus.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CueKey {
    /// The phase.
    pub phase: CuePhase,
    /// Trial index in the protocol (255 = none).
    pub trial: u8,
    /// Cued finger (0..4, 5 whole hand, anything else none).
    pub finger: u8,
    /// Direction.
    pub kind: CueKind,
    /// Repetition of the trial.
    pub repetition: u8,
    /// Attempt at the trial (0 = first).
    pub attempt: u8,
    /// Requested effort, percent of maximal.
    pub effort: u8,
}

impl CueKey {
    /// The instruction a decoded cue carries.
    pub fn of(cue: &CalibrationCue) -> Self {
        Self {
            phase: cue.phase(),
            trial: cue.trial(),
            finger: cue.finger(),
            kind: cue.kind(),
            repetition: cue.repetition(),
            attempt: cue.attempt(),
            effort: cue.effort(),
        }
    }

    /// Whether the cue asks for a contraction at all: HOLD, a finger (or the whole hand), a
    /// direction and some effort. Every other cue means rest.
    pub fn is_contraction(&self) -> bool {
        self.phase == CuePhase::Hold
            && usize::from(self.finger) <= N_FINGERS
            && self.kind != CueKind::Rest
            && self.effort > 0
    }

    /// The intent the cue asks for at effort `level` (0..=1): `±level` on the cued finger or
    /// on every finger (flexion +, extension -), rest for anything but a contraction.
    pub fn intent(&self, level: f64) -> Intent {
        if !self.is_contraction() {
            return Intent::REST;
        }
        let sign = if self.kind == CueKind::Flexion {
            1.0
        } else {
            -1.0
        };
        let x = (sign * level).clamp(-1.0, 1.0);
        if self.finger == WHOLE_HAND {
            Intent::all(x)
        } else {
            Intent::finger(usize::from(self.finger), x)
        }
    }

    /// The effort the cue requests, 0..=1 (the DBC caps `Effort` at 100 %).
    pub fn requested_level(&self) -> f64 {
        f64::from(self.effort.min(100)) / 100.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn key(phase: CuePhase, finger: u8, kind: CueKind, effort: u8) -> CueKey {
        let cue = CalibrationCue::new(phase, 3, finger, kind, 0, 0, 1.0, effort).expect("valid");
        CueKey::of(&cue)
    }

    #[test]
    fn only_a_hold_of_a_finger_in_a_direction_is_a_contraction() {
        let k = key(CuePhase::Hold, 1, CueKind::Flexion, 100);
        assert_eq!(k.intent(k.requested_level()), Intent::finger(1, 1.0));
        let k = key(CuePhase::Hold, WHOLE_HAND, CueKind::Extension, 60);
        assert_eq!(k.intent(k.requested_level()), Intent::all(-0.6));
        for k in [
            key(CuePhase::Prepare, 1, CueKind::Flexion, 100),
            key(CuePhase::Relax, 1, CueKind::Flexion, 100),
            key(CuePhase::Hold, 15, CueKind::Flexion, 100),
            key(CuePhase::Hold, 9, CueKind::Flexion, 100),
            key(CuePhase::Hold, 2, CueKind::Rest, 100),
            key(CuePhase::Hold, 2, CueKind::Flexion, 0),
        ] {
            assert!(!k.is_contraction(), "{k:?}");
            assert_eq!(k.intent(1.0), Intent::REST, "{k:?}");
        }
    }
}
