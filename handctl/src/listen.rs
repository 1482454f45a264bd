//! A listen-only raw CAN socket with kernel receive timestamps, shared by `handctl record` and
//! the monitor's bus source: they never write to the bus.

use std::time::{Duration, UNIX_EPOCH};

use socketcan::{CanSocket, Socket, SocketOptions};

use super::error::CliError;

/// Opens `iface` (checked up first) for reading with kernel receive timestamps; a read waits at
/// most `timeout`. With `error_frames` the kernel's error frames are delivered too.
pub fn open(iface: &str, timeout: Duration, error_frames: bool) -> Result<CanSocket, CliError> {
    driver::socketcan_bus::interface_up(iface)?;
    let bad = |source| CliError::Can {
        iface: iface.to_owned(),
        what: "cannot open it".into(),
        source,
    };
    let sock = CanSocket::open(iface).map_err(bad)?;
    sock.set_recv_timestamp(true).map_err(bad)?;
    if error_frames {
        sock.set_error_filter_accept_all().map_err(bad)?;
    }
    sock.set_read_timeout(timeout).map_err(bad)?;
    Ok(sock)
}

/// The next frame and its kernel receive time (µs since the Unix epoch); `None` when the read
/// timed out.
pub fn read(sock: &CanSocket) -> std::io::Result<Option<(socketcan::CanFrame, u64)>> {
    match sock.read_frame_with_timestamp() {
        Ok((frame, ts)) => {
            let t = ts
                .duration_since(UNIX_EPOCH)
                .map_or(0, |d| d.as_micros() as u64);
            Ok(Some((frame, t)))
        }
        Err(e)
            if matches!(
                e.kind(),
                std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
            ) =>
        {
            Ok(None)
        }
        Err(e) => Err(e),
    }
}
