//! The simulated world on the bus: an sEMG amplifier node, finger motor-controller nodes and a
//! simulated patient, so that the daemon can be calibrated, run and broken without a person or
//! a prosthesis. It speaks hand.dbc through `hand-dbc`, keeps time with `hand-clock` and
//! writes its calibration sessions with the decoder's session types; it never depends on the
//! daemon, and the daemon never depends on it (only `driver`'s `sim` feature does).
//!
//! Map:
//! - [`clock`]: [`Clock`], [`VirtualClock`] (tests), [`SystemClock`] (real time), re-exported
//!   from `hand-clock`.
//! - [`bus`]: [`MemBus`], an in-memory broadcast CAN bus whose endpoints implement
//!   `embedded_can::nb::Can` and `blocking::Can`; [`socketcan_bus`] is the SocketCAN transport.
//! - [`emg`]: the signal model: 10 muscle sources (flexor and extensor per finger), cross-talk
//!   into 12 channels, mains, DC offset and drift, noise floor, 12-bit ADC.
//! - [`patient`]: intents per finger, scripts (rest, holds, ramps, gestures), the calibration
//!   protocol with its trials ([`patient::Trial`], the decoder's type), the closed-loop user,
//!   and the cued patient ([`patient::CuedPatient`]) who follows CALIBRATION_CUE frames from
//!   the bus as a person follows `handctl calibrate`'s cues.
//! - [`finger`]: one finger's mechanics and control law.
//! - [`nodes`]: the bus nodes, each stepped by `poll(now_us, &mut bus)`: amplifier, motor
//!   controllers, fault injector, and a setpoint source standing in for the daemon in tests.
//! - [`faults`]: faults on demand ([`faults::Fault`], [`faults::FaultPlan`]).
//! - [`world`] and [`scenario`]: all nodes and the patient together, and named scenarios;
//!   [`record`] runs a world faster than real time and shows every frame (sessions, demo).
//!
//! Fingers are indexed 0 thumb, 1 index, 2 middle, 3 ring, 4 pinky (the paper's L(5-f)).

pub mod bus;
pub mod clock;
pub mod dbc;
pub mod emg;
pub mod error;
pub mod faults;
pub mod finger;
pub mod nodes;
pub mod patient;
pub mod record;
pub mod scenario;
pub mod socketcan_bus;
pub mod world;

pub use bus::{MemBus, MemBusError, MemEndpoint, Received};
pub use clock::{Clock, SystemClock, VirtualClock};
pub use error::SimError;
pub use scenario::Scenario;
pub use world::World;
