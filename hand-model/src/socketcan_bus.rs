//! SocketCAN as a node transport: a `socketcan::CanSocket` that speaks `hand_dbc::CanFrame`,
//! so the same nodes run on `vcan0` or a real `can0` beside a real daemon.

use std::path::Path;

use embedded_can::Frame;

use crate::dbc::CanFrame;
use crate::world::Listens;

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

    /// Opens `iface` as [`SocketCanBus::open`] does, with the kernel's acceptance filter set
    /// to what the node reads: the kernel delivers nothing else to this socket.
    pub fn open_listening(iface: &str, listens: Listens) -> Result<Self, SocketBusError> {
        let bus = Self::open(iface)?;
        use socketcan::SocketOptions;
        let set = match listens {
            Listens::Nothing => bus.socket.set_filter_drop_all(),
            Listens::To(ids) => {
                // Standard ids, exactly: the mask covers the 11 id bits and the extended-frame
                // flag, so an extended frame with the same low bits does not pass.
                let filters: Vec<(u32, u32)> = ids
                    .iter()
                    .map(|&id| (id, libc_can::SFF_MASK | libc_can::EFF_FLAG))
                    .collect();
                bus.socket.set_filters(&filters)
            }
            Listens::Except(ids) => {
                // Joined: a frame passes when it matches every filter, each inverted on one id.
                let filters: Vec<socketcan::CanFilter> = ids
                    .iter()
                    .map(|&id| {
                        socketcan::CanFilter::new_inverted(
                            id,
                            libc_can::SFF_MASK | libc_can::EFF_FLAG,
                        )
                    })
                    .collect();
                bus.socket
                    .set_join_filters(true)
                    .and_then(|()| bus.socket.set_filters(&filters))
            }
        };
        set.map_err(|source| SocketBusError::Open {
            iface: iface.to_owned(),
            source,
        })?;
        Ok(bus)
    }
}

/// The two constants of linux/can.h the filters need.
mod libc_can {
    /// Standard frame id bits.
    pub const SFF_MASK: u32 = 0x7FF;
    /// Extended frame flag of `can_id`.
    pub const EFF_FLAG: u32 = 0x8000_0000;
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
