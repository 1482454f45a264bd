//! handstack's CANopen master subset (CiA 301 + CiA 402), I/O-free: codecs and state
//! machines that take frames and a `now` in microseconds and return frames to send. No
//! sockets, threads or timers live here; the daemon's loop owns those.
//!
//! - [`frame`]: [`CanFrame`], converted to and from any [`embedded_can::Frame`].
//! - [`ids`]: [`NodeId`] (1..=127), [`CobId`], [`ObjectAddr`].
//! - [`nmt`]: NMT commands, boot-up and heartbeat states.
//! - [`sync`]: the SYNC frame and a producer driven by the caller's clock.
//! - [`sdo`]: expedited SDO codec, the abort code table, the client.
//! - [`pdo`]: PDO mapping as a plan of SDO writes, read-back, payload codec.
//! - [`heartbeat`]: handd's producer and the per-drive consumer.
//! - [`emcy`]: EMCY decoding with the error classes named.
//! - [`cia402`]: statusword/controlword, the transition table, the walk to Operation enabled.
//! - [`scaling`]: daemon units to drive units, validated once.
//! - [`startup`]: one drive's start-up as data and as a state machine.
//! - [`master`]: every drive after start-up: the per-tick RPDO1s, SYNC and heartbeat, feedback
//!   age, latched faults, recovery on `arm`.
//! - [`sim`] (feature `sim`): a simulated CiA 402 drive node.
//!
//! ```
//! use hand_canopen::sdo::{SdoDone, SdoReply};
//! use hand_canopen::{NodeId, ObjectAddr, SdoClient, SdoData};
//!
//! let drive = NodeId::try_new(3)?;
//! let vendor = ObjectAddr::new(0x1018, 1);
//! let mut sdo = SdoClient::new(drive, 20_000);
//! let request = sdo.upload(vendor, 0)?; // the caller sends this frame
//! assert_eq!(request.cob_id(), 0x603);
//! // The drive's answer arrives; the caller offers it with its own clock's `now`.
//! let reply = SdoReply::Uploaded(vendor, SdoData::u32(0x1D)).frame(drive);
//! assert_eq!(sdo.on_frame(&reply), Some(Ok(SdoDone::Uploaded(SdoData::u32(0x1D)))));
//! assert!(sdo.poll(1_000_000).is_none(), "nothing in flight, nothing times out");
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod cia402;
pub mod emcy;
pub mod frame;
pub mod heartbeat;
pub mod ids;
pub mod master;
pub mod nmt;
pub mod pdo;
pub mod scaling;
pub mod sdo;
#[cfg(feature = "sim")]
pub mod sim;
pub mod startup;
pub mod sync;

pub use cia402::{Controlword, Mode, PowerState, Statusword};
pub use emcy::Emcy;
pub use frame::CanFrame;
pub use heartbeat::{HeartbeatConsumer, HeartbeatProducer};
pub use ids::{CobId, NodeId, ObjectAddr};
pub use master::{DriveBank, DriveFault, DriveStatus, Target};
pub use nmt::{NmtCommand, NmtState};
pub use sdo::{AbortCode, SdoClient, SdoData, SdoError};
pub use startup::{Startup, StartupSettings, StartupStatus};
pub use sync::SyncProducer;
