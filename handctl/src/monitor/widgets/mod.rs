//! The monitor's widgets: plain ratatui widgets over plain state (no source, no terminal), so
//! the guided calibration can show the same channel bars during its trials.

mod channels;
mod daemon;
mod fingers;
mod plot;

pub use channels::{bar_cells, ChannelBars};
pub use daemon::{Baseline, DaemonPanel};
pub use fingers::{drive_cell, FingerTable};
pub use plot::FingerPlot;
