//! The master's walk to Operation enabled: one command per observed state, the statusword
//! checked at each step, a timeout per step, fault reset as a clean 0 -> 1 edge on bit 7.

use super::controlword::{Command, Controlword};
use super::state::{PowerState, Statusword};
use super::transitions::toward_operation_enabled;
use thiserror::Error;

/// Why the walk failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Error)]
pub enum Cia402Error {
    /// The drive stayed in `state` longer than the step timeout.
    #[error(
        "drive stayed in {state} for {timeout_us} us (waiting for it to leave after {sent:?})"
    )]
    StepTimeout {
        /// The state it stayed in.
        state: PowerState,
        /// The last command sent in that state, if any.
        sent: Option<Command>,
        /// The per-step timeout.
        timeout_us: u64,
    },
    /// A statusword outside the CiA 402 state table.
    #[error("statusword 0x{0:04X} encodes no CiA 402 state")]
    UnknownStatusword(u16),
}

/// What the master does next.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DriverStep {
    /// Send this controlword, then read the statusword again.
    Send(Controlword),
    /// Read the statusword again (the drive is moving by itself or has not reacted yet).
    Wait,
    /// Operation enabled.
    Reached,
}

/// Walks one drive to Operation enabled.
#[derive(Clone, Debug)]
pub struct PowerDriver {
    step_timeout_us: u64,
    state: Option<PowerState>,
    deadline_us: u64,
    /// Controlwords sent since the drive entered `state`.
    sent: [Option<Controlword>; 2],
}

impl PowerDriver {
    /// A driver with a per-step timeout.
    pub fn new(step_timeout_us: u64) -> Self {
        Self {
            step_timeout_us,
            state: None,
            deadline_us: 0,
            sent: [None; 2],
        }
    }

    /// The last state seen.
    pub fn state(&self) -> Option<PowerState> {
        self.state
    }

    fn last_command(&self) -> Option<Command> {
        let state = self.state?;
        self.sent[1]
            .or(self.sent[0])
            .and(toward_operation_enabled(state))
    }

    /// Checks the step deadline when no statusword arrived.
    pub fn poll(&self, now_us: u64) -> Result<(), Cia402Error> {
        match self.state {
            Some(state) if now_us >= self.deadline_us => Err(Cia402Error::StepTimeout {
                state,
                sent: self.last_command(),
                timeout_us: self.step_timeout_us,
            }),
            _ => Ok(()),
        }
    }

    /// Takes a statusword read at `now`; the next step.
    pub fn step(&mut self, sw: Statusword, now_us: u64) -> Result<DriverStep, Cia402Error> {
        let state = sw.state().ok_or(Cia402Error::UnknownStatusword(sw.0))?;
        if self.state != Some(state) {
            self.state = Some(state);
            self.deadline_us = now_us.saturating_add(self.step_timeout_us);
            self.sent = [None; 2];
        }
        self.poll(now_us)?;
        let Some(command) = toward_operation_enabled(state) else {
            return Ok(if state == PowerState::OperationEnabled {
                DriverStep::Reached
            } else {
                DriverStep::Wait
            });
        };
        let next = match (command, self.sent) {
            // Fault reset: bit 7 low first, then high, so the drive sees a clean edge.
            (Command::FaultReset, [None, _]) => Some(Controlword::FAULT_RESET_LOW),
            (Command::FaultReset, [Some(_), None]) => Some(command.controlword()),
            (_, [None, _]) => Some(command.controlword()),
            _ => None,
        };
        Ok(match next {
            Some(cw) => {
                let slot = usize::from(self.sent[0].is_some());
                self.sent[slot] = Some(cw);
                DriverStep::Send(cw)
            }
            None => DriverStep::Wait,
        })
    }
}
