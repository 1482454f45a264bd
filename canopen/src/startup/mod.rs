//! The start-up of one CiA 402 drive (reset communication, boot-up, identity, supported
//! modes, configuration written and read back, targets zeroed, NMT start, Operation
//! enabled): the plan as data ([`StartupSettings::plan`]) and the sans-IO runner
//! ([`Startup`]).

pub mod machine;
pub mod settings;
pub mod step;

pub use machine::{
    Identity, Startup, StartupError, StartupStatus, StepFailure, MAX_BOOT_UPS_DURING_STARTUP,
};
pub use settings::{
    interpolation_period, SettingsError, StartupSettings, ABORT_CONNECTION_QUICK_STOP,
    QUICK_STOP_RAMP_THEN_DISABLE,
};
pub use step::Step;
