//! [`CanFrame`]: the one concrete classic-CAN frame type of handstack.
//!
//! The in-memory bus, candump logs and tests all move this type; real transports (SocketCAN)
//! have their own frame types, and the generated codec converts to and from any
//! [`embedded_can::Frame`], so nothing depends on this type being the one on the wire.

use core::fmt;

use embedded_can::{ExtendedId, Frame, Id, StandardId};

/// Largest payload of a classic CAN frame.
pub const MAX_DLC: usize = 8;

/// A classic CAN 2.0 frame: 11- or 29-bit id, 0..=8 data bytes, or a remote request.
///
/// The receive time is deliberately not part of the frame: it belongs to whoever received it
/// (see `hand_dbc::candump::LogEntry`).
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub struct CanFrame {
    id: Id,
    dlc: u8,
    data: [u8; MAX_DLC],
    remote: bool,
}

impl CanFrame {
    /// A data frame; `None` if `data` is longer than 8 bytes.
    pub fn new(id: impl Into<Id>, data: &[u8]) -> Option<Self> {
        if data.len() > MAX_DLC {
            return None;
        }
        let mut bytes = [0u8; MAX_DLC];
        bytes[..data.len()].copy_from_slice(data);
        Some(Self {
            id: id.into(),
            // Cannot truncate: checked against MAX_DLC above.
            dlc: data.len() as u8,
            data: bytes,
            remote: false,
        })
    }

    /// A data frame with an 11-bit id given as a number; `None` if the id exceeds 0x7FF or the
    /// payload exceeds 8 bytes.
    pub fn new_standard(id: u16, data: &[u8]) -> Option<Self> {
        Self::new(StandardId::new(id)?, data)
    }

    /// A data frame with a 29-bit id; `None` if the id exceeds 0x1FFF_FFFF or the payload
    /// exceeds 8 bytes.
    pub fn new_extended(id: u32, data: &[u8]) -> Option<Self> {
        Self::new(ExtendedId::new(id)?, data)
    }

    /// A remote (RTR) frame requesting `dlc` bytes; `None` if `dlc > 8`.
    pub fn new_remote(id: impl Into<Id>, dlc: usize) -> Option<Self> {
        if dlc > MAX_DLC {
            return None;
        }
        Some(Self {
            id: id.into(),
            dlc: dlc as u8,
            data: [0; MAX_DLC],
            remote: true,
        })
    }

    /// The id as a number, without any flag bits (11 or 29 significant bits).
    #[inline]
    pub fn raw_id(&self) -> u32 {
        match self.id {
            Id::Standard(id) => u32::from(id.as_raw()),
            Id::Extended(id) => id.as_raw(),
        }
    }

    /// The id.
    pub fn id(&self) -> Id {
        self.id
    }

    /// Payload bytes (empty for a remote frame).
    #[inline]
    pub fn data(&self) -> &[u8] {
        if self.remote {
            &[]
        } else {
            &self.data[..usize::from(self.dlc)]
        }
    }

    /// Data length code: payload length, or the requested length of a remote frame.
    pub fn dlc(&self) -> usize {
        usize::from(self.dlc)
    }

    /// True for an extended (29-bit) id.
    #[inline]
    pub fn is_extended(&self) -> bool {
        matches!(self.id, Id::Extended(_))
    }

    /// True for a remote (RTR) frame.
    #[inline]
    pub fn is_remote(&self) -> bool {
        self.remote
    }

    /// Mutable payload, for protection layers that rewrite bytes in place (E2E).
    pub fn data_mut(&mut self) -> &mut [u8] {
        if self.remote {
            &mut []
        } else {
            &mut self.data[..usize::from(self.dlc)]
        }
    }

    /// A frame for an id and payload that the code generator has validated (11-bit id, at most
    /// 8 bytes); keeps generated `to_frame` infallible.
    pub(crate) fn from_dbc(id: u32, data: &[u8]) -> Self {
        let id = StandardId::new((id & 0x7FF) as u16).unwrap_or(StandardId::ZERO);
        let len = data.len().min(MAX_DLC);
        let mut bytes = [0u8; MAX_DLC];
        bytes[..len].copy_from_slice(&data[..len]);
        Self {
            id: Id::Standard(id),
            dlc: len as u8,
            data: bytes,
            remote: false,
        }
    }

    /// Copies any [`embedded_can::Frame`] into a `CanFrame`; `None` if the other frame claims
    /// more than 8 bytes (a CAN FD frame).
    pub fn from_frame<F: Frame>(frame: &F) -> Option<Self> {
        if frame.is_remote_frame() {
            Self::new_remote(frame.id(), frame.dlc())
        } else {
            Self::new(frame.id(), frame.data())
        }
    }
}

impl Frame for CanFrame {
    fn new(id: impl Into<Id>, data: &[u8]) -> Option<Self> {
        CanFrame::new(id, data)
    }

    fn new_remote(id: impl Into<Id>, dlc: usize) -> Option<Self> {
        CanFrame::new_remote(id, dlc)
    }

    fn is_extended(&self) -> bool {
        CanFrame::is_extended(self)
    }

    fn is_remote_frame(&self) -> bool {
        self.remote
    }

    fn id(&self) -> Id {
        self.id
    }

    fn dlc(&self) -> usize {
        usize::from(self.dlc)
    }

    fn data(&self) -> &[u8] {
        CanFrame::data(self)
    }
}

/// candump's compact notation: `123#DEADBEEF`, `1234ABCD#00`, `123#R`, `123#R4`.
impl fmt::Display for CanFrame {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.id {
            Id::Standard(id) => write!(f, "{:03X}#", id.as_raw())?,
            Id::Extended(id) => write!(f, "{:08X}#", id.as_raw())?,
        }
        if self.remote {
            f.write_str("R")?;
            if self.dlc > 0 {
                write!(f, "{}", self.dlc)?;
            }
            return Ok(());
        }
        for byte in self.data() {
            write!(f, "{byte:02X}")?;
        }
        Ok(())
    }
}

impl fmt::Debug for CanFrame {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "CanFrame({self})")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn data_frame_round_trips_through_the_trait() {
        let frame = CanFrame::new_standard(0x123, &[0xDE, 0xAD]).expect("valid frame");
        let copy: CanFrame = Frame::new(Frame::id(&frame), Frame::data(&frame)).expect("valid");
        assert_eq!(copy, frame);
        assert_eq!(frame.raw_id(), 0x123);
        assert_eq!(frame.dlc(), 2);
        assert!(!frame.is_extended());
        assert_eq!(frame.to_string(), "123#DEAD");
    }

    #[test]
    fn limits_are_refused() {
        assert!(CanFrame::new_standard(0x800, &[]).is_none());
        assert!(CanFrame::new_extended(0x2000_0000, &[]).is_none());
        assert!(CanFrame::new_standard(1, &[0; 9]).is_none());
        assert!(CanFrame::new_remote(StandardId::ZERO, 9).is_none());
    }

    #[test]
    fn remote_and_extended_display() {
        let ext = CanFrame::new_extended(0x1234_ABCD, &[0]).expect("valid");
        assert_eq!(ext.to_string(), "1234ABCD#00");
        let rtr = CanFrame::new_remote(StandardId::new(0x7FF).expect("id"), 4).expect("valid");
        assert!(rtr.is_remote());
        assert!(rtr.data().is_empty());
        assert_eq!(rtr.dlc(), 4);
        assert_eq!(rtr.to_string(), "7FF#R4");
    }
}
