//! SocketCAN as a node transport: a `socketcan::CanSocket` that speaks `hand_dbc::CanFrame`,
//! so the same nodes run on `vcan0` or a real `can0` beside a real daemon.

use std::path::Path;

use embedded_can::Frame;

use crate::dbc::CanFrame;

/// What can go wrong on a SocketCAN interface.
#[derive(Debug, thiserror::Error)]
pub enum SocketBusError {
    /// The interface does not exist (no CAN support in this kernel, or not created yet).
    #[error(
        "CAN interface {0:?} not found: create it first (e.g. `ip link add dev {0} type vcan && \
ip link set up {0}`; needs the vcan kernel module), or run handsim with --mem"
    )]
    NoSuchInterface(String),
    /// Opening the socket failed.
    #[error("cannot open CAN interface {iface:?}: {source}")]
    Open {
        /// Interface name.
        iface: String,
        /// The OS error.
        source: std::io::Error,
    },
    /// A frame that cannot be represented on the other side (CAN FD, error frame).
    #[error("frame not representable as a classic CAN frame")]
    Frame,
    /// A read or write failed.
    #[error("SocketCAN I/O: {0}")]
    Io(#[from] socketcan::Error),
}

impl embedded_can::Error for SocketBusError {
    fn kind(&self) -> embedded_can::ErrorKind {
        match self {
            SocketBusError::Io(e) => embedded_can::Error::kind(e),
            _ => embedded_can::ErrorKind::Other,
        }
    }
}

/// A non-blocking SocketCAN socket carrying [`CanFrame`]s.
#[derive(Debug)]
pub struct SocketCanBus {
    socket: socketcan::CanSocket,
}

impl SocketCanBus {
    /// Opens `iface` in non-blocking mode. Fails with [`SocketBusError::NoSuchInterface`] when
    /// the interface does not exist.
    pub fn open(iface: &str) -> Result<Self, SocketBusError> {
        if !Path::new("/sys/class/net").join(iface).exists() {
            return Err(SocketBusError::NoSuchInterface(iface.to_owned()));
        }
        use socketcan::Socket;
        let open_err = |source| SocketBusError::Open {
            iface: iface.to_owned(),
            source,
        };
        let socket = socketcan::CanSocket::open(iface).map_err(open_err)?;
        socket.set_nonblocking(true).map_err(open_err)?;
        Ok(Self { socket })
    }
}

impl embedded_can::nb::Can for SocketCanBus {
    type Frame = CanFrame;
    type Error = SocketBusError;

    fn transmit(&mut self, frame: &CanFrame) -> nb::Result<Option<CanFrame>, SocketBusError> {
        let out = socketcan::CanFrame::new(frame.id(), frame.data())
            .ok_or(nb::Error::Other(SocketBusError::Frame))?;
        match embedded_can::nb::Can::transmit(&mut self.socket, &out) {
            Ok(_) => Ok(None),
            Err(nb::Error::WouldBlock) => Err(nb::Error::WouldBlock),
            Err(nb::Error::Other(e)) => Err(nb::Error::Other(e.into())),
        }
    }

    fn receive(&mut self) -> nb::Result<CanFrame, SocketBusError> {
        match embedded_can::nb::Can::receive(&mut self.socket) {
            Ok(f) => CanFrame::from_frame(&f).ok_or(nb::Error::Other(SocketBusError::Frame)),
            Err(nb::Error::WouldBlock) => Err(nb::Error::WouldBlock),
            Err(nb::Error::Other(e)) => Err(nb::Error::Other(e.into())),
        }
    }
}
