//! A simulated CiA 402 finger drive (feature `sim`): the other end of the master subset for
//! host tests and, later, hand-model's simulator.

pub mod drive;
pub mod od;

pub use drive::{SimDrive, SimStats, EMCY_HEARTBEAT, EMCY_PDO_LENGTH};
pub use od::{Access, ObjectDef, ObjectDictionary, FINGER_DRIVE_OBJECTS, SIM_SUPPORTED_MODES};
