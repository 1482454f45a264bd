//! PDO mapping as data: the SDO writes that configure one PDO (disable, clear, map, count,
//! enable), the read-back of what was written, and the PDO payload codec.

use crate::cia402::{objects, Mode};
use crate::frame::CanFrame;
use crate::ids::{CobId, Function, NodeId, ObjectAddr};
use crate::sdo::{SdoData, SdoWrite};
use thiserror::Error;

/// COB-ID bit 31: the PDO is not valid (disabled).
pub const PDO_INVALID: u32 = 1 << 31;

/// Receive (master -> drive) or transmit (drive -> master).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Direction {
    /// RPDO.
    Rx,
    /// TPDO.
    Tx,
}

/// One mapped object: address and length in bits (8, 16 or 32).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Mapped {
    /// The object.
    pub addr: ObjectAddr,
    /// Its length in bits.
    pub bits: u8,
}

impl Mapped {
    /// A mapping entry.
    pub const fn new(index: u16, sub: u8, bits: u8) -> Self {
        Self {
            addr: ObjectAddr::new(index, sub),
            bits,
        }
    }

    /// The mapping parameter value: index << 16 | sub << 8 | bits.
    pub fn raw(self) -> u32 {
        (u32::from(self.addr.index) << 16) | (u32::from(self.addr.sub) << 8) | u32::from(self.bits)
    }

    /// The entry for a mapping parameter value.
    pub fn from_raw(raw: u32) -> Self {
        Self::new((raw >> 16) as u16, (raw >> 8) as u8, raw as u8)
    }
}

/// One PDO's configuration: which, its COB-ID and transmission type, and what it carries
/// (nothing: the PDO is disabled).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PdoConfig {
    /// Receive or transmit.
    pub direction: Direction,
    /// 1..=4.
    pub number: u8,
    /// The COB-ID.
    pub cob_id: CobId,
    /// Transmission type (1: every SYNC).
    pub transmission_type: u8,
    /// The mapped objects in order; empty: disabled.
    pub entries: Vec<Mapped>,
}

/// A PDO mapping that cannot be right.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Error)]
pub enum PdoError {
    /// The mapped objects exceed 64 bits.
    #[error("PDO mapping of {0} bits exceeds 64")]
    TooLong(u32),
    /// A mapped length other than 8, 16 or 32 bits.
    #[error("mapped length of {0} bits (8, 16 or 32 supported)")]
    BadLength(u8),
    /// A PDO payload of the wrong length.
    #[error("PDO 0x{cob_id:03X} of {got} bytes, mapping needs {expected}")]
    PayloadLength {
        /// The COB-ID.
        cob_id: u16,
        /// Bytes the mapping needs.
        expected: usize,
        /// Bytes received.
        got: usize,
    },
    /// A different number of values than mapped objects.
    #[error("{got} values for {expected} mapped objects")]
    ValueCount {
        /// Mapped objects.
        expected: usize,
        /// Values given.
        got: usize,
    },
}

impl PdoConfig {
    /// The communication parameter index (0x1400/0x1800 + number - 1).
    pub fn comm_index(&self) -> u16 {
        let base = match self.direction {
            Direction::Rx => 0x1400,
            Direction::Tx => 0x1800,
        };
        base + u16::from(self.number) - 1
    }

    /// The mapping parameter index (0x1600/0x1A00 + number - 1).
    pub fn map_index(&self) -> u16 {
        self.comm_index() + 0x200
    }

    /// Whether the PDO carries anything.
    pub fn enabled(&self) -> bool {
        !self.entries.is_empty()
    }

    /// Total mapped bytes; checks lengths.
    pub fn byte_len(&self) -> Result<usize, PdoError> {
        let mut bits = 0u32;
        for e in &self.entries {
            if !matches!(e.bits, 8 | 16 | 32) {
                return Err(PdoError::BadLength(e.bits));
            }
            bits += u32::from(e.bits);
        }
        if bits > 64 {
            return Err(PdoError::TooLong(bits));
        }
        Ok((bits / 8) as usize)
    }

    /// The COB-ID parameter value (bit 31 set when disabled).
    pub fn cob_param(&self) -> u32 {
        let invalid = if self.enabled() { 0 } else { PDO_INVALID };
        u32::from(self.cob_id.raw()) | invalid
    }

    /// The SDO writes, in order: disable (bit 31), transmission type, count 0, each entry,
    /// count, enable. A disabled PDO is only written invalid.
    pub fn plan(&self) -> Vec<SdoWrite> {
        let c = self.comm_index();
        let m = self.map_index();
        let disabled = u32::from(self.cob_id.raw()) | PDO_INVALID;
        let mut w = vec![SdoWrite::new(ObjectAddr::new(c, 1), SdoData::u32(disabled))];
        if !self.enabled() {
            return w;
        }
        w.push(SdoWrite::new(
            ObjectAddr::new(c, 2),
            SdoData::u8(self.transmission_type),
        ));
        w.push(SdoWrite::new(ObjectAddr::new(m, 0), SdoData::u8(0)));
        for (k, e) in self.entries.iter().enumerate() {
            w.push(SdoWrite::new(
                ObjectAddr::new(m, k as u8 + 1),
                SdoData::u32(e.raw()),
            ));
        }
        w.push(SdoWrite::new(
            ObjectAddr::new(m, 0),
            SdoData::u8(self.entries.len() as u8),
        ));
        w.push(SdoWrite::new(
            ObjectAddr::new(c, 1),
            SdoData::u32(self.cob_param()),
        ));
        w
    }

    /// What a read-back must find: the final value of every object the plan wrote.
    pub fn expected(&self) -> Vec<SdoWrite> {
        let mut last: Vec<SdoWrite> = Vec::new();
        for w in self.plan() {
            last.retain(|x| x.addr != w.addr);
            last.push(w);
        }
        last.sort_by_key(|w| w.addr);
        last
    }

    /// Encodes raw values (one per entry, low `bits` used) into this PDO's frame.
    pub fn encode(&self, values: &[u32]) -> Result<CanFrame, PdoError> {
        let len = self.byte_len()?;
        if values.len() != self.entries.len() {
            return Err(PdoError::ValueCount {
                expected: self.entries.len(),
                got: values.len(),
            });
        }
        let mut d = [0u8; 8];
        let mut at = 0;
        for (e, v) in self.entries.iter().zip(values) {
            let n = usize::from(e.bits / 8);
            d[at..at + n].copy_from_slice(&v.to_le_bytes()[..n]);
            at += n;
        }
        Ok(CanFrame::from_parts(self.cob_id.raw(), len, d))
    }

    /// Decodes a payload into raw values, one per entry (sign-extend by the object's type).
    pub fn decode(&self, f: &CanFrame) -> Result<Vec<u32>, PdoError> {
        let len = self.byte_len()?;
        let p = f.payload();
        if p.len() != len {
            return Err(PdoError::PayloadLength {
                cob_id: f.cob_id(),
                expected: len,
                got: p.len(),
            });
        }
        let mut at = 0;
        let mut out = Vec::with_capacity(self.entries.len());
        for e in &self.entries {
            let n = usize::from(e.bits / 8);
            let mut b = [0u8; 4];
            b[..n].copy_from_slice(&p[at..at + n]);
            out.push(u32::from_le_bytes(b));
            at += n;
        }
        Ok(out)
    }
}

/// The PDOs of a finger drive in `mode`: RPDO1 controlword + target (CST: target torque; CSV
/// and PV: target velocity + max torque 0x6072, the velocity loop's torque limit); TPDO1
/// statusword, torque actual, velocity actual; TPDO2 position actual; the rest disabled.
/// Every PDO synchronous (type 1: RPDO applied and TPDO sent on each SYNC).
pub fn finger_pdos(node: NodeId, mode: Mode) -> Vec<PdoConfig> {
    let controlword = Mapped::new(objects::CONTROLWORD, 0, 16);
    let rpdo1 = match mode {
        Mode::CyclicSyncTorque => vec![controlword, Mapped::new(objects::TARGET_TORQUE, 0, 16)],
        Mode::CyclicSyncVelocity | Mode::ProfileVelocity => vec![
            controlword,
            Mapped::new(objects::TARGET_VELOCITY, 0, 32),
            Mapped::new(objects::MAX_TORQUE, 0, 16),
        ],
    };
    let mut out = Vec::with_capacity(8);
    for (direction, function) in [
        (Direction::Rx, Function::Rpdo as fn(u8) -> Function),
        (Direction::Tx, Function::Tpdo),
    ] {
        for number in 1..=4u8 {
            let entries = match (direction, number) {
                (Direction::Rx, 1) => rpdo1.clone(),
                (Direction::Tx, 1) => vec![
                    Mapped::new(objects::STATUSWORD, 0, 16),
                    Mapped::new(objects::TORQUE_ACTUAL, 0, 16),
                    Mapped::new(objects::VELOCITY_ACTUAL, 0, 32),
                ],
                (Direction::Tx, 2) => vec![Mapped::new(objects::POSITION_ACTUAL, 0, 32)],
                _ => Vec::new(),
            };
            let cob_id = CobId::of(function(number), node).unwrap_or(CobId::SYNC);
            out.push(PdoConfig {
                direction,
                number,
                cob_id,
                transmission_type: 1,
                entries,
            });
        }
    }
    out
}
