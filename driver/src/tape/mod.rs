//! The tape: handd's own record of everything its control loop gave the engine (each frame with
//! the receive time the loop used, each tick's deadline and start, commands, faults from the
//! bus, epochs) and of every frame the engine returned, so that a run replays through a fresh
//! engine bit for bit (`handd --tape FILE`).
//!
//! A recording of the bus from another socket cannot do that: its receive times are another
//! socket's, and which frames a tick had depends on them. The tape holds the daemon's own.
//!
//! - [`entry`]: one entry and its line in the file.
//! - [`recorder`]: the engine's end (a bounded queue, no waiting, no allocation) and the thread
//!   that writes the file.
//! - [`replay`]: reads a tape and replays it.

pub mod entry;
pub mod recorder;
pub mod replay;

pub use entry::{Entry, EntryError, Recorded, HEADER};
pub use recorder::{start, unwritten, Recorder, RecorderError, TapeWriter};
pub use replay::{read, replay, Difference, End, Replay, TapeError};
