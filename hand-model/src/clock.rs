//! Time as the nodes see it: [`Clock`], [`VirtualClock`] and [`SystemClock`] live in the
//! `hand-clock` crate, below both the daemon and the simulator; re-exported here.

pub use hand_clock::{Clock, SystemClock, VirtualClock};
