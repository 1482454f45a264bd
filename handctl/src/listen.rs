//! The raw CAN socket handctl reads the bus with (`handctl record`, the monitor's bus source,
//! the calibration's bus): kernel receive timestamps and the kernel's drop count, read with
//! each frame by the same `recvmsg` as handd's (`driver::can_recv`), and the receive buffer
//! handd asks for.
//!
//! A reader that falls behind (a slow disk, a loaded board) loses frames in the kernel when
//! the socket's receive queue is full; without SO_RXQ_OVFL the loss is silent and a recording
//! has gaps nobody sees. The count is here for every reader, and `handctl record` refuses a
//! recording that lost frames.

use std::os::fd::{AsFd, AsRawFd};
use std::time::Duration;

use driver::can_recv::{self, KernelDrops, RawFrame, RecvBuf};
use driver::socketcan_bus::{size_receive_buffer, RCVBUF_BYTES};
use hand_dbc::CanFrame;
use socketcan::{CanSocket, EmbeddedFrame, Socket, SocketOptions, StandardId};

use super::error::CliError;

/// A raw CAN socket on one interface, read with kernel stamps and drop counts.
pub struct Listener {
    sock: CanSocket,
    buf: RecvBuf,
    drops: KernelDrops,
    timeout: Duration,
    /// What the kernel granted of [`RCVBUF_BYTES`].
    rcvbuf: usize,
}

impl Listener {
    /// Opens `iface` (checked up first); a read waits at most `timeout` (zero: not at all).
    /// With `error_frames` the kernel's error frames are delivered too.
    pub fn open(iface: &str, timeout: Duration, error_frames: bool) -> Result<Self, CliError> {
        driver::socketcan_bus::interface_up(iface)?;
        let bad = |what: &str| {
            let what = what.to_owned();
            move |source| CliError::Can {
                iface: iface.to_owned(),
                what,
                source,
            }
        };
        let sock = CanSocket::open(iface).map_err(bad("cannot open it"))?;
        sock.set_nonblocking(true)
            .map_err(bad("cannot make it non-blocking"))?;
        sock.set_recv_timestamp(true)
            .map_err(bad("cannot switch on receive timestamps"))?;
        if error_frames {
            sock.set_error_filter_accept_all()
                .map_err(bad("cannot receive error frames"))?;
        }
        nix::sys::socket::setsockopt(&sock, nix::sys::socket::sockopt::RxqOvfl, &1)
            .map_err(|e| bad("cannot count the kernel's drops (SO_RXQ_OVFL)")(e.into()))?;
        let rcvbuf = size_receive_buffer(&sock).map_err(bad("cannot size the receive buffer"))?;
        Ok(Self {
            sock,
            buf: RecvBuf::default(),
            drops: KernelDrops::default(),
            timeout,
            rcvbuf,
        })
    }

    /// The next frame (data, remote or error) and its kernel receive time (µs since the Unix
    /// epoch); `None` when nothing came within the timeout.
    pub fn read(&mut self) -> std::io::Result<Option<(RawFrame, u64)>> {
        let mut waited = false;
        loop {
            match can_recv::recv(self.sock.as_raw_fd(), &mut self.buf) {
                Ok((bytes, meta)) => {
                    self.drops.seen(meta.drops);
                    if bytes != can_recv::CAN_MTU {
                        // Not a classic frame (the socket is CAN 2.0 only).
                        continue;
                    }
                    let stamp = meta.stamp_us.ok_or_else(|| {
                        std::io::Error::new(
                            std::io::ErrorKind::InvalidData,
                            "a frame without its kernel receive timestamp",
                        )
                    })?;
                    let t = u64::try_from(stamp).unwrap_or(0);
                    return Ok(Some((can_recv::decode(self.buf.frame()), t)));
                }
                Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => {
                    if waited || self.timeout.is_zero() {
                        return Ok(None);
                    }
                    waited = true;
                    self.wait_readable()?;
                }
                Err(e) => return Err(e),
            }
        }
    }

    /// The next data or remote frame as the codec's frame, skipping error frames (counted in
    /// `errors`); `None` when nothing came within the timeout.
    pub fn read_frame(&mut self, errors: &mut u64) -> std::io::Result<Option<(CanFrame, u64)>> {
        loop {
            let Some((raw, t)) = self.read()? else {
                return Ok(None);
            };
            if let RawFrame::Error { .. } = raw {
                *errors += 1;
                continue;
            }
            if let Some(f) = raw.to_frame() {
                return Ok(Some((f, t)));
            }
        }
    }

    /// Frames the kernel dropped because this socket's receive queue was full.
    pub fn kernel_drops(&self) -> u64 {
        self.drops.total()
    }

    /// The receive buffer the kernel granted, when less than handd's [`RCVBUF_BYTES`].
    pub fn small_rcvbuf(&self) -> Option<(usize, usize)> {
        (self.rcvbuf < RCVBUF_BYTES).then_some((self.rcvbuf, RCVBUF_BYTES))
    }

    /// Writes a standard-id data frame (the calibration's commands to handd's peers).
    pub fn send(&self, frame: &CanFrame) -> std::io::Result<()> {
        let bad = |what| std::io::Error::new(std::io::ErrorKind::InvalidInput, what);
        let id = u16::try_from(frame.raw_id())
            .ok()
            .and_then(StandardId::new)
            .ok_or_else(|| bad("not a standard id"))?;
        let f = socketcan::CanFrame::new(id, frame.data()).ok_or_else(|| bad("bad frame"))?;
        self.sock.write_frame(&f)
    }

    fn wait_readable(&self) -> std::io::Result<()> {
        use nix::poll::{poll, PollFd, PollFlags, PollTimeout};
        let ms = u16::try_from(self.timeout.as_millis()).unwrap_or(u16::MAX);
        let mut fds = [PollFd::new(self.sock.as_fd(), PollFlags::POLLIN)];
        match poll(&mut fds, PollTimeout::from(ms)) {
            Ok(_) => Ok(()),
            Err(nix::errno::Errno::EINTR) => Ok(()),
            Err(e) => Err(e.into()),
        }
    }
}
