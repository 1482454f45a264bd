//! The real transport and clock: a raw SocketCAN socket (kernel receive timestamps, the time
//! base of `handctl record`'s logs) and the wall clock in µs since the Unix epoch, the same
//! base as those timestamps.

use std::time::{Duration, SystemTime, UNIX_EPOCH};

use crate::listen::Listener;
use hand_dbc::CanFrame;

use super::error::CalibrateError;
use super::workflow::{Pace, Transport};

/// The bus on SocketCAN.
pub struct SocketBus {
    sock: Listener,
    iface: String,
    /// Error frames read (not the calibration's business: the daemon reports the bus state).
    error_frames: u64,
}

impl SocketBus {
    /// Opens `iface` (checked up first), non-blocking, with receive timestamps.
    pub fn open(iface: &str) -> Result<Self, crate::error::CliError> {
        let sock = Listener::open(iface, Duration::ZERO, false)?;
        Ok(SocketBus {
            sock,
            iface: iface.to_owned(),
            error_frames: 0,
        })
    }

    /// The receive buffer the kernel granted and the one asked for, when it is smaller.
    pub fn small_rcvbuf(&self) -> Option<(usize, usize)> {
        self.sock.small_rcvbuf()
    }

    /// Frames the kernel dropped because this socket fell behind.
    pub fn kernel_drops(&self) -> u64 {
        self.sock.kernel_drops()
    }

    fn err(&self, what: &str, e: impl std::fmt::Display) -> CalibrateError {
        CalibrateError::Bus(format!("{}: {what}: {e}", self.iface))
    }
}

impl Transport for SocketBus {
    fn send(&mut self, frame: &CanFrame) -> Result<(), CalibrateError> {
        self.sock.send(frame).map_err(|e| self.err("send", e))
    }

    fn receive(&mut self) -> Result<Option<(CanFrame, u64)>, CalibrateError> {
        match self.sock.read_frame(&mut self.error_frames) {
            Ok(x) => Ok(x),
            Err(e) => Err(self.err("read", e)),
        }
    }
}

/// The wall clock, µs since the Unix epoch.
#[derive(Debug, Default)]
pub struct WallClock;

impl Pace for WallClock {
    fn now_us(&mut self) -> u64 {
        SystemTime::now()
            .duration_since(UNIX_EPOCH)
            .map_or(0, |d| d.as_micros() as u64)
    }

    fn wait_until(&mut self, t_us: u64) {
        let now = self.now_us();
        if t_us > now {
            std::thread::sleep(Duration::from_micros(t_us - now));
        }
    }
}
