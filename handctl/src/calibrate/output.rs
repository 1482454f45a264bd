//! What the technician (and the patient) see on the terminal: on a TTY a live status line
//! redrawn at 10 Hz (what to do now, the countdown, and the live bar of the contraction against
//! the rest level, the monitor's channel bar); with `--yes` or a non-TTY stdout one plain line
//! per phase and per check; nothing at all in the in-memory test.

use std::io::Write;

use decoder::session::{Trial, TrialKind, FINGER_NAMES};

use super::protocol::Movement;
use super::sequencer::{Cue, Phase};
use crate::monitor::widgets::bar_cells;

/// Width of the live bar, cells.
const BAR_WIDTH: usize = 30;

/// How progress is shown.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// The live line on a terminal.
    Live,
    /// Plain lines (scripts, logs, `--yes`).
    Plain,
    /// Nothing (tests).
    Quiet,
}

/// The terminal output of a calibration.
#[derive(Debug)]
pub struct Output {
    mode: Mode,
    trials: usize,
    live_line: bool,
}

/// What the patient is asked to do.
pub fn instruction(m: &Movement) -> String {
    let what = m.finger.map_or("the whole hand".to_string(), |f| {
        format!("the {} finger", FINGER_NAMES[f])
    });
    match m.kind {
        TrialKind::Rest => "REST: relax the whole hand, do not move".into(),
        TrialKind::Flexion => format!("FLEX {what} as hard as you can"),
        TrialKind::Extension => format!("EXTEND {what} as hard as you can"),
    }
}

impl Output {
    /// Output in `mode` for a protocol of `trials` trials.
    pub fn new(mode: Mode, trials: usize) -> Self {
        Output {
            mode,
            trials,
            live_line: false,
        }
    }

    fn end_live(&mut self) {
        if self.live_line {
            println!();
            self.live_line = false;
        }
    }

    /// A line for the technician.
    pub fn say(&mut self, text: &str) {
        if self.mode != Mode::Quiet {
            self.end_live();
            println!("{text}");
        }
    }

    /// A new phase began.
    pub fn phase(&mut self, cue: &Cue) {
        match cue.phase {
            Phase::Done => return self.say("calibration: every trial recorded"),
            Phase::Aborted => return self.say("calibration: stopped"),
            _ => {}
        }
        let (Some(i), Some(m)) = (cue.trial, cue.movement) else {
            return;
        };
        let attempt = if cue.attempt > 0 {
            format!(", attempt {}", cue.attempt + 1)
        } else {
            String::new()
        };
        let head = format!(
            "trial {}/{} (repetition {}{attempt})",
            i + 1,
            self.trials,
            cue.repetition + 1
        );
        let secs = cue.time_left_us as f64 / 1e6;
        match cue.phase {
            Phase::Prepare => self.say(&format!(
                "{head}: get ready: {} in {secs:.1} s",
                instruction(&m)
            )),
            Phase::Hold => self.say(&format!("{head}: NOW {} ({secs:.1} s)", instruction(&m))),
            Phase::Relax => self.say(&format!("{head}: relax ({secs:.1} s)")),
            _ => {}
        }
    }

    /// The 10 Hz refresh: countdown and live bar (TTY only).
    pub fn tick(&mut self, cue: &Cue, level_uv: f64, rest_uv: Option<f64>) {
        if self.mode != Mode::Live || cue.trial.is_none() {
            return;
        }
        let word = match cue.phase {
            Phase::Prepare => "get ready",
            Phase::Hold => "HOLD",
            Phase::Relax => "relax",
            _ => "",
        };
        let ratio = rest_uv
            .filter(|&r| r > 0.0)
            .map_or(String::new(), |r| format!(" {:>5.1}x rest", level_uv / r));
        let mut out = std::io::stdout().lock();
        let _ = write!(
            out,
            "\r  {word:<9} {:>4.1} s  {} {level_uv:>6.1} µV{ratio}   ",
            cue.time_left_us as f64 / 1e6,
            bar_cells(level_uv, rest_uv, BAR_WIDTH)
        );
        let _ = out.flush();
        self.live_line = true;
    }

    /// The check of an attempt.
    pub fn verdict(
        &mut self,
        trial: &Trial,
        attempt: u32,
        reaction_us: Option<u64>,
        reasons: &[String],
    ) {
        let reaction = reaction_us.map_or(String::new(), |r| format!(", reaction {} ms", r / 1000));
        if reasons.is_empty() {
            self.say(&format!(
                "  ok: {trial} kept (attempt {}{reaction})",
                attempt + 1
            ));
        } else {
            self.say(&format!(
                "  REPEAT: {trial} attempt {} failed its check{reaction}:",
                attempt + 1
            ));
            for r in reasons {
                self.say(&format!("    {r}"));
            }
        }
    }
}
