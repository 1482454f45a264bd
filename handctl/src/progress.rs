//! Training progress: a live line on a terminal, nothing in logs or pipes.

use std::io::{IsTerminal, Write};

use decoder::model::EpochReport;

/// Shows epochs and losses on stderr when it is a terminal.
pub struct Progress {
    live: bool,
    label: String,
    started: bool,
}

impl Progress {
    /// A progress display for training `label`.
    pub fn new(label: &str) -> Self {
        Progress {
            live: std::io::stderr().is_terminal(),
            label: label.to_string(),
            started: false,
        }
    }

    /// Called after every epoch.
    pub fn epoch(&mut self, r: &EpochReport) {
        if !self.live {
            return;
        }
        self.started = true;
        let val = r
            .val_loss
            .map_or(String::new(), |v| format!("  held-out {v:.5}"));
        let mut e = std::io::stderr().lock();
        let _ = write!(
            e,
            "\r{}: epoch {:>4}/{}  train loss {:.5}{val}  (best epoch {})   ",
            self.label, r.epoch, r.max_epochs, r.train_loss, r.best_epoch
        );
        let _ = e.flush();
    }

    /// Ends the live line.
    pub fn finish(&mut self) {
        if self.live {
            eprintln!();
        }
    }

    /// Ends the live line if an epoch was shown since the last call (the demo's phases).
    #[cfg(feature = "sim")]
    pub fn finish_if_started(&mut self) {
        if self.started {
            self.finish();
            self.started = false;
        }
    }
}
