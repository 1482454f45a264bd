//! The real transport and clock: a raw SocketCAN socket (kernel receive timestamps, the time
//! base of `handctl record`'s logs) and the wall clock in µs since the Unix epoch, the same
//! base as those timestamps.

use std::time::{Duration, SystemTime, UNIX_EPOCH};

use hand_dbc::CanFrame;
use socketcan::{CanSocket, EmbeddedFrame, Socket, StandardId};

use super::error::CalibrateError;
use super::workflow::{Pace, Transport};

/// The bus on SocketCAN.
pub struct SocketBus {
    sock: CanSocket,
    iface: String,
}

impl SocketBus {
    /// Opens `iface` (checked up first), non-blocking, with receive timestamps.
    pub fn open(iface: &str) -> Result<Self, crate::error::CliError> {
        let sock = crate::listen::open(iface, Duration::from_millis(1), false)?;
        sock.set_nonblocking(true)
            .map_err(|source| crate::error::CliError::Can {
                iface: iface.to_owned(),
                what: "cannot make it non-blocking".into(),
                source,
            })?;
        Ok(SocketBus {
            sock,
            iface: iface.to_owned(),
        })
    }

    fn err(&self, what: &str, e: impl std::fmt::Display) -> CalibrateError {
        CalibrateError::Bus(format!("{}: {what}: {e}", self.iface))
    }
}

impl Transport for SocketBus {
    fn send(&mut self, frame: &CanFrame) -> Result<(), CalibrateError> {
        let id = StandardId::new(frame.raw_id() as u16)
            .ok_or_else(|| self.err("send", "not a standard id"))?;
        let f = socketcan::CanFrame::new(id, frame.data())
            .ok_or_else(|| self.err("send", "bad frame"))?;
        self.sock.write_frame(&f).map_err(|e| self.err("send", e))
    }

    fn receive(&mut self) -> Result<Option<(CanFrame, u64)>, CalibrateError> {
        loop {
            let Some((frame, t)) =
                crate::listen::read(&self.sock).map_err(|e| self.err("read", e))?
            else {
                return Ok(None);
            };
            let ours = match frame {
                socketcan::CanFrame::Data(d) => CanFrame::new(d.id(), d.data()),
                socketcan::CanFrame::Remote(r) => CanFrame::new_remote(r.id(), r.dlc()),
                socketcan::CanFrame::Error(_) => None,
            };
            if let Some(f) = ours {
                return Ok(Some((f, t)));
            }
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
