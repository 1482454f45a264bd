//! The simulated patient: intents per finger, scripted, closed-loop or cued from the bus
//! ([`CuedPatient`], following CALIBRATION_CUE), and the muscle activations they produce.

pub mod calibration;
pub mod cue;
pub mod cued;
pub mod intent;
pub mod reaction;
pub mod script;
pub mod tracking;

pub use calibration::{CalibrationPlan, CalibrationProtocol};
pub use cue::CueKey;
pub use cued::{CueStats, CuedConfig, CuedPatient};
pub use decoder::session::{Trial, TrialKind};
pub use intent::{Intent, MuscleDrive};
pub use reaction::Reaction;
pub use script::{target_intent, Gesture, Motion, Script, Segment};
pub use tracking::{ClosedLoopUser, Target, TrackingConfig};
