//! The classic CAN data frame CANopen uses (11-bit id, 0..=8 bytes), with conversion to and
//! from any [`embedded_can::Frame`] at the edge.

use embedded_can::{Id, StandardId};

/// One classic CAN data frame with an 11-bit identifier.
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub struct CanFrame {
    id: u16,
    len: u8,
    data: [u8; 8],
}

impl CanFrame {
    /// A frame; `None` if the id is beyond 11 bits or the data beyond 8 bytes.
    pub fn new(id: u16, data: &[u8]) -> Option<Self> {
        if id > 0x7FF || data.len() > 8 {
            return None;
        }
        let mut d = [0u8; 8];
        d[..data.len()].copy_from_slice(data);
        Some(Self {
            id,
            len: data.len() as u8,
            data: d,
        })
    }

    /// A frame from parts this crate built itself (id <= 0x7FF, len <= 8 by construction).
    pub(crate) fn from_parts(id: u16, len: usize, data: [u8; 8]) -> Self {
        debug_assert!(id <= 0x7FF && len <= 8);
        Self {
            id: id & 0x7FF,
            len: len.min(8) as u8,
            data,
        }
    }

    /// The 11-bit identifier (COB-ID).
    pub fn cob_id(&self) -> u16 {
        self.id
    }

    /// The payload.
    pub fn payload(&self) -> &[u8] {
        &self.data[..usize::from(self.len)]
    }

    /// Converts any standard data frame; `None` for extended or remote frames (CANopen's
    /// master subset uses neither).
    pub fn from_frame<F: embedded_can::Frame>(f: &F) -> Option<Self> {
        if f.is_remote_frame() {
            return None;
        }
        match f.id() {
            Id::Standard(s) => Self::new(s.as_raw(), f.data()),
            Id::Extended(_) => None,
        }
    }

    /// Converts into any [`embedded_can::Frame`] implementation.
    pub fn to_frame<F: embedded_can::Frame>(&self) -> Option<F> {
        F::new(StandardId::new(self.id)?, self.payload())
    }
}

impl core::fmt::Debug for CanFrame {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "{:03X}#", self.id)?;
        for b in self.payload() {
            write!(f, "{b:02X}")?;
        }
        Ok(())
    }
}

impl embedded_can::Frame for CanFrame {
    fn new(id: impl Into<Id>, data: &[u8]) -> Option<Self> {
        match id.into() {
            Id::Standard(s) => CanFrame::new(s.as_raw(), data),
            Id::Extended(_) => None,
        }
    }

    fn new_remote(_id: impl Into<Id>, _dlc: usize) -> Option<Self> {
        None
    }

    fn is_extended(&self) -> bool {
        false
    }

    fn is_remote_frame(&self) -> bool {
        false
    }

    fn id(&self) -> Id {
        Id::Standard(StandardId::new(self.id).unwrap_or(StandardId::ZERO))
    }

    fn dlc(&self) -> usize {
        usize::from(self.len)
    }

    fn data(&self) -> &[u8] {
        self.payload()
    }
}
