//! Expedited SDO frames (CiA 301 7.2.4.3): client requests on 0x600 + node, server replies
//! on 0x580 + node. Segmented and block transfers are not part of this subset.

use super::abort::AbortCode;
use crate::frame::CanFrame;
use crate::ids::{NodeId, ObjectAddr};
use thiserror::Error;

/// 1..=4 bytes of expedited SDO data, little-endian as on the wire.
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub struct SdoData {
    len: u8,
    bytes: [u8; 4],
}

impl SdoData {
    /// Data of 1..=4 bytes; `None` otherwise.
    pub fn new(b: &[u8]) -> Option<Self> {
        if !(1..=4).contains(&b.len()) {
            return None;
        }
        let mut bytes = [0u8; 4];
        bytes[..b.len()].copy_from_slice(b);
        Some(Self {
            len: b.len() as u8,
            bytes,
        })
    }

    /// An UNSIGNED8 / INTEGER8 value.
    pub const fn u8(v: u8) -> Self {
        Self {
            len: 1,
            bytes: [v, 0, 0, 0],
        }
    }

    /// An UNSIGNED16 value.
    pub const fn u16(v: u16) -> Self {
        let b = v.to_le_bytes();
        Self {
            len: 2,
            bytes: [b[0], b[1], 0, 0],
        }
    }

    /// An UNSIGNED32 value.
    pub const fn u32(v: u32) -> Self {
        Self {
            len: 4,
            bytes: v.to_le_bytes(),
        }
    }

    /// An INTEGER8 value.
    pub fn i8(v: i8) -> Self {
        Self::u8(v as u8)
    }

    /// An INTEGER16 value.
    pub fn i16(v: i16) -> Self {
        Self::u16(v as u16)
    }

    /// An INTEGER32 value.
    pub fn i32(v: i32) -> Self {
        Self::u32(v as u32)
    }

    /// The bytes.
    pub fn bytes(&self) -> &[u8] {
        &self.bytes[..usize::from(self.len)]
    }

    /// The length, 1..=4.
    pub fn len(&self) -> usize {
        usize::from(self.len)
    }

    /// Never true (kept for the `len` convention).
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The value zero-extended to 32 bits.
    pub fn as_u32(&self) -> u32 {
        u32::from_le_bytes(self.bytes)
    }

    /// The value sign-extended from its length.
    pub fn as_i32(&self) -> i32 {
        let shift = 32 - 8 * u32::from(self.len);
        ((self.as_u32() << shift) as i32) >> shift
    }
}

impl core::fmt::Debug for SdoData {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "SdoData(")?;
        for b in self.bytes() {
            write!(f, "{b:02X}")?;
        }
        write!(f, ")")
    }
}

/// What can be wrong with an SDO frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Error)]
pub enum SdoFrameError {
    /// Not an SDO frame of the expected direction.
    #[error("COB-ID 0x{0:03X} is not an SDO frame of this direction")]
    WrongId(u16),
    /// From (or to) another node than expected.
    #[error("SDO frame for node {got}, expected {expected}")]
    WrongNode {
        /// The node expected.
        expected: u8,
        /// The node in the COB-ID.
        got: u8,
    },
    /// SDO frames are 8 bytes.
    #[error("SDO frame of {0} bytes (8 expected)")]
    Length(usize),
    /// An unknown or unsupported command specifier.
    #[error("unknown SDO command byte 0x{0:02X}")]
    UnknownCommand(u8),
    /// A segmented (non-expedited) transfer, outside this subset.
    #[error("segmented SDO transfer (command 0x{0:02X}); only expedited transfers are supported")]
    NotExpedited(u8),
}

/// A client -> server request (0x600 + node).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SdoRequest {
    /// Initiate upload (read).
    Upload(ObjectAddr),
    /// Expedited download (write).
    Download(ObjectAddr, SdoData),
    /// Abort by the client.
    Abort(ObjectAddr, AbortCode),
}

/// A server -> client reply (0x580 + node).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SdoReply {
    /// Expedited upload response with the data.
    Uploaded(ObjectAddr, SdoData),
    /// Download confirmed.
    Downloaded(ObjectAddr),
    /// Aborted by the server.
    Abort(ObjectAddr, AbortCode),
}

fn frame(id: u16, cmd: u8, addr: ObjectAddr, data: [u8; 4]) -> CanFrame {
    let i = addr.index.to_le_bytes();
    CanFrame::from_parts(
        id,
        8,
        [
            cmd, i[0], i[1], addr.sub, data[0], data[1], data[2], data[3],
        ],
    )
}

fn split(
    f: &CanFrame,
    base: u16,
    node: NodeId,
) -> Result<(u8, ObjectAddr, [u8; 4]), SdoFrameError> {
    let id = f.cob_id();
    if !(base + 1..=base + 0x7F).contains(&id) {
        return Err(SdoFrameError::WrongId(id));
    }
    let got = (id - base) as u8;
    if got != node.get() {
        return Err(SdoFrameError::WrongNode {
            expected: node.get(),
            got,
        });
    }
    let p = f.payload();
    if p.len() != 8 {
        return Err(SdoFrameError::Length(p.len()));
    }
    let addr = ObjectAddr::new(u16::from_le_bytes([p[1], p[2]]), p[3]);
    Ok((p[0], addr, [p[4], p[5], p[6], p[7]]))
}

/// Expedited data from a command byte with `e` set: `s` gives the size in bits 2-3,
/// no `s` means 4 bytes.
fn expedited(cmd: u8, d: [u8; 4]) -> SdoData {
    let n = if cmd & 0x01 != 0 {
        4 - usize::from((cmd >> 2) & 0x03)
    } else {
        4
    };
    SdoData {
        len: n as u8,
        bytes: d,
    }
    .masked()
}

impl SdoData {
    /// Clears the bytes beyond `len` (unused bytes are "don't care" on the wire).
    fn masked(mut self) -> Self {
        for b in &mut self.bytes[usize::from(self.len)..] {
            *b = 0;
        }
        self
    }
}

impl SdoRequest {
    /// The frame to `node` (0x600 + node).
    pub fn frame(&self, node: NodeId) -> CanFrame {
        let id = 0x600 + u16::from(node.get());
        match *self {
            Self::Upload(a) => frame(id, 0x40, a, [0; 4]),
            Self::Download(a, d) => frame(id, 0x23 | ((4 - d.len) << 2), a, d.masked().bytes),
            Self::Abort(a, c) => frame(id, 0x80, a, c.raw().to_le_bytes()),
        }
    }

    /// Decodes a request addressed to `node` (the server side).
    pub fn decode(f: &CanFrame, node: NodeId) -> Result<Self, SdoFrameError> {
        let (cmd, addr, d) = split(f, 0x600, node)?;
        match cmd >> 5 {
            1 if cmd & 0x02 == 0 => Err(SdoFrameError::NotExpedited(cmd)),
            1 => Ok(Self::Download(addr, expedited(cmd, d))),
            2 => Ok(Self::Upload(addr)),
            4 => Ok(Self::Abort(
                addr,
                AbortCode::from_raw(u32::from_le_bytes(d)),
            )),
            _ => Err(SdoFrameError::UnknownCommand(cmd)),
        }
    }

    /// The object addressed.
    pub fn addr(&self) -> ObjectAddr {
        match *self {
            Self::Upload(a) | Self::Download(a, _) | Self::Abort(a, _) => a,
        }
    }
}

impl SdoReply {
    /// The frame from `node` (0x580 + node).
    pub fn frame(&self, node: NodeId) -> CanFrame {
        let id = 0x580 + u16::from(node.get());
        match *self {
            Self::Uploaded(a, d) => frame(id, 0x43 | ((4 - d.len) << 2), a, d.masked().bytes),
            Self::Downloaded(a) => frame(id, 0x60, a, [0; 4]),
            Self::Abort(a, c) => frame(id, 0x80, a, c.raw().to_le_bytes()),
        }
    }

    /// Decodes a reply from `node` (the client side).
    pub fn decode(f: &CanFrame, node: NodeId) -> Result<Self, SdoFrameError> {
        let (cmd, addr, d) = split(f, 0x580, node)?;
        match cmd >> 5 {
            2 if cmd & 0x02 == 0 => Err(SdoFrameError::NotExpedited(cmd)),
            2 => Ok(Self::Uploaded(addr, expedited(cmd, d))),
            3 => Ok(Self::Downloaded(addr)),
            4 => Ok(Self::Abort(
                addr,
                AbortCode::from_raw(u32::from_le_bytes(d)),
            )),
            _ => Err(SdoFrameError::UnknownCommand(cmd)),
        }
    }

    /// The object the reply names.
    pub fn addr(&self) -> ObjectAddr {
        match *self {
            Self::Uploaded(a, _) | Self::Downloaded(a) | Self::Abort(a, _) => a,
        }
    }
}
