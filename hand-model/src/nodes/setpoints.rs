//! A stand-in for the daemon's output side: sends FINGER_SETPOINT_f at 20 Hz, correctly or
//! corrupted on purpose. Tests use it to exercise the motor controllers without a daemon;
//! `handsim` uses it for scenarios that move the hand without a decoder.
//!
//! It keeps the epoch protocol as handd does (hand.dbc, FINGER_SETPOINT's `Epoch`): every
//! frame carries its epoch, and the first frame of each epoch is a SAFE_STOP, whatever the
//! command; [`SetpointSource::new_epoch`] starts the next epoch, [`SetpointSource::set_epoch`]
//! lets a test play a stale sender.

use hand_dbc::messages::{FingerMode, FingerSetpoint};

use super::{Bus, NodeStats};
use crate::dbc::seal;
use crate::error::SimError;
use crate::finger::N_FINGERS;

/// Period of FINGER_SETPOINT (hand.dbc: 50 ms).
pub const SETPOINT_PERIOD_US: u64 = 50_000;

/// How the setpoints are sent.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SetpointCorruption {
    /// Correct frames.
    #[default]
    None,
    /// Every frame's CRC is wrong.
    BadCrc,
    /// The alive counter never changes (a hung sender repeating its buffer).
    StuckCounter,
    /// Nothing is sent (a killed daemon).
    Silent,
}

/// Sends setpoints for one finger.
#[derive(Debug, Clone)]
pub struct SetpointSource {
    finger: usize,
    mode: FingerMode,
    force_n: f64,
    velocity_rad_s: f64,
    corruption: SetpointCorruption,
    counter: u8,
    epoch: u16,
    opened: bool,
    next_us: u64,
    stats: NodeStats,
}

impl SetpointSource {
    /// A source for `finger`, first frame at `start_us`, commanding ACTIVE with zero force
    /// and velocity.
    pub fn try_new(finger: usize, start_us: u64) -> Result<Self, SimError> {
        if finger >= N_FINGERS {
            return Err(SimError::BadFinger(finger));
        }
        Ok(Self {
            finger,
            mode: FingerMode::Active,
            force_n: 0.0,
            velocity_rad_s: 0.0,
            corruption: SetpointCorruption::None,
            counter: 0,
            epoch: 0,
            opened: false,
            next_us: start_us,
            stats: NodeStats::default(),
        })
    }

    /// Sets the command; force and velocity are checked against hand.dbc's ranges.
    pub fn set(
        &mut self,
        mode: FingerMode,
        force_n: f64,
        velocity_rad_s: f64,
    ) -> Result<(), SimError> {
        FingerSetpoint::new(self.finger, mode, force_n, velocity_rad_s, self.epoch)
            .map_err(|e| SimError::BadScript(format!("setpoint: {e}")))?;
        self.mode = mode;
        self.force_n = force_n;
        self.velocity_rad_s = velocity_rad_s;
        Ok(())
    }

    /// The epoch of the frames it sends.
    pub fn epoch(&self) -> u16 {
        self.epoch
    }

    /// Starts the next epoch (+1, wrapping), opened by a SAFE_STOP as handd does.
    pub fn new_epoch(&mut self) {
        self.set_epoch(self.epoch.wrapping_add(1), true);
    }

    /// Sends in `epoch` from now on; with `open` its first frame is a SAFE_STOP, without it the
    /// command goes out as it is (a stale sender replaying an old epoch).
    pub fn set_epoch(&mut self, epoch: u16, open: bool) {
        self.epoch = epoch;
        self.opened = !open;
    }

    /// Switches corruption on or off.
    pub fn set_corruption(&mut self, c: SetpointCorruption) {
        self.corruption = c;
    }

    /// Transmit counts.
    pub fn stats(&self) -> NodeStats {
        self.stats
    }

    /// Sends the setpoints due by `now_us`.
    pub fn poll<B: Bus>(&mut self, now_us: u64, bus: &mut B) {
        while self.stats.receive(bus).is_some() {}
        while self.next_us <= now_us {
            self.next_us += SETPOINT_PERIOD_US;
            if self.corruption == SetpointCorruption::Silent {
                continue;
            }
            let (mode, force, velocity) = if self.opened {
                (self.mode, self.force_n, self.velocity_rad_s)
            } else {
                (FingerMode::SafeStop, 0.0, 0.0)
            };
            self.opened = true;
            let Ok(msg) = FingerSetpoint::new(self.finger, mode, force, velocity, self.epoch)
            else {
                // Unreachable: `set` checked the values against the DBC.
                self.stats.tx_errors += 1;
                continue;
            };
            let mut frame = msg.to_frame();
            let counter = self.counter;
            if self.corruption != SetpointCorruption::StuckCounter {
                self.counter = (self.counter + 1) & 0x0F;
            }
            let bad = self.corruption == SetpointCorruption::BadCrc;
            seal(&mut frame, FingerSetpoint::E2E[self.finger], counter, bad);
            self.stats.transmit(bus, &frame);
        }
    }
}
