//! CALIBRATION_CUE frames (hand.dbc, id 0x380, E2E data id 0x1380) through the generated
//! codec: the cue as the patient's display and the simulated patient read it. Sent at every
//! phase change and at 10 Hz.

use decoder::session::TrialKind;
use hand_dbc::e2e::E2eProtector;
use hand_dbc::messages::{CalibrationCue, CueKind, CuePhase};
use hand_dbc::CanFrame;

use super::sequencer::{Cue, Phase};

/// Trial "none".
pub const NO_TRIAL: u8 = 255;
/// Finger: the whole hand.
pub const WHOLE_HAND: u8 = 5;
/// Finger: none (rest).
pub const NO_FINGER: u8 = 15;
/// The effort a normal cue asks for, percent of maximal.
pub const FULL_EFFORT: u8 = 100;

/// Encodes cues with the E2E counter and CRC.
#[derive(Debug, Clone)]
pub struct CueSender {
    protector: E2eProtector,
}

impl Default for CueSender {
    fn default() -> Self {
        Self::new()
    }
}

fn phase(p: Phase) -> CuePhase {
    match p {
        Phase::Idle => CuePhase::Idle,
        Phase::Prepare => CuePhase::Prepare,
        Phase::Hold => CuePhase::Hold,
        Phase::Relax => CuePhase::Relax,
        Phase::Done => CuePhase::Done,
        Phase::Aborted => CuePhase::Aborted,
    }
}

/// The message of `cue` (counter and CRC still 0).
pub fn message(cue: &Cue) -> CalibrationCue {
    let (finger, kind) = match cue.movement {
        None => (NO_FINGER, CueKind::Rest),
        Some(m) => {
            let finger = m.finger.map_or(WHOLE_HAND, |f| f as u8);
            match m.kind {
                TrialKind::Rest => (NO_FINGER, CueKind::Rest),
                TrialKind::Flexion => (finger, CueKind::Flexion),
                TrialKind::Extension => (finger, CueKind::Extension),
            }
        }
    };
    let trial = cue.trial.map_or(NO_TRIAL, |t| t.min(254) as u8);
    let time_left = (cue.time_left_us / 10_000).min(65_535) as f64 * 0.01;
    // Every value is inside hand.dbc's ranges by construction (the protocol bounds repetitions
    // and attempts to 15 and phases to 600 s).
    CalibrationCue::new(
        phase(cue.phase),
        trial,
        finger,
        kind,
        cue.repetition.min(15) as u8,
        cue.attempt.min(15) as u8,
        time_left.min(CalibrationCue::TIME_LEFT_MAX),
        FULL_EFFORT,
    )
    .unwrap_or_else(|e| panic!("a cue inside hand.dbc's ranges: {e}"))
}

impl CueSender {
    /// A sender whose counter starts at 0.
    pub fn new() -> Self {
        CueSender {
            protector: E2eProtector::new(CalibrationCue::E2E),
        }
    }

    /// The protected frame of `cue`.
    pub fn frame(&mut self, cue: &Cue) -> CanFrame {
        self.protector
            .protect_message(&message(cue))
            .expect("the protector was made for CALIBRATION_CUE")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::calibrate::protocol::Movement;
    use hand_dbc::e2e::{E2eChecker, E2eStatus};

    #[test]
    fn cues_decode_as_sent_and_pass_the_e2e_check() {
        let mut s = CueSender::new();
        let mut check = E2eChecker::try_new(CalibrationCue::E2E, 1).expect("profile");
        let cue = Cue {
            phase: Phase::Hold,
            trial: Some(7),
            movement: Some(Movement {
                finger: Some(3),
                kind: TrialKind::Extension,
            }),
            repetition: 2,
            attempt: 1,
            time_left_us: 4_321_000,
        };
        for n in 0..3u8 {
            let f = s.frame(&cue);
            assert_eq!(check.check_frame(Some(&f)), E2eStatus::Ok);
            let m = CalibrationCue::try_from_frame(&f).expect("decodes");
            assert_eq!(m.counter(), n);
            assert_eq!(
                (m.phase(), m.trial(), m.finger(), m.kind()),
                (CuePhase::Hold, 7, 3, CueKind::Extension)
            );
            assert_eq!((m.repetition(), m.attempt(), m.effort()), (2, 1, 100));
            assert!((m.time_left() - 4.32).abs() < 1e-9, "{}", m.time_left());
        }
        let rest = message(&Cue {
            phase: Phase::Done,
            trial: None,
            movement: None,
            repetition: 0,
            attempt: 0,
            time_left_us: 0,
        });
        assert_eq!(
            (rest.trial(), rest.finger(), rest.phase()),
            (NO_TRIAL, NO_FINGER, CuePhase::Done)
        );
    }
}
