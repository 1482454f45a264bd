//! CALIBRATION_CUE frames (hand.dbc, id 0x380, E2E data id 0x1380): the cue as the patient's
//! display and the simulated patient read it. Sent at every phase change and at 10 Hz.

use hand_dbc::e2e::{E2eProfile, E2eProtector};
use hand_dbc::CanFrame;

use super::sequencer::Cue;
use decoder::session::TrialKind;

/// CALIBRATION_CUE's id.
pub const CUE_ID: u16 = 0x380;
/// Its E2E data id: layout version 1.
const CUE_DATA_ID: u16 = 0x1380;
/// Trial "none".
const NO_TRIAL: u8 = 255;
/// Finger: the whole hand.
const WHOLE_HAND: u8 = 5;
/// Finger: none (rest).
const NO_FINGER: u8 = 15;

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

impl CueSender {
    /// A sender whose counter starts at 0.
    pub fn new() -> Self {
        let profile = E2eProfile::try_new(CUE_DATA_ID, 4, 8).expect("a valid E2E profile");
        CueSender {
            protector: E2eProtector::new(profile),
        }
    }

    /// The protected frame of `cue`.
    pub fn frame(&mut self, cue: &Cue) -> CanFrame {
        let mut data = [0u8; 8];
        let (finger, kind) = match cue.movement {
            None => (NO_FINGER, 0),
            Some(m) => match m.kind {
                TrialKind::Rest => (NO_FINGER, 0),
                TrialKind::Flexion => (m.finger.map_or(WHOLE_HAND, |f| f as u8), 1),
                TrialKind::Extension => (m.finger.map_or(WHOLE_HAND, |f| f as u8), 2),
            },
        };
        let trial = cue.trial.map_or(NO_TRIAL, |t| t.min(254) as u8);
        let time_left = (cue.time_left_us / 10_000).min(u64::from(u16::MAX)) as u16;
        data[1] = cue.phase.code() << 4;
        data[2] = trial;
        data[3] = finger | (kind << 4);
        data[4] = (cue.repetition.min(15) as u8) | ((cue.attempt.min(15) as u8) << 4);
        data[5..7].copy_from_slice(&time_left.to_le_bytes());
        data[7] = 100;
        self.protector
            .protect_bytes(&mut data)
            .expect("8 bytes, as the profile says");
        CanFrame::new_standard(CUE_ID, &data).expect("a standard id and 8 bytes")
    }
}
