//! Replay of a closed loop over vcan from handd's own tape (`handd --tape`, `driver::tape`):
//! the tape's inputs through a fresh engine, built from handd's config and model, must give
//! every round of frames the tape holds, bit for bit; and handd's frames that an independent
//! recorder (`handctl record`, its own socket) saw on the bus must be the tape's, in order.
//!
//! The tape holds the receive times handd used, so nothing here depends on another socket's
//! timestamps or on guessing which frames a tick had.

use driver::tape::{Entry, Replay};
use hand_dbc::candump::LogEntry;
use hand_dbc::CanFrame;

/// What a replay of the closed loop found.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TapeReplay {
    /// The tape through a fresh engine.
    pub replay: Replay,
    /// handd's frames in the bus log that agree with the tape's, from the first.
    pub on_bus: usize,
    /// The first of handd's frames on the bus that is not the tape's next one: its index
    /// among handd's frames in the bus log, the bus's frame and the tape's.
    pub first_difference: Option<(usize, CanFrame, Option<CanFrame>)>,
}

/// Frames only handd sends: FINGER_SETPOINT_0..4, HAND_HEARTBEAT, HAND_DIAG.
fn from_handd(id: u32) -> bool {
    matches!(id, 0x200..=0x204 | 0x300 | 0x301)
}

/// Replays `tape` (handd's, under `config`) and compares handd's frames in `log` (a recording
/// of the same bus that began before handd) with the tape's. Panics if the model does not
/// load or the tape does not start.
pub fn replay_tape(config: &driver::Config, tape: &[Entry], log: &[LogEntry]) -> TapeReplay {
    let loaded = driver::startup::load_model(&config.model, config.mains_hz).expect("model");
    let settings = driver::startup::engine_settings(config, loaded.model_id);
    let replay = driver::tape::replay(
        tape,
        &loaded.chain,
        Some(loaded.model.predictor()),
        settings,
    )
    .expect("the tape replays");
    let out: Vec<CanFrame> = tape
        .iter()
        .filter_map(|e| match e {
            Entry::Out { frame } => Some(*frame),
            _ => None,
        })
        .collect();
    let on_bus: Vec<CanFrame> = log
        .iter()
        .map(|e| e.frame)
        .filter(|f| from_handd(f.raw_id()))
        .collect();
    let agree = on_bus.iter().zip(&out).take_while(|(a, b)| a == b).count();
    let first_difference =
        (agree < on_bus.len()).then(|| (agree, on_bus[agree], out.get(agree).copied()));
    TapeReplay {
        replay,
        on_bus: agree,
        first_difference,
    }
}
