//! The simulated patient: intents per finger, scripted or closed-loop, and the muscle
//! activations they produce.

pub mod calibration;
pub mod intent;
pub mod script;
pub mod tracking;

pub use calibration::{CalibrationPlan, CalibrationProtocol};
pub use decoder::session::{Trial, TrialKind};
pub use intent::{Intent, MuscleDrive};
pub use script::{target_intent, Gesture, Motion, Script, Segment};
pub use tracking::{ClosedLoopUser, Target, TrackingConfig};
