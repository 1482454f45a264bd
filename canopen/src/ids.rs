//! Identifier newtypes: node ids, COB-IDs, object dictionary addresses.

use thiserror::Error;

/// A CANopen node id, 1..=127 (0 addresses every node in NMT and is never a node's own id).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct NodeId(u8);

/// A node id outside 1..=127.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Error)]
#[error("node id {0} is outside 1..=127")]
pub struct BadNodeId(pub u8);

impl NodeId {
    /// Validates 1..=127.
    pub fn try_new(id: u8) -> Result<Self, BadNodeId> {
        if (1..=127).contains(&id) {
            Ok(Self(id))
        } else {
            Err(BadNodeId(id))
        }
    }

    /// The raw id.
    pub fn get(self) -> u8 {
        self.0
    }
}

impl core::fmt::Display for NodeId {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "node {}", self.0)
    }
}

/// The CiA 301 predefined connection set: function code of each COB-ID (base + node id).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Function {
    /// 0x000: NMT command.
    Nmt,
    /// 0x080: SYNC (no node id).
    Sync,
    /// 0x080 + node: EMCY.
    Emcy,
    /// 0x180/0x280/0x380/0x480 + node: TPDO1..4 (number 1..=4).
    Tpdo(u8),
    /// 0x200/0x300/0x400/0x500 + node: RPDO1..4 (number 1..=4).
    Rpdo(u8),
    /// 0x580 + node: SDO server -> client.
    SdoTx,
    /// 0x600 + node: SDO client -> server.
    SdoRx,
    /// 0x700 + node: NMT error control (boot-up, heartbeat).
    Heartbeat,
}

/// An 11-bit COB-ID.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct CobId(u16);

impl CobId {
    /// The NMT command id.
    pub const NMT: CobId = CobId(0x000);
    /// The SYNC id.
    pub const SYNC: CobId = CobId(0x080);

    /// Validates 11 bits.
    pub fn try_new(raw: u16) -> Option<Self> {
        (raw <= 0x7FF).then_some(Self(raw))
    }

    /// The predefined-connection-set COB-ID of `function` for `node` (SYNC and NMT ignore
    /// the node; a PDO number outside 1..=4 gives `None`).
    pub fn of(function: Function, node: NodeId) -> Option<Self> {
        let n = u16::from(node.get());
        let raw = match function {
            Function::Nmt => 0x000,
            Function::Sync => 0x080,
            Function::Emcy => 0x080 + n,
            Function::Tpdo(k @ 1..=4) => 0x080 + 0x100 * u16::from(k) + n,
            Function::Rpdo(k @ 1..=4) => 0x100 + 0x100 * u16::from(k) + n,
            Function::Tpdo(_) | Function::Rpdo(_) => return None,
            Function::SdoTx => 0x580 + n,
            Function::SdoRx => 0x600 + n,
            Function::Heartbeat => 0x700 + n,
        };
        Some(Self(raw))
    }

    /// Splits a COB-ID into function and node per the predefined connection set.
    pub fn split(self) -> Option<(Function, Option<NodeId>)> {
        let node = (self.0 & 0x7F) as u8;
        let code = self.0 >> 7;
        let with_node = |f| NodeId::try_new(node).ok().map(|n| (f, Some(n)));
        match (code, node) {
            (0, 0) => Some((Function::Nmt, None)),
            (1, 0) => Some((Function::Sync, None)),
            (1, _) => with_node(Function::Emcy),
            (3 | 5 | 7 | 9, _) => with_node(Function::Tpdo(((code - 1) / 2) as u8)),
            (4 | 6 | 8 | 10, _) => with_node(Function::Rpdo(((code - 2) / 2) as u8)),
            (11, _) => with_node(Function::SdoTx),
            (12, _) => with_node(Function::SdoRx),
            (14, _) => with_node(Function::Heartbeat),
            _ => None,
        }
    }

    /// Every COB-ID of the predefined connection set that `node` uses (EMCY, 4 TPDOs,
    /// 4 RPDOs, the two SDO channels, heartbeat): for collision checks against other ids.
    pub fn all_of(node: NodeId) -> [CobId; 12] {
        let n = u16::from(node.get());
        [
            0x080, 0x180, 0x280, 0x380, 0x480, 0x200, 0x300, 0x400, 0x500, 0x580, 0x600, 0x700,
        ]
        .map(|b| CobId(b + n))
    }

    /// The raw 11-bit value.
    pub fn raw(self) -> u16 {
        self.0
    }
}

/// An object dictionary index.
pub type Index = u16;
/// An object dictionary subindex.
pub type SubIndex = u8;

/// One object dictionary entry: index and subindex.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct ObjectAddr {
    /// Index (0x1000..=0x9FFF for the objects this crate uses).
    pub index: Index,
    /// Subindex.
    pub sub: SubIndex,
}

impl ObjectAddr {
    /// An address.
    pub const fn new(index: Index, sub: SubIndex) -> Self {
        Self { index, sub }
    }
}

impl core::fmt::Display for ObjectAddr {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "0x{:04X}:{:02X}", self.index, self.sub)
    }
}
