//! The validated model of a DBC: what the renderers read. Built once, up front, by
//! [`Bus::from_dbc`]; every refusal happens there, so rendering cannot fail.

mod family;
mod message;
mod signal;

/// Every message type and value-table enum of a DBC.
#[derive(Debug, Clone)]
pub struct Bus {
    /// Value-table enums, by Rust name.
    pub enums: Vec<EnumDef>,
    /// One entry per generated type, in DBC file order.
    pub groups: Vec<Group>,
}

/// A value table that becomes a Rust enum.
#[derive(Debug, Clone, PartialEq)]
pub struct EnumDef {
    /// Rust type name.
    pub name: String,
    /// (raw value, DBC name), sorted by raw value.
    pub values: Vec<(i64, String)>,
}

/// One generated type: a single message, or a family of identical per-instance messages
/// (`FINGER_SETPOINT_0..4`) that becomes one type with an instance index.
#[derive(Debug, Clone)]
pub struct Group {
    /// Rust type name.
    pub ty: String,
    /// DBC name (the family name without `_<n>` for a family).
    pub name: String,
    /// The members, instance order; one for a plain message.
    pub messages: Vec<Message>,
}

impl Group {
    /// Whether this type has an instance index.
    pub fn is_family(&self) -> bool {
        self.messages.len() > 1
    }

    /// The first member: layout, DLC, cycle time and E2E width are the same for all.
    pub fn first(&self) -> &Message {
        &self.messages[0]
    }
}

/// One DBC message.
#[derive(Debug, Clone)]
pub struct Message {
    /// DBC name.
    pub name: String,
    /// 11-bit CAN id.
    pub id: u32,
    /// Payload length (0..=8).
    pub dlc: u32,
    /// `GenMsgCycleTime` in ms.
    pub cycle_ms: u32,
    /// Transmitting nodes.
    pub senders: Vec<String>,
    /// Receiving nodes (union over the signals).
    pub receivers: Vec<String>,
    /// DBC comment.
    pub comment: Option<String>,
    /// Signals in DBC order.
    pub signals: Vec<Signal>,
    /// E2E protection, if `HandE2EDataId` is set.
    pub e2e: Option<E2e>,
}

impl Message {
    /// Whether `s` is filled by the E2E protector rather than by the caller.
    pub fn is_e2e_signal(&self, s: &Signal) -> bool {
        self.e2e.is_some() && (s.name == "Crc" || s.name == "Counter")
    }
}

/// E2E protection: CRC-8 in byte 0, alive counter from bit 8.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct E2e {
    /// `HandE2EDataId`.
    pub data_id: u16,
    /// Alive counter width (4 or 8).
    pub counter_bits: u32,
}

impl E2e {
    /// The CRC-8 SAE J1850 register (poly 0x1D, init 0xFF, not yet finalised) after the data
    /// id's two bytes, low byte first. The CRC of a payload depends on the data id only through
    /// this register, so two messages of one length with equal registers carry the same CRC
    /// for every payload: [`Bus::from_dbc`] refuses such a pair.
    pub fn register(self) -> u8 {
        crc_register_after_id(self.data_id)
    }
}

/// The J1850 register after `data_id` (low byte first) from init 0xFF, bit by bit: the
/// reference the generated code's table-driven `crc_after_id` must agree with.
pub fn crc_register_after_id(data_id: u16) -> u8 {
    data_id.to_le_bytes().iter().fold(0xFF, |mut crc: u8, &b| {
        crc ^= b;
        for _ in 0..8 {
            crc = if crc & 0x80 != 0 {
                (crc << 1) ^ 0x1D
            } else {
                crc << 1
            };
        }
        crc
    })
}

/// What a signal is at the Rust API.
#[derive(Debug, Clone, PartialEq)]
pub enum Kind {
    /// Value table: the field is the named enum.
    Enum(String),
    /// Factor 1, offset 0: the field is the integer itself.
    Int,
    /// Anything else: raw integer stored, physical `f64` at the API.
    Scaled,
}

/// The Rust integer type that stores a signal's raw value.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RawType {
    /// `u8`
    U8,
    /// `u16`
    U16,
    /// `u32`
    U32,
    /// `u64`
    U64,
    /// `i8`
    I8,
    /// `i16`
    I16,
    /// `i32`
    I32,
    /// `i64`
    I64,
}

impl RawType {
    /// The narrowest type for `size` bits.
    pub fn for_bits(signed: bool, size: u32) -> Self {
        match (signed, size) {
            (false, 1..=8) => Self::U8,
            (false, 9..=16) => Self::U16,
            (false, 17..=32) => Self::U32,
            (false, _) => Self::U64,
            (true, 1..=8) => Self::I8,
            (true, 9..=16) => Self::I16,
            (true, 17..=32) => Self::I32,
            (true, _) => Self::I64,
        }
    }

    /// The Rust spelling.
    pub fn name(self) -> &'static str {
        match self {
            Self::U8 => "u8",
            Self::U16 => "u16",
            Self::U32 => "u32",
            Self::U64 => "u64",
            Self::I8 => "i8",
            Self::I16 => "i16",
            Self::I32 => "i32",
            Self::I64 => "i64",
        }
    }

    /// Whether the type is 64 bits wide (no lossless `From` into `i64`/`f64`).
    pub fn is_64(self) -> bool {
        matches!(self, Self::U64 | Self::I64)
    }

    /// The type's smallest value.
    pub fn min(self) -> i64 {
        match self {
            Self::U8 | Self::U16 | Self::U32 | Self::U64 => 0,
            Self::I8 => i64::from(i8::MIN),
            Self::I16 => i64::from(i16::MIN),
            Self::I32 => i64::from(i32::MIN),
            Self::I64 => i64::MIN,
        }
    }

    /// The type's largest value.
    pub fn max(self) -> i64 {
        match self {
            Self::U8 => i64::from(u8::MAX),
            Self::U16 => i64::from(u16::MAX),
            Self::U32 => i64::from(u32::MAX),
            Self::I8 => i64::from(i8::MAX),
            Self::I16 => i64::from(i16::MAX),
            Self::I32 => i64::from(i32::MAX),
            Self::U64 | Self::I64 => i64::MAX,
        }
    }
}

/// One signal, checked: its bits fit the payload, its range fits its bits, its values fit its
/// range.
#[derive(Debug, Clone)]
pub struct Signal {
    /// DBC name.
    pub name: String,
    /// Rust field and method name.
    pub field: String,
    /// Start bit (little-endian numbering).
    pub start: u32,
    /// Width in bits (1..=63).
    pub size: u32,
    /// Two's complement.
    pub signed: bool,
    /// Physical units per raw step.
    pub factor: f64,
    /// Physical value of raw 0.
    pub offset: f64,
    /// Smallest physical value.
    pub min: f64,
    /// Largest physical value.
    pub max: f64,
    /// Smallest raw value (from `min`).
    pub raw_min: i64,
    /// Largest raw value (from `max`).
    pub raw_max: i64,
    /// Storage type of the raw value.
    pub raw_ty: RawType,
    /// DBC unit.
    pub unit: String,
    /// DBC comment.
    pub comment: Option<String>,
    /// Enum, integer or scaled.
    pub kind: Kind,
    /// Value table (raw, name), sorted; empty for non-enums.
    pub values: Vec<(i64, String)>,
}

impl Signal {
    /// Same layout, scaling and values (comments and receivers may differ between instances).
    pub fn same_layout(&self, o: &Signal) -> bool {
        self.name == o.name
            && self.start == o.start
            && self.size == o.size
            && self.signed == o.signed
            && self.factor == o.factor
            && self.offset == o.offset
            && self.min == o.min
            && self.max == o.max
            && self.unit == o.unit
            && self.kind == o.kind
            && self.values == o.values
    }

    /// Smallest value the bits hold.
    pub fn bit_min(&self) -> i64 {
        bit_range(self.signed, self.size).0
    }

    /// Largest value the bits hold.
    pub fn bit_max(&self) -> i64 {
        bit_range(self.signed, self.size).1
    }

    /// The type at the API: the enum, the raw integer, or `f64`.
    pub fn api_ty(&self) -> &str {
        match &self.kind {
            Kind::Enum(e) => e,
            Kind::Int => self.raw_ty.name(),
            Kind::Scaled => "f64",
        }
    }

    /// The const prefix (`FORCE` for `Force`).
    pub fn upper(&self) -> String {
        self.field.to_uppercase()
    }
}

/// The values `size` bits hold.
pub fn bit_range(signed: bool, size: u32) -> (i64, i64) {
    if signed {
        (-(1i64 << (size - 1)), (1i64 << (size - 1)) - 1)
    } else {
        (0, (1i64 << size) - 1)
    }
}
