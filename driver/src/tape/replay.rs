//! A tape through a fresh engine: every input in the order the loop gave it, with the times it
//! used, and every round of frames the engine returns compared with the tape's, bit for bit.
//!
//! Deterministic by design: the engine decides from its inputs alone, and the tape holds all
//! of them (the receive times the loop used among them), so a replay that differs shows an
//! engine that is not a function of its inputs, or a tape that misses one. It ends at the
//! tape's end, at a model swap (the model is not on the tape) or where the recorder lost
//! entries.

use std::io::BufRead;
use std::path::{Path, PathBuf};

use decoder::dsp::ChainSettings;
use decoder::model::Predictor;
use hand_dbc::CanFrame;

use super::entry::{Entry, EntryError, Recorded, HEADER};
use crate::engine::{Command, Engine, EngineSettings};
use crate::persist::Latches;

/// Why a tape cannot be read or replayed.
#[derive(Debug, thiserror::Error)]
pub enum TapeError {
    /// The file could not be read.
    #[error("cannot read the tape {path}: {source}")]
    Read {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// The first line is not [`HEADER`].
    #[error("{0} is not a handstack tape (its first line is not {HEADER:?})")]
    NotATape(PathBuf),
    /// A line that is not an entry.
    #[error("tape line {line}: {source}")]
    Line {
        /// Its number, from 1.
        line: usize,
        /// Why.
        source: EntryError,
    },
    /// The tape does not begin with the engine's construction.
    #[error("the tape does not begin with its engine's construction (a `B` line)")]
    NoStart,
    /// The tape was recorded with another model.
    #[error("the tape ran model {tape:08x}, the replay has {given:08x}")]
    OtherModel {
        /// The tape's.
        tape: u32,
        /// The replay's.
        given: u32,
    },
}

/// Reads a tape. A last line cut off (handd killed while writing it) is left out.
pub fn read(path: &Path) -> Result<Vec<Entry>, TapeError> {
    let err = |source| TapeError::Read {
        path: path.to_owned(),
        source,
    };
    let mut input = std::io::BufReader::new(std::fs::File::open(path).map_err(err)?);
    let mut entries = Vec::new();
    let mut line = String::new();
    let mut n = 0;
    loop {
        line.clear();
        if input.read_line(&mut line).map_err(err)? == 0 || !line.ends_with('\n') {
            break;
        }
        n += 1;
        let text = line.trim_end();
        if n == 1 {
            if text != HEADER {
                return Err(TapeError::NotATape(path.to_owned()));
            }
            continue;
        }
        if text.is_empty() || text.starts_with('#') {
            continue;
        }
        entries.push(
            text.parse()
                .map_err(|source| TapeError::Line { line: n, source })?,
        );
    }
    if n == 0 {
        return Err(TapeError::NotATape(path.to_owned()));
    }
    Ok(entries)
}

/// Where a replay stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum End {
    /// At the tape's end.
    Tape,
    /// At a model swap, at this time (the new model is not on the tape).
    Swap {
        /// When, µs.
        at_us: u64,
    },
    /// Where the recorder lost entries.
    Lost {
        /// How many.
        entries: u64,
    },
}

/// A round of frames that differs.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Difference {
    /// The round's deadline (a tick's), or the last deadline before it (safe stops between
    /// ticks), µs.
    pub at_us: u64,
    /// What the tape says the engine returned.
    pub recorded: Vec<CanFrame>,
    /// What the replay's engine returned.
    pub replayed: Vec<CanFrame>,
}

/// What a replay found.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Replay {
    /// Ticks replayed.
    pub ticks: u64,
    /// Rounds (ticks, safe stops between them, the last before exit) whose frames match.
    pub matched: u64,
    /// Rounds whose frames differ (the first [`MAX_DIFFERENCES`]).
    pub differences: Vec<Difference>,
    /// Rounds that differ, all of them.
    pub differing: u64,
    /// Where it stopped.
    pub end: End,
}

/// Differences a [`Replay`] keeps.
pub const MAX_DIFFERENCES: usize = 10;

struct Round {
    at_us: u64,
    replayed: Vec<CanFrame>,
    recorded: Vec<CanFrame>,
}

impl Replay {
    fn close(&mut self, round: Option<Round>) {
        let Some(r) = round else { return };
        if r.recorded == r.replayed {
            self.matched += 1;
        } else {
            self.differing += 1;
            if self.differences.len() < MAX_DIFFERENCES {
                self.differences.push(Difference {
                    at_us: r.at_us,
                    recorded: r.recorded,
                    replayed: r.replayed,
                });
            }
        }
    }
}

/// Replays `entries` (a tape's) through a fresh engine for `chain` and `predictor` (None: the
/// tape's engine ran without a model) with `settings`, the ones the daemon derived from its
/// config and model (`crate::startup::engine_settings`).
pub fn replay(
    entries: &[Entry],
    chain: &ChainSettings,
    predictor: Option<Predictor>,
    settings: EngineSettings,
) -> Result<Replay, TapeError> {
    let Some(&Entry::Built {
        at_us,
        epochs,
        model_id,
    }) = entries.first()
    else {
        return Err(TapeError::NoStart);
    };
    if model_id != settings.model_id {
        return Err(TapeError::OtherModel {
            tape: model_id,
            given: settings.model_id,
        });
    }
    let mut engine = match predictor {
        Some(p) => Engine::new(chain, p, settings, at_us),
        None => Engine::without_model(chain, settings, at_us),
    }
    .with_epochs(epochs);
    let mut report = Replay {
        ticks: 0,
        matched: 0,
        differences: Vec::new(),
        differing: 0,
        end: End::Tape,
    };
    let mut round: Option<Round> = None;
    let mut last_deadline = at_us;
    for e in &entries[1..] {
        if let Entry::Out { frame } = e {
            if let Some(r) = &mut round {
                r.recorded.push(*frame);
            }
            continue;
        }
        report.close(round.take());
        match *e {
            Entry::Built { .. } => return Err(TapeError::NoStart),
            Entry::Validated { at_us } => engine.validated(at_us),
            Entry::Restored {
                at_us,
                faults,
                hold,
            } => engine.restore(at_us, Latches::of(faults, hold)),
            Entry::Raised { at_us, fault } => engine.raise(at_us, fault),
            Entry::Command { at_us, command } => {
                let cmd = match command {
                    Recorded::Arm => Command::Arm,
                    Recorded::Stop => Command::Stop,
                    Recorded::Calibrating => Command::Calibrating,
                    Recorded::Gains(f, g) => Command::SetGains(usize::from(f), g),
                    // A swap the loop refused changed nothing.
                    Recorded::Swap { swapped: false, .. } => continue,
                    Recorded::Swap { swapped: true, .. } => {
                        report.end = End::Swap { at_us };
                        return Ok(report);
                    }
                };
                // A refused `arm` is refused again, the same way.
                let _ = engine.command(at_us, cmd);
            }
            Entry::Frame { rx_us, frame } => engine.on_frame(&frame, rx_us),
            Entry::Tick {
                deadline_us,
                started_us,
            } => {
                report.ticks += 1;
                last_deadline = deadline_us;
                round = Some(Round {
                    at_us: deadline_us,
                    replayed: engine.tick(deadline_us, started_us).to_vec(),
                    recorded: Vec::new(),
                });
            }
            Entry::SafeStops | Entry::Shutdown => {
                let replayed = if *e == Entry::SafeStops {
                    engine.safe_stop_frames().to_vec()
                } else {
                    engine.shutdown_frames().to_vec()
                };
                round = Some(Round {
                    at_us: last_deadline,
                    replayed,
                    recorded: Vec::new(),
                });
            }
            Entry::Written { at_us, compute_us } => engine.written(at_us, compute_us),
            Entry::BeganEpoch { finger, epoch } => engine.begin_epoch(usize::from(finger), epoch),
            Entry::NewEpoch => engine.new_epoch(),
            Entry::Lost { entries } => {
                report.end = End::Lost { entries };
                return Ok(report);
            }
            Entry::Out { .. } => unreachable!("handled above"),
        }
    }
    report.close(round.take());
    Ok(report)
}
