//! SocketCAN as the daemon's [`Transport`]: a non-blocking raw CAN socket with kernel receive
//! timestamps (SO_TIMESTAMPNS) and error frames switched on, so the controller's error state
//! reaches the daemon, not silence: bus-off as an error ([`TransportError::BusOff`]), warning
//! and error-passive (and the return to error-active) as the controller state in
//! [`Transport::health`], every error class counted ([`crate::transport::BusCounters`]). A
//! full transmit queue (ENOBUFS) is [`TransportError::QueueFull`], not a dead bus. Frames the
//! kernel drops from a full receive queue (SO_RXQ_OVFL, read with each frame's stamp by
//! [`crate::can_recv`]) are counted as `kernel_drops`, not left to look like a silent amplifier.
//!
//! The receive buffer is sized for [`RCVBUF_BYTES`] (a few ticks of this bus); the kernel caps
//! the request at `net.core.rmem_max`, and handd logs the size it got when that is less (the
//! README's install section sets the sysctl). No kernel filter is set: handd reads every id on
//! the bus, because its bus-load figure and its count of unknown frames need them all.
//!
//! Kernel timestamps are wall-clock times; [`RxTimes`] maps them onto the daemon's monotonic
//! clock by an offset re-measured at every read, so a step of the wall clock (NTP's first
//! sync, `date -s`) neither stales every window nor hides frames past the tick's deadline.

use std::path::Path;
use std::time::{SystemTime, UNIX_EPOCH};

use hand_clock::Clock;
use hand_dbc::CanFrame;
use socketcan::{CanSocket, EmbeddedFrame, Socket, SocketOptions};

use crate::can_recv::{self, KernelDrops, RawFrame, RecvBuf};
use crate::rx_times::RxTimes;
use crate::transport::{BusHealth, ControllerState, Timestamped, Transport, TransportError};

/// The receive buffer handd asks for: 200 ms of this bus at its worst case. hand.dbc's load is
/// about 3,500 frames/s (EMG 3,000/s, status 250/s, the rest about 250/s); each received CAN
/// frame costs the socket one skb, about 960 bytes of truesize on 64-bit kernels: 700 frames
/// in 200 ms, 672,000 bytes, rounded up to 656 KiB. 200 ms is four ticks: a tick that starts
/// three ticks late still finds every frame. The kernel default (208 KiB) holds about 60 ms.
/// Measured on Debian's 6.1 kernel with vcan (the VM suite): the kernel doubles the request
/// for its bookkeeping and a frame costs about 700 bytes there, so the queue holds about
/// 1,900 frames, 0.55 s of the bus (a 500 ms stall of handd lost none, a 700 ms stall of
/// `handctl record`, same size, lost 539); the figure above is the conservative floor.
pub const RCVBUF_BYTES: usize = 656 * 1024;

/// Linux `CAN_ERR_*` bits of an error frame's id and data bytes (linux/can/error.h).
mod err {
    pub const TX_TIMEOUT: u32 = 0x0001;
    pub const LOSTARB: u32 = 0x0002;
    pub const CRTL: u32 = 0x0004;
    pub const PROT: u32 = 0x0008;
    pub const TRX: u32 = 0x0010;
    pub const ACK: u32 = 0x0020;
    pub const BUSOFF: u32 = 0x0040;
    pub const BUSERROR: u32 = 0x0080;
    pub const RESTARTED: u32 = 0x0100;
    pub const CNT: u32 = 0x0200;
    pub const CRTL_RX_OVERFLOW: u8 = 0x01;
    pub const CRTL_TX_OVERFLOW: u8 = 0x02;
    pub const CRTL_RX_WARNING: u8 = 0x04;
    pub const CRTL_TX_WARNING: u8 = 0x08;
    pub const CRTL_RX_PASSIVE: u8 = 0x10;
    pub const CRTL_TX_PASSIVE: u8 = 0x20;
    pub const CRTL_ACTIVE: u8 = 0x40;
}

/// `IFF_UP` of `/sys/class/net/<if>/flags`. The carrier (a CAN controller that is bus-off or
/// stopped has none) is `/sys/class/net/<if>/carrier`.
const IFF_UP: u32 = 0x1;

/// One error frame (`CAN_ERR_*` bits of its id, its data) applied to the controller's state
/// and the counters; true when it reports bus-off.
pub fn on_error_frame(bits: u32, data: &[u8], health: &mut BusHealth) -> bool {
    let c = &mut health.counters;
    let ctrl = data.get(1).copied().unwrap_or(0);
    if bits & err::RESTARTED != 0 {
        c.restarted += 1;
        health.state = ControllerState::ErrorActive;
    }
    if bits & err::ACK != 0 {
        c.no_ack += 1;
    }
    if bits & (err::PROT | err::BUSERROR) != 0 {
        c.protocol += 1;
    }
    if bits & (err::TX_TIMEOUT | err::LOSTARB | err::TRX) != 0 {
        c.other += 1;
    }
    if bits & err::CRTL != 0 {
        if ctrl & (err::CRTL_RX_OVERFLOW | err::CRTL_TX_OVERFLOW) != 0 {
            c.controller_overflow += 1;
        }
        if ctrl & (err::CRTL_RX_PASSIVE | err::CRTL_TX_PASSIVE) != 0 {
            c.passive += 1;
            health.state = ControllerState::ErrorPassive;
        } else if ctrl & (err::CRTL_RX_WARNING | err::CRTL_TX_WARNING) != 0 {
            c.warning += 1;
            health.state = ControllerState::Warning;
        } else if ctrl & err::CRTL_ACTIVE != 0 {
            health.state = ControllerState::ErrorActive;
        }
    } else if bits & err::CNT != 0 && health.state != ControllerState::BusOff {
        // The error counters alone (bytes 6 and 7: transmit, receive).
        let worst = data
            .get(6)
            .copied()
            .unwrap_or(0)
            .max(data.get(7).copied().unwrap_or(0));
        health.state = match worst {
            128.. => ControllerState::ErrorPassive,
            96..=127 => ControllerState::Warning,
            _ => ControllerState::ErrorActive,
        };
    }
    if bits & err::BUSOFF != 0 {
        c.bus_off += 1;
        health.state = ControllerState::BusOff;
        return true;
    }
    false
}

/// A SocketCAN interface as a transport.
pub struct SocketCanTransport<K: Clock> {
    iface: String,
    socket: Option<CanSocket>,
    clock: K,
    rx_times: RxTimes,
    rx_buf: RecvBuf,
    drops: KernelDrops,
    health: BusHealth,
}

fn wall_us() -> i128 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map(|d| d.as_micros() as i128)
        .unwrap_or(0)
}

/// Whether `iface` exists, is administratively up and has a carrier (a CAN controller that is
/// bus-off or stopped has none: reopening it would only fail at the first send).
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
    if flags & IFF_UP == 0 {
        return Err(TransportError::Down(format!(
            "CAN interface {iface:?} is down (`ip link set up {iface}`)"
        )));
    }
    // The carrier (not in `flags`: the kernel computes IFF_RUNNING for ioctl and netlink only).
    let carrier = std::fs::read_to_string(dir.join("carrier")).unwrap_or_default();
    if carrier.trim() != "1" {
        return Err(TransportError::Down(format!(
            "CAN interface {iface:?} has no carrier (the controller is bus-off or stopped; \
             `ip -details link show {iface}` shows its state)"
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
            rx_times: RxTimes::default(),
            rx_buf: RecvBuf::default(),
            drops: KernelDrops::default(),
            health: BusHealth::default(),
        }
    }

    fn map_io(&self, e: std::io::Error) -> TransportError {
        match e.raw_os_error() {
            Some(code) if code == rustix::io::Errno::NOBUFS.raw_os_error() => {
                TransportError::QueueFull
            }
            _ if e.kind() == std::io::ErrorKind::WouldBlock => TransportError::QueueFull,
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

/// Asks the kernel for a receive buffer of [`RCVBUF_BYTES`] on `sock`; returns what it granted
/// (the kernel caps the request at `net.core.rmem_max`). Shared by handd and handctl's
/// listen-only sockets (`handctl record`, the monitor, calibration).
pub fn size_receive_buffer(sock: &CanSocket) -> std::io::Result<usize> {
    use std::os::fd::AsFd;
    let fd = sock.as_fd();
    rustix::net::sockopt::set_socket_recv_buffer_size(fd, RCVBUF_BYTES)?;
    // The kernel doubles the request for its bookkeeping and caps it at rmem_max.
    Ok(rustix::net::sockopt::socket_recv_buffer_size(fd)? / 2)
}

impl<K: Clock> SocketCanTransport<K> {
    /// Asks for [`RCVBUF_BYTES`]; logs what the kernel granted when it is less.
    fn size_receive_buffer(&self, sock: &CanSocket) {
        match size_receive_buffer(sock) {
            Ok(got) if got < RCVBUF_BYTES => tracing::warn!(
                wanted = RCVBUF_BYTES,
                got,
                "CAN receive buffer smaller than wanted: set net.core.rmem_max to at least \
                 the wanted size (README, install) or a late tick may lose frames"
            ),
            Ok(_) => {}
            Err(e) => tracing::warn!(error = %e, "could not size the CAN receive buffer"),
        }
    }
}

impl<K: Clock> Transport for SocketCanTransport<K> {
    fn try_recv(&mut self) -> Result<Option<Timestamped>, TransportError> {
        use std::os::fd::AsRawFd;
        loop {
            let Some(sock) = &self.socket else {
                return Err(TransportError::Down(format!("{} is closed", self.iface)));
            };
            let (bytes, meta) = match can_recv::recv(sock.as_raw_fd(), &mut self.rx_buf) {
                Ok(x) => x,
                Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => return Ok(None),
                Err(e) => return Err(self.map_io(e)),
            };
            self.drops.seen(meta.drops);
            self.health.counters.kernel_drops = self.drops.total();
            if bytes != can_recv::CAN_MTU {
                // Not a classic frame (the socket is CAN 2.0 only): nothing handd can read.
                continue;
            }
            // Without a stamp (SO_TIMESTAMPNS refused), the frame's time is when it was read.
            let now_wall = wall_us();
            let ts_us = meta.stamp_us.unwrap_or(now_wall);
            let rx_us = self.rx_times.map(ts_us, now_wall, self.clock.now_us());
            self.health.counters.clock_steps = self.rx_times.steps();
            let raw = can_recv::decode(self.rx_buf.frame());
            if let RawFrame::Error { bits, data } = raw {
                if on_error_frame(bits, &data, &mut self.health) {
                    return Err(TransportError::BusOff);
                }
                continue;
            }
            let ours = raw.to_frame();
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
        self.drops.socket_closed();
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

    fn health(&self) -> BusHealth {
        self.health
    }

    fn reopen(&mut self) -> Result<(), TransportError> {
        if self.socket.take().is_some() {
            self.drops.socket_closed();
        }
        interface_up(&self.iface)?;
        let sock = CanSocket::open(&self.iface).map_err(|e| self.map_io(e))?;
        sock.set_nonblocking(true).map_err(|e| self.map_io(e))?;
        sock.set_recv_timestamp(true).map_err(|e| self.map_io(e))?;
        sock.set_error_filter_accept_all()
            .map_err(|e| self.map_io(e))?;
        self.size_receive_buffer(&sock);
        // Frames the kernel drops from a full receive queue, counted (kernel_drops).
        if let Err(e) = nix::sys::socket::setsockopt(&sock, nix::sys::socket::sockopt::RxqOvfl, &1)
        {
            tracing::warn!(error = %e, "could not enable SO_RXQ_OVFL: kernel drops will read 0");
        }
        self.health.state = ControllerState::ErrorActive;
        self.rx_times.reset();
        self.socket = Some(sock);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(bits: u32, ctrl: u8) -> (u32, [u8; 8]) {
        (bits, [0, ctrl, 0, 0, 0, 0, 0, 0])
    }

    #[test]
    fn error_passive_is_a_state_that_clears_and_only_bus_off_is_an_error() {
        let mut h = BusHealth::default();
        let (b, d) = frame(err::CRTL, err::CRTL_TX_WARNING);
        assert!(!on_error_frame(b, &d, &mut h));
        assert_eq!(h.state, ControllerState::Warning);
        let (b, d) = frame(err::CRTL | err::ACK, err::CRTL_TX_PASSIVE);
        assert!(
            !on_error_frame(b, &d, &mut h),
            "error-passive is not bus-off"
        );
        assert_eq!(h.state, ControllerState::ErrorPassive);
        let (b, d) = frame(err::CRTL, err::CRTL_ACTIVE);
        assert!(!on_error_frame(b, &d, &mut h));
        assert_eq!(
            h.state,
            ControllerState::ErrorActive,
            "back to error-active"
        );
        let (b, d) = frame(err::BUSOFF, 0);
        assert!(on_error_frame(b, &d, &mut h));
        assert_eq!(h.state, ControllerState::BusOff);
        let (b, d) = frame(err::RESTARTED, 0);
        assert!(!on_error_frame(b, &d, &mut h));
        assert_eq!(h.state, ControllerState::ErrorActive, "restarted");
        let (b, d) = frame(err::CRTL | err::PROT | err::LOSTARB, err::CRTL_RX_OVERFLOW);
        assert!(!on_error_frame(b, &d, &mut h));
        let c = h.counters;
        assert_eq!(
            (c.warning, c.passive, c.no_ack, c.bus_off, c.restarted),
            (1, 1, 1, 1, 1)
        );
        assert_eq!((c.controller_overflow, c.protocol, c.other), (1, 1, 1));
    }

    #[test]
    fn the_error_counters_alone_give_the_state() {
        let mut h = BusHealth::default();
        let cnt = |tx: u8, rx: u8| [0, 0, 0, 0, 0, 0, tx, rx];
        assert!(!on_error_frame(err::CNT, &cnt(130, 0), &mut h));
        assert_eq!(h.state, ControllerState::ErrorPassive);
        assert!(!on_error_frame(err::CNT, &cnt(0, 100), &mut h));
        assert_eq!(h.state, ControllerState::Warning);
        assert!(!on_error_frame(err::CNT, &cnt(3, 4), &mut h));
        assert_eq!(h.state, ControllerState::ErrorActive);
    }

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
