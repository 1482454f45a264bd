//! One entry of a tape and its line: what the control loop gave the engine, or what the engine
//! gave back, in the order it happened.
//!
//! One line per entry, a letter and its fields, times in µs of handd's monotonic clock:
//!
//! | line | entry |
//! |---|---|
//! | `B AT E0,E1,E2,E3,E4 MODEL` | the engine built at `AT`, fingers in epochs `E0..E4`, model id (hex, 0: none) |
//! | `V AT` | config, model and bus validated |
//! | `L AT FAULTS HOLD` | latches restored from the previous process (fault bits hex, `free`/`calibrating`/`deployed`) |
//! | `R AT BIT` | a fault raised from outside the engine (bus-off, interface down, bus degraded), by bit |
//! | `C AT arm`, `stop`, `calibrating` | a technician's command |
//! | `C AT gains F KF KA WMAX DB SLEW D DREST RAMP` | new gains for finger F (each an f64's bits, hex) |
//! | `C AT swap MODEL 0/1` | a model swap and whether it took place |
//! | `F RX ID#DATA` | a frame received at `RX` (the time the loop used) |
//! | `T DEADLINE STARTED` | a tick due at `DEADLINE`, started at `STARTED` |
//! | `O ID#DATA` | a frame the engine returned to send, in order (after `T`, `S` or `Z`) |
//! | `S` | safe stops asked for between ticks (the bus came back) |
//! | `Z` | the last safe stops before exit |
//! | `W AT COMPUTE` | the tick's frames written at `AT` after `COMPUTE` µs |
//! | `E F EPOCH` | finger F put in epoch `EPOCH` |
//! | `N` | every finger's next epoch (after a bus recovery) |
//! | `X N` | the recorder lost `N` entries here (its queue was full): what follows does not replay |
//!
//! A line starting with `#` is a comment (the first line names the format).

use std::fmt;

use hand_dbc::CanFrame;

use crate::conditioner::FingerGains;
use crate::engine::Hold;
use crate::safety::{Fault, FaultSet};
use crate::units::N_FINGERS;

/// The first line of every tape.
pub const HEADER: &str = "# handstack tape 1";

/// A technician's command as a tape holds it (a swap's model is not on the tape, only its id).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Recorded {
    /// `arm`.
    Arm,
    /// `stop`.
    Stop,
    /// The calibrating hold began.
    Calibrating,
    /// New gains for one finger.
    Gains(u8, FingerGains),
    /// A model swap (deploy, rollback) and whether the loop took it.
    Swap {
        /// The new model's id.
        model_id: u32,
        /// Whether it was swapped in.
        swapped: bool,
    },
}

/// One thing the loop gave the engine or the engine gave back.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Entry {
    /// The engine was built.
    Built {
        /// When, µs.
        at_us: u64,
        /// Each finger's first epoch.
        epochs: [u16; N_FINGERS],
        /// The running model's id (0: none).
        model_id: u32,
    },
    /// `Engine::validated`.
    Validated {
        /// When, µs.
        at_us: u64,
    },
    /// `Engine::restore`.
    Restored {
        /// When, µs.
        at_us: u64,
        /// The latched faults taken over.
        faults: FaultSet,
        /// The calibrating hold taken over.
        hold: Hold,
    },
    /// `Engine::raise` from outside the engine.
    Raised {
        /// When, µs.
        at_us: u64,
        /// The fault.
        fault: Fault,
    },
    /// `Engine::command`.
    Command {
        /// When, µs.
        at_us: u64,
        /// What.
        command: Recorded,
    },
    /// `Engine::on_frame`.
    Frame {
        /// The receive time the loop used, µs.
        rx_us: u64,
        /// The frame.
        frame: CanFrame,
    },
    /// `Engine::tick`.
    Tick {
        /// Its deadline, µs.
        deadline_us: u64,
        /// When it started, µs.
        started_us: u64,
    },
    /// `Engine::safe_stop_frames`: safe stops between ticks.
    SafeStops,
    /// `Engine::shutdown_frames`: the last safe stops before exit.
    Shutdown,
    /// A frame the engine returned (from the last `Tick`, `SafeStops` or `Shutdown`).
    Out {
        /// The frame.
        frame: CanFrame,
    },
    /// `Engine::written`.
    Written {
        /// When, µs.
        at_us: u64,
        /// The tick's compute time, µs.
        compute_us: u64,
    },
    /// `Engine::begin_epoch`.
    BeganEpoch {
        /// The finger.
        finger: u8,
        /// Its epoch.
        epoch: u16,
    },
    /// `Engine::new_epoch`.
    NewEpoch,
    /// The recorder lost entries here (its queue was full).
    Lost {
        /// How many.
        entries: u64,
    },
}

fn hold_name(h: Hold) -> &'static str {
    match h {
        Hold::Free => "free",
        Hold::Calibrating => "calibrating",
        Hold::Deployed => "deployed",
    }
}

fn bit_of(f: Fault) -> usize {
    f.bit().trailing_zeros() as usize
}

fn gains_fields(g: &FingerGains) -> [f64; 8] {
    [
        g.kf,
        g.kalpha,
        g.omega_max,
        g.deadband,
        g.slew_per_s,
        g.damping_per_s,
        g.rest_damping_per_s,
        g.ramp_s,
    ]
}

impl fmt::Display for Entry {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Entry::Built {
                at_us,
                epochs: e,
                model_id,
            } => write!(
                f,
                "B {at_us} {},{},{},{},{} {model_id:08x}",
                e[0], e[1], e[2], e[3], e[4]
            ),
            Entry::Validated { at_us } => write!(f, "V {at_us}"),
            Entry::Restored {
                at_us,
                faults,
                hold,
            } => write!(f, "L {at_us} {:04x} {}", faults.0, hold_name(hold)),
            Entry::Raised { at_us, fault } => write!(f, "R {at_us} {}", bit_of(fault)),
            Entry::Command { at_us, command } => {
                write!(f, "C {at_us} ")?;
                match command {
                    Recorded::Arm => f.write_str("arm"),
                    Recorded::Stop => f.write_str("stop"),
                    Recorded::Calibrating => f.write_str("calibrating"),
                    Recorded::Gains(finger, g) => {
                        write!(f, "gains {finger}")?;
                        for v in gains_fields(&g) {
                            write!(f, " {:016x}", v.to_bits())?;
                        }
                        Ok(())
                    }
                    Recorded::Swap { model_id, swapped } => {
                        write!(f, "swap {model_id:08x} {}", u8::from(swapped))
                    }
                }
            }
            Entry::Frame { rx_us, frame } => write!(f, "F {rx_us} {frame}"),
            Entry::Tick {
                deadline_us,
                started_us,
            } => write!(f, "T {deadline_us} {started_us}"),
            Entry::Out { frame } => write!(f, "O {frame}"),
            Entry::SafeStops => f.write_str("S"),
            Entry::Shutdown => f.write_str("Z"),
            Entry::Written { at_us, compute_us } => write!(f, "W {at_us} {compute_us}"),
            Entry::BeganEpoch { finger, epoch } => write!(f, "E {finger} {epoch}"),
            Entry::NewEpoch => f.write_str("N"),
            Entry::Lost { entries } => write!(f, "X {entries}"),
        }
    }
}

/// Why a line is not an entry.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum EntryError {
    /// An unknown letter.
    #[error("unknown entry {0:?}")]
    Unknown(String),
    /// Fewer or more fields than the entry has.
    #[error("{0}: wrong number of fields")]
    Fields(char),
    /// A field that does not parse.
    #[error("{entry}: bad {what} {value:?}")]
    Field {
        /// The entry's letter.
        entry: char,
        /// Which field.
        what: &'static str,
        /// Its text.
        value: String,
    },
}

fn field<T>(
    entry: char,
    what: &'static str,
    value: &str,
    parse: impl Fn(&str) -> Result<T, ()>,
) -> Result<T, EntryError> {
    parse(value).map_err(|()| EntryError::Field {
        entry,
        what,
        value: value.to_string(),
    })
}

fn dec<T: std::str::FromStr>(s: &str) -> Result<T, ()> {
    s.parse().map_err(|_| ())
}

fn hex32(s: &str) -> Result<u32, ()> {
    u32::from_str_radix(s, 16).map_err(|_| ())
}

fn frame(s: &str) -> Result<CanFrame, ()> {
    hand_dbc::candump::parse_frame(s).map_err(|_| ())
}

impl std::str::FromStr for Entry {
    type Err = EntryError;

    fn from_str(line: &str) -> Result<Self, EntryError> {
        let mut parts = line.split_ascii_whitespace();
        let tag = parts.next().unwrap_or("");
        let rest: Vec<&str> = parts.collect();
        let c = tag.chars().next().unwrap_or('?');
        let n = |k: usize| {
            if rest.len() == k {
                Ok(())
            } else {
                Err(EntryError::Fields(c))
            }
        };
        let at = |i: usize| field(c, "time", rest[i], dec::<u64>);
        Ok(match tag {
            "B" => {
                n(3)?;
                let e: Vec<u16> = rest[1]
                    .split(',')
                    .map(dec::<u16>)
                    .collect::<Result<_, ()>>()
                    .map_err(|()| EntryError::Field {
                        entry: c,
                        what: "epochs",
                        value: rest[1].to_string(),
                    })?;
                let epochs: [u16; N_FINGERS] = e.try_into().map_err(|_| EntryError::Field {
                    entry: c,
                    what: "epochs",
                    value: rest[1].to_string(),
                })?;
                Entry::Built {
                    at_us: at(0)?,
                    epochs,
                    model_id: field(c, "model id", rest[2], hex32)?,
                }
            }
            "V" => {
                n(1)?;
                Entry::Validated { at_us: at(0)? }
            }
            "L" => {
                n(3)?;
                let faults = field(c, "fault bits", rest[1], |s| {
                    u16::from_str_radix(s, 16).map_err(|_| ())
                })?;
                let hold = field(c, "hold", rest[2], |s| match s {
                    "free" => Ok(Hold::Free),
                    "calibrating" => Ok(Hold::Calibrating),
                    "deployed" => Ok(Hold::Deployed),
                    _ => Err(()),
                })?;
                Entry::Restored {
                    at_us: at(0)?,
                    faults: FaultSet(faults),
                    hold,
                }
            }
            "R" => {
                n(2)?;
                let fault = field(c, "fault bit", rest[1], |s| {
                    dec::<usize>(s).and_then(|b| Fault::ALL.get(b).copied().ok_or(()))
                })?;
                Entry::Raised {
                    at_us: at(0)?,
                    fault,
                }
            }
            "C" => {
                if rest.len() < 2 {
                    return Err(EntryError::Fields(c));
                }
                let command = match (rest[1], rest.len()) {
                    ("arm", 2) => Recorded::Arm,
                    ("stop", 2) => Recorded::Stop,
                    ("calibrating", 2) => Recorded::Calibrating,
                    ("swap", 4) => Recorded::Swap {
                        model_id: field(c, "model id", rest[2], hex32)?,
                        swapped: field(c, "swapped", rest[3], |s| match s {
                            "0" => Ok(false),
                            "1" => Ok(true),
                            _ => Err(()),
                        })?,
                    },
                    ("gains", 11) => {
                        let finger = field(c, "finger", rest[2], |s| {
                            dec::<u8>(s).and_then(|f| {
                                if usize::from(f) < N_FINGERS {
                                    Ok(f)
                                } else {
                                    Err(())
                                }
                            })
                        })?;
                        let mut v = [0.0; 8];
                        for (k, slot) in v.iter_mut().enumerate() {
                            *slot = field(c, "gain", rest[3 + k], |s| {
                                u64::from_str_radix(s, 16)
                                    .map(f64::from_bits)
                                    .map_err(|_| ())
                            })?;
                        }
                        Recorded::Gains(
                            finger,
                            FingerGains {
                                kf: v[0],
                                kalpha: v[1],
                                omega_max: v[2],
                                deadband: v[3],
                                slew_per_s: v[4],
                                damping_per_s: v[5],
                                rest_damping_per_s: v[6],
                                ramp_s: v[7],
                            },
                        )
                    }
                    ("arm" | "stop" | "calibrating" | "swap" | "gains", _) => {
                        return Err(EntryError::Fields(c))
                    }
                    (other, _) => {
                        return Err(EntryError::Field {
                            entry: c,
                            what: "command",
                            value: other.to_string(),
                        })
                    }
                };
                Entry::Command {
                    at_us: at(0)?,
                    command,
                }
            }
            "F" => {
                n(2)?;
                Entry::Frame {
                    rx_us: at(0)?,
                    frame: field(c, "frame", rest[1], frame)?,
                }
            }
            "T" => {
                n(2)?;
                Entry::Tick {
                    deadline_us: at(0)?,
                    started_us: at(1)?,
                }
            }
            "O" => {
                n(1)?;
                Entry::Out {
                    frame: field(c, "frame", rest[0], frame)?,
                }
            }
            "W" => {
                n(2)?;
                Entry::Written {
                    at_us: at(0)?,
                    compute_us: at(1)?,
                }
            }
            "E" => {
                n(2)?;
                Entry::BeganEpoch {
                    finger: field(c, "finger", rest[0], |s| {
                        dec::<u8>(s).and_then(|f| {
                            if usize::from(f) < N_FINGERS {
                                Ok(f)
                            } else {
                                Err(())
                            }
                        })
                    })?,
                    epoch: field(c, "epoch", rest[1], dec::<u16>)?,
                }
            }
            "N" => {
                n(0)?;
                Entry::NewEpoch
            }
            "S" => {
                n(0)?;
                Entry::SafeStops
            }
            "Z" => {
                n(0)?;
                Entry::Shutdown
            }
            "X" => {
                n(1)?;
                Entry::Lost {
                    entries: field(c, "count", rest[0], dec::<u64>)?,
                }
            }
            other => return Err(EntryError::Unknown(other.to_string())),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn every_kind() -> Vec<Entry> {
        let frame = CanFrame::new_standard(0x100, &[1, 2, 3, 0xFF]).expect("frame");
        let gains = FingerGains {
            kf: 7.25,
            ramp_s: 0.1 + 0.2,
            ..FingerGains::default()
        };
        vec![
            Entry::Built {
                at_us: 12,
                epochs: [1, 2, 65535, 0, 9],
                model_id: 0xdead_beef,
            },
            Entry::Validated { at_us: 13 },
            Entry::Restored {
                at_us: 14,
                faults: FaultSet(0x8421),
                hold: Hold::Deployed,
            },
            Entry::Raised {
                at_us: 15,
                fault: Fault::BusDegraded,
            },
            Entry::Command {
                at_us: 16,
                command: Recorded::Arm,
            },
            Entry::Command {
                at_us: 16,
                command: Recorded::Stop,
            },
            Entry::Command {
                at_us: 16,
                command: Recorded::Calibrating,
            },
            Entry::Command {
                at_us: 17,
                command: Recorded::Gains(4, gains),
            },
            Entry::Command {
                at_us: 18,
                command: Recorded::Swap {
                    model_id: 3,
                    swapped: true,
                },
            },
            Entry::Frame { rx_us: 19, frame },
            Entry::Tick {
                deadline_us: 50_000,
                started_us: 50_210,
            },
            Entry::Out { frame },
            Entry::Written {
                at_us: 50_300,
                compute_us: 90,
            },
            Entry::BeganEpoch {
                finger: 3,
                epoch: 777,
            },
            Entry::NewEpoch,
            Entry::SafeStops,
            Entry::Shutdown,
            Entry::Lost { entries: 5 },
        ]
    }

    #[test]
    fn every_entry_reads_back_as_written_bit_for_bit() {
        for e in every_kind() {
            let line = e.to_string();
            let back: Entry = line.parse().unwrap_or_else(|err| panic!("{line}: {err}"));
            assert_eq!(back, e, "{line}");
            if let Entry::Command {
                command: Recorded::Gains(_, g),
                ..
            } = back
            {
                assert_eq!(g.ramp_s.to_bits(), (0.1f64 + 0.2).to_bits());
            }
        }
    }

    #[test]
    fn bad_lines_are_refused_with_what_is_wrong() {
        for (line, want) in [
            ("Q 1", "unknown entry"),
            ("T 1", "wrong number of fields"),
            ("T x 2", "bad time"),
            ("R 1 16", "bad fault bit"),
            ("E 5 1", "bad finger"),
            ("B 1 1,2,3 0", "bad epochs"),
            ("F 1 1000#00", "bad frame"),
            ("C 1 dance", "bad command"),
            ("C 1 swap 1", "wrong number of fields"),
            ("L 1 0 maybe", "bad hold"),
        ] {
            let err = line.parse::<Entry>().expect_err(line).to_string();
            assert!(err.contains(want), "{line}: {err}");
        }
    }
}
