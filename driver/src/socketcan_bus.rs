//! SocketCAN as the daemon's [`Transport`]: a non-blocking raw CAN socket with kernel receive
//! timestamps (SO_TIMESTAMPNS) and error frames switched on, so bus-off and error-passive
//! reach the daemon as errors, not as silence.
//!
//! Kernel timestamps are wall-clock times; they are mapped onto the daemon's monotonic clock
//! by the offset measured when the socket is opened (re-measured at every reopen), so latency
//! figures compare like with like. A wall-clock step between two opens shifts latencies by
//! that step until the next reopen: the figures are diagnostics, never used for control.

use std::path::Path;
use std::time::{SystemTime, UNIX_EPOCH};

use hand_clock::Clock;
use hand_dbc::CanFrame;
use socketcan::{CanSocket, EmbeddedFrame, Socket, SocketOptions};

use crate::transport::{Timestamped, Transport, TransportError};

/// Linux `CAN_ERR_*` bits of an error frame's id and `data[1]` (linux/can/error.h).
mod err {
    pub const CRTL: u32 = 0x0004;
    pub const BUSOFF: u32 = 0x0040;
    pub const RESTARTED: u32 = 0x0100;
    pub const CRTL_RX_PASSIVE: u8 = 0x10;
    pub const CRTL_TX_PASSIVE: u8 = 0x20;
}

/// A SocketCAN interface as a transport.
pub struct SocketCanTransport<K: Clock> {
    iface: String,
    socket: Option<CanSocket>,
    clock: K,
    offset_us: i128,
    /// Error frames that were neither bus-off nor error-passive (counted, not fatal).
    pub other_error_frames: u64,
}

fn wall_us() -> i128 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map(|d| d.as_micros() as i128)
        .unwrap_or(0)
}

/// Whether `iface` exists and is administratively up.
pub fn interface_up(iface: &str) -> Result<(), TransportError> {
    let dir = Path::new("/sys/class/net").join(iface);
    if !dir.exists() {
        return Err(TransportError::Down(format!(
            "no CAN interface {iface:?} (create it, e.g. `ip link add dev {iface} type vcan && \
             ip link set up {iface}`, or check the driver of a real CAN controller)"
        )));
    }
    let flags = std::fs::read_to_string(dir.join("flags")).unwrap_or_default();
    let flags = u32::from_str_radix(flags.trim().trim_start_matches("0x"), 16).unwrap_or(0);
    if flags & 1 == 0 {
        return Err(TransportError::Down(format!(
            "CAN interface {iface:?} is down (`ip link set up {iface}`)"
        )));
    }
    Ok(())
}

impl<K: Clock> SocketCanTransport<K> {
    /// Opens `iface`; the error says what is missing.
    pub fn open(iface: &str, clock: K) -> Result<Self, TransportError> {
        let mut t = Self::closed(iface, clock);
        t.reopen()?;
        Ok(t)
    }

    /// `iface`, not open yet: every receive and send fails until a [`Transport::reopen`]
    /// succeeds (handd starts this way when the bus is down, and reopens it with backoff).
    pub fn closed(iface: &str, clock: K) -> Self {
        Self {
            iface: iface.to_owned(),
            socket: None,
            clock,
            offset_us: 0,
            other_error_frames: 0,
        }
    }

    fn map_io(&self, e: std::io::Error) -> TransportError {
        match e.raw_os_error() {
            Some(code)
                if code == rustix::io::Errno::NETDOWN.raw_os_error()
                    || code == rustix::io::Errno::NXIO.raw_os_error()
                    || code == rustix::io::Errno::NODEV.raw_os_error() =>
            {
                TransportError::Down(format!("{}: {e}", self.iface))
            }
            _ => TransportError::Io(e),
        }
    }
}

impl<K: Clock> Transport for SocketCanTransport<K> {
    fn try_recv(&mut self) -> Result<Option<Timestamped>, TransportError> {
        loop {
            let Some(sock) = &self.socket else {
                return Err(TransportError::Down(format!("{} is closed", self.iface)));
            };
            let (frame, ts) = match sock.read_frame_with_timestamp() {
                Ok(x) => x,
                Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => return Ok(None),
                Err(e) => return Err(self.map_io(e)),
            };
            let ts_us = ts
                .duration_since(UNIX_EPOCH)
                .map(|d| d.as_micros() as i128)
                .unwrap_or(0);
            let rx_us = (ts_us - self.offset_us).max(0) as u64;
            let ours = match frame {
                socketcan::CanFrame::Data(d) => CanFrame::new(d.id(), d.data()),
                socketcan::CanFrame::Remote(r) => CanFrame::new_remote(r.id(), r.dlc()),
                socketcan::CanFrame::Error(e) => {
                    let bits = e.error_bits();
                    let ctrl = e.data().get(1).copied().unwrap_or(0);
                    if bits & err::BUSOFF != 0 {
                        return Err(TransportError::BusOff);
                    }
                    if bits & err::CRTL != 0
                        && ctrl & (err::CRTL_RX_PASSIVE | err::CRTL_TX_PASSIVE) != 0
                    {
                        return Err(TransportError::ErrorPassive);
                    }
                    if bits & err::RESTARTED == 0 {
                        self.other_error_frames += 1;
                    }
                    continue;
                }
            };
            if let Some(f) = ours {
                return Ok(Some((f, rx_us)));
            }
        }
    }

    fn send(&mut self, frame: &CanFrame) -> Result<(), TransportError> {
        let Some(sock) = &self.socket else {
            return Err(TransportError::Down(format!("{} is closed", self.iface)));
        };
        let out = socketcan::CanFrame::new(frame.id(), frame.data()).ok_or_else(|| {
            TransportError::Io(std::io::Error::new(
                std::io::ErrorKind::InvalidInput,
                "frame not representable",
            ))
        })?;
        sock.write_frame(&out).map_err(|e| self.map_io(e))
    }

    fn drop_queued(&mut self) {
        // Closing our socket stops this process writing until `reopen` (and then the daemon
        // sends only SAFE-state setpoints), but it purges nothing: `send` hands each frame
        // straight to the kernel, and a frame once written belongs to the interface, not to
        // the socket. On a real controller, frames still in the interface's qdisc (pfifo_fast,
        // txqueuelen 10 by default for CAN) or in the controller's transmit mailboxes can go
        // out after the bus recovers: under error-passive the controller keeps retrying them;
        // after bus-off it depends on the driver and the restart (a carrier drop resets the
        // qdisc; a controller restart may or may not clear the mailboxes). Such a stale
        // setpoint passes the motor controller's E2E check (its counter was in sequence).
        // Purging needs CAP_NET_ADMIN, which handd does not have: `tc qdisc replace dev <if>
        // root pfifo_fast` flushes the qdisc; `ip link set <if> down` stops the controller and
        // drops what it holds. (vcan has no queue: nothing is ever pending there.) What makes
        // such a frame harmless is the setpoint epoch (hand.dbc, can-dbc/README.md): the
        // daemon comes back in a new epoch and opens it with a SAFE_STOP, after which the
        // controller ignores every frame of the old one.
        self.socket = None;
    }

    fn reopen(&mut self) -> Result<(), TransportError> {
        self.socket = None;
        interface_up(&self.iface)?;
        let sock = CanSocket::open(&self.iface).map_err(|e| self.map_io(e))?;
        sock.set_nonblocking(true).map_err(|e| self.map_io(e))?;
        sock.set_recv_timestamp(true).map_err(|e| self.map_io(e))?;
        sock.set_error_filter_accept_all()
            .map_err(|e| self.map_io(e))?;
        self.offset_us = wall_us() - self.clock.now_us() as i128;
        self.socket = Some(sock);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_missing_interface_says_how_to_create_it() {
        let e = SocketCanTransport::open("nosuchcan9", hand_clock::SystemClock::new())
            .err()
            .expect("no such interface here");
        let msg = e.to_string();
        assert!(
            msg.contains("nosuchcan9") && msg.contains("type vcan"),
            "{msg}"
        );
    }
}
