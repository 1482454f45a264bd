//! The simulated drive's object dictionary: a table of object definitions (as the EDS
//! lists them) and the values, with the SDO access rules.

use crate::ids::{NodeId, ObjectAddr};
use crate::sdo::{AbortCode, SdoData};

/// SDO access of an object.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Access {
    /// Read only (the drive changes it).
    Ro,
    /// Read and write.
    Rw,
    /// Constant.
    Const,
}

/// One object dictionary entry's definition.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ObjectDef {
    /// Address.
    pub addr: ObjectAddr,
    /// Size in bytes (1, 2 or 4).
    pub bytes: u8,
    /// Signed type (INTEGERn).
    pub signed: bool,
    /// Access.
    pub access: Access,
    /// May be mapped into a PDO.
    pub mappable: bool,
    /// Default value (raw bits).
    pub default: u32,
    /// The default is `default + node id` ($NODEID in the EDS).
    pub plus_node: bool,
}

const fn d(
    index: u16,
    sub: u8,
    bytes: u8,
    signed: bool,
    access: Access,
    map: bool,
    default: u32,
) -> ObjectDef {
    ObjectDef {
        addr: ObjectAddr::new(index, sub),
        bytes,
        signed,
        access,
        mappable: map,
        default,
        plus_node: false,
    }
}

const fn n(index: u16, sub: u8, default: u32) -> ObjectDef {
    ObjectDef {
        plus_node: true,
        ..d(index, sub, 4, false, Access::Rw, false, default)
    }
}

use Access::{Const, Ro, Rw};

/// Vendor id the simulated drive reports (0x1018:01).
pub const SIM_VENDOR_ID: u32 = 0x0000_0A1D;
/// Product code (0x1018:02).
pub const SIM_PRODUCT: u32 = 0x0000_0402;
/// Supported modes (0x6502): profile velocity (3), cyclic synchronous velocity (9) and
/// torque (10).
pub const SIM_SUPPORTED_MODES: u32 = (1 << 2) | (1 << 8) | (1 << 9);

/// The finger drive's objects (the same as `eds/finger_drive.eds`).
pub const FINGER_DRIVE_OBJECTS: &[ObjectDef] = &[
    d(0x1000, 0, 4, false, Ro, false, 0x0002_0192),
    d(0x1001, 0, 1, false, Ro, false, 0),
    d(0x1005, 0, 4, false, Rw, false, 0x80),
    d(0x1016, 0, 1, false, Const, false, 1),
    d(0x1016, 1, 4, false, Rw, false, 0),
    d(0x1017, 0, 2, false, Rw, false, 0),
    d(0x1018, 0, 1, false, Const, false, 4),
    d(0x1018, 1, 4, false, Ro, false, SIM_VENDOR_ID),
    d(0x1018, 2, 4, false, Ro, false, SIM_PRODUCT),
    d(0x1018, 3, 4, false, Ro, false, 1),
    d(0x1018, 4, 4, false, Ro, false, 0x0000_0001),
    // RPDO1..4 communication and mapping
    d(0x1400, 0, 1, false, Const, false, 2),
    n(0x1400, 1, 0x200),
    d(0x1400, 2, 1, false, Rw, false, 0xFF),
    d(0x1401, 0, 1, false, Const, false, 2),
    n(0x1401, 1, 0x300),
    d(0x1401, 2, 1, false, Rw, false, 0xFF),
    d(0x1402, 0, 1, false, Const, false, 2),
    n(0x1402, 1, 0x8000_0400),
    d(0x1402, 2, 1, false, Rw, false, 0xFF),
    d(0x1403, 0, 1, false, Const, false, 2),
    n(0x1403, 1, 0x8000_0500),
    d(0x1403, 2, 1, false, Rw, false, 0xFF),
    d(0x1600, 0, 1, false, Rw, false, 1),
    d(0x1600, 1, 4, false, Rw, false, 0x6040_0010),
    d(0x1600, 2, 4, false, Rw, false, 0),
    d(0x1600, 3, 4, false, Rw, false, 0),
    d(0x1600, 4, 4, false, Rw, false, 0),
    d(0x1601, 0, 1, false, Rw, false, 2),
    d(0x1601, 1, 4, false, Rw, false, 0x6040_0010),
    d(0x1601, 2, 4, false, Rw, false, 0x60FF_0020),
    d(0x1601, 3, 4, false, Rw, false, 0),
    d(0x1601, 4, 4, false, Rw, false, 0),
    d(0x1602, 0, 1, false, Rw, false, 0),
    d(0x1602, 1, 4, false, Rw, false, 0),
    d(0x1602, 2, 4, false, Rw, false, 0),
    d(0x1602, 3, 4, false, Rw, false, 0),
    d(0x1602, 4, 4, false, Rw, false, 0),
    d(0x1603, 0, 1, false, Rw, false, 0),
    d(0x1603, 1, 4, false, Rw, false, 0),
    d(0x1603, 2, 4, false, Rw, false, 0),
    d(0x1603, 3, 4, false, Rw, false, 0),
    d(0x1603, 4, 4, false, Rw, false, 0),
    // TPDO1..4 communication and mapping
    d(0x1800, 0, 1, false, Const, false, 2),
    n(0x1800, 1, 0x180),
    d(0x1800, 2, 1, false, Rw, false, 0xFF),
    d(0x1801, 0, 1, false, Const, false, 2),
    n(0x1801, 1, 0x280),
    d(0x1801, 2, 1, false, Rw, false, 0xFF),
    d(0x1802, 0, 1, false, Const, false, 2),
    n(0x1802, 1, 0x8000_0380),
    d(0x1802, 2, 1, false, Rw, false, 0xFF),
    d(0x1803, 0, 1, false, Const, false, 2),
    n(0x1803, 1, 0x8000_0480),
    d(0x1803, 2, 1, false, Rw, false, 0xFF),
    d(0x1A00, 0, 1, false, Rw, false, 1),
    d(0x1A00, 1, 4, false, Rw, false, 0x6041_0010),
    d(0x1A00, 2, 4, false, Rw, false, 0),
    d(0x1A00, 3, 4, false, Rw, false, 0),
    d(0x1A00, 4, 4, false, Rw, false, 0),
    d(0x1A01, 0, 1, false, Rw, false, 2),
    d(0x1A01, 1, 4, false, Rw, false, 0x6041_0010),
    d(0x1A01, 2, 4, false, Rw, false, 0x6064_0020),
    d(0x1A01, 3, 4, false, Rw, false, 0),
    d(0x1A01, 4, 4, false, Rw, false, 0),
    d(0x1A02, 0, 1, false, Rw, false, 0),
    d(0x1A02, 1, 4, false, Rw, false, 0),
    d(0x1A02, 2, 4, false, Rw, false, 0),
    d(0x1A02, 3, 4, false, Rw, false, 0),
    d(0x1A02, 4, 4, false, Rw, false, 0),
    d(0x1A03, 0, 1, false, Rw, false, 0),
    d(0x1A03, 1, 4, false, Rw, false, 0),
    d(0x1A03, 2, 4, false, Rw, false, 0),
    d(0x1A03, 3, 4, false, Rw, false, 0),
    d(0x1A03, 4, 4, false, Rw, false, 0),
    // CiA 402
    d(0x603F, 0, 2, false, Ro, true, 0),
    d(0x6007, 0, 2, true, Rw, false, 1),
    d(0x6040, 0, 2, false, Rw, true, 0),
    d(0x6041, 0, 2, false, Ro, true, 0),
    d(0x605A, 0, 2, true, Rw, false, 2),
    d(0x6060, 0, 1, true, Rw, true, 0),
    d(0x6061, 0, 1, true, Ro, true, 0),
    d(0x6064, 0, 4, true, Ro, true, 0),
    d(0x606C, 0, 4, true, Ro, true, 0),
    d(0x6071, 0, 2, true, Rw, true, 0),
    d(0x6072, 0, 2, false, Rw, true, 1000),
    d(0x6076, 0, 4, false, Rw, false, 100),
    d(0x6077, 0, 2, true, Ro, true, 0),
    d(0x60C2, 0, 1, false, Const, false, 2),
    d(0x60C2, 1, 1, false, Rw, false, 1),
    d(0x60C2, 2, 1, true, Rw, false, 0xFD),
    d(0x60FF, 0, 4, true, Rw, true, 0),
    d(0x6502, 0, 4, false, Ro, false, SIM_SUPPORTED_MODES),
];

/// Values of every object of a table.
#[derive(Clone, Debug)]
pub struct ObjectDictionary {
    node: NodeId,
    defs: &'static [ObjectDef],
    values: Vec<u32>,
}

impl ObjectDictionary {
    /// The dictionary of `defs` at its defaults for `node`.
    pub fn new(node: NodeId, defs: &'static [ObjectDef]) -> Self {
        let mut od = Self {
            node,
            defs,
            values: vec![0; defs.len()],
        };
        od.reset(|_| true);
        od
    }

    /// Resets the objects `which` selects to their defaults.
    pub fn reset(&mut self, which: impl Fn(&ObjectDef) -> bool) {
        for (def, v) in self.defs.iter().zip(&mut self.values) {
            if which(def) {
                *v = if def.plus_node {
                    def.default + u32::from(self.node.get())
                } else {
                    def.default
                };
            }
        }
    }

    /// The definition of an entry, or the abort a missing one gets.
    pub fn def(&self, addr: ObjectAddr) -> Result<&'static ObjectDef, AbortCode> {
        let defs: &'static [ObjectDef] = self.defs;
        match defs.iter().find(|d| d.addr == addr) {
            Some(d) => Ok(d),
            None if defs.iter().any(|d| d.addr.index == addr.index) => Err(AbortCode::NoSubIndex),
            None => Err(AbortCode::NoObject),
        }
    }

    fn slot(&self, addr: ObjectAddr) -> Option<usize> {
        self.defs.iter().position(|d| d.addr == addr)
    }

    /// The raw value (zero for a missing entry).
    pub fn get(&self, addr: ObjectAddr) -> u32 {
        self.slot(addr).map_or(0, |i| self.values[i])
    }

    /// The value sign-extended by the entry's type.
    pub fn get_i32(&self, addr: ObjectAddr) -> i32 {
        match self.def(addr) {
            Ok(d) if d.signed && d.bytes < 4 => {
                let shift = 32 - 8 * u32::from(d.bytes);
                ((self.get(addr) << shift) as i32) >> shift
            }
            _ => self.get(addr) as i32,
        }
    }

    /// Sets a value from the drive's side (no access check; missing entries ignored).
    pub fn set(&mut self, addr: ObjectAddr, raw: u32) {
        if let Some(i) = self.slot(addr) {
            let bytes = self.defs[i].bytes;
            let mask = if bytes >= 4 {
                u32::MAX
            } else {
                (1 << (8 * bytes)) - 1
            };
            self.values[i] = raw & mask;
        }
    }

    /// An SDO upload.
    pub fn read(&self, addr: ObjectAddr) -> Result<SdoData, AbortCode> {
        let def = self.def(addr)?;
        let v = self.get(addr).to_le_bytes();
        SdoData::new(&v[..usize::from(def.bytes)]).ok_or(AbortCode::General)
    }

    /// Checks an SDO download's access and length; the raw value to store.
    pub fn check_write(&self, addr: ObjectAddr, data: SdoData) -> Result<u32, AbortCode> {
        let def = self.def(addr)?;
        if def.access != Access::Rw {
            return Err(AbortCode::ReadOnly);
        }
        match data.len().cmp(&usize::from(def.bytes)) {
            core::cmp::Ordering::Greater => Err(AbortCode::TypeLengthHigh),
            core::cmp::Ordering::Less => Err(AbortCode::TypeLengthLow),
            core::cmp::Ordering::Equal => Ok(data.as_u32()),
        }
    }
}
