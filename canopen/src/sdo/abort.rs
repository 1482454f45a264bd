//! SDO abort codes (CiA 301 table 22), as data: code, name and meaning.

/// A named SDO abort code; [`AbortCode::Other`] keeps any code outside the standard table.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[allow(missing_docs)] // each variant's meaning is in ABORT_CODES
pub enum AbortCode {
    ToggleBit,
    Timeout,
    InvalidCommand,
    InvalidBlockSize,
    InvalidSequence,
    Crc,
    OutOfMemory,
    UnsupportedAccess,
    WriteOnly,
    ReadOnly,
    NoObject,
    NotMappable,
    PdoLength,
    ParameterIncompatible,
    DeviceIncompatible,
    Hardware,
    TypeLength,
    TypeLengthHigh,
    TypeLengthLow,
    NoSubIndex,
    InvalidValue,
    ValueHigh,
    ValueLow,
    MaxBelowMin,
    NoResource,
    General,
    CannotStore,
    CannotStoreLocal,
    CannotStoreState,
    NoDictionary,
    NoData,
    /// A code outside the CiA 301 table (vendor-specific or corrupt).
    Other(u32),
}

/// The CiA 301 abort code table: variant, code, meaning.
pub const ABORT_CODES: &[(AbortCode, u32, &str)] = &[
    (AbortCode::ToggleBit, 0x0503_0000, "toggle bit not alternated"),
    (AbortCode::Timeout, 0x0504_0000, "SDO protocol timed out"),
    (AbortCode::InvalidCommand, 0x0504_0001, "client/server command specifier not valid or unknown"),
    (AbortCode::InvalidBlockSize, 0x0504_0002, "invalid block size"),
    (AbortCode::InvalidSequence, 0x0504_0003, "invalid sequence number"),
    (AbortCode::Crc, 0x0504_0004, "CRC error"),
    (AbortCode::OutOfMemory, 0x0504_0005, "out of memory"),
    (AbortCode::UnsupportedAccess, 0x0601_0000, "unsupported access to an object"),
    (AbortCode::WriteOnly, 0x0601_0001, "attempt to read a write only object"),
    (AbortCode::ReadOnly, 0x0601_0002, "attempt to write a read only object"),
    (AbortCode::NoObject, 0x0602_0000, "object does not exist in the object dictionary"),
    (AbortCode::NotMappable, 0x0604_0041, "object cannot be mapped to the PDO"),
    (AbortCode::PdoLength, 0x0604_0042, "the number and length of the objects to be mapped would exceed PDO length"),
    (AbortCode::ParameterIncompatible, 0x0604_0043, "general parameter incompatibility"),
    (AbortCode::DeviceIncompatible, 0x0604_0047, "general internal incompatibility in the device"),
    (AbortCode::Hardware, 0x0606_0000, "access failed due to a hardware error"),
    (AbortCode::TypeLength, 0x0607_0010, "data type does not match, length of service parameter does not match"),
    (AbortCode::TypeLengthHigh, 0x0607_0012, "data type does not match, length of service parameter too high"),
    (AbortCode::TypeLengthLow, 0x0607_0013, "data type does not match, length of service parameter too low"),
    (AbortCode::NoSubIndex, 0x0609_0011, "sub-index does not exist"),
    (AbortCode::InvalidValue, 0x0609_0030, "invalid value for parameter"),
    (AbortCode::ValueHigh, 0x0609_0031, "value of parameter written too high"),
    (AbortCode::ValueLow, 0x0609_0032, "value of parameter written too low"),
    (AbortCode::MaxBelowMin, 0x0609_0036, "maximum value is less than minimum value"),
    (AbortCode::NoResource, 0x060A_0023, "resource not available: SDO connection"),
    (AbortCode::General, 0x0800_0000, "general error"),
    (AbortCode::CannotStore, 0x0800_0020, "data cannot be transferred or stored to the application"),
    (AbortCode::CannotStoreLocal, 0x0800_0021, "data cannot be transferred or stored to the application because of local control"),
    (AbortCode::CannotStoreState, 0x0800_0022, "data cannot be transferred or stored to the application because of the present device state"),
    (AbortCode::NoDictionary, 0x0800_0023, "object dictionary dynamic generation failed or no object dictionary is present"),
    (AbortCode::NoData, 0x0800_0024, "no data available"),
];

impl AbortCode {
    /// The named code for a raw value.
    pub fn from_raw(raw: u32) -> Self {
        ABORT_CODES
            .iter()
            .find(|(_, c, _)| *c == raw)
            .map_or(Self::Other(raw), |(a, _, _)| *a)
    }

    /// The raw 32-bit code.
    pub fn raw(self) -> u32 {
        match self {
            Self::Other(raw) => raw,
            named => ABORT_CODES
                .iter()
                .find(|(a, _, _)| *a == named)
                .map_or(0, |(_, c, _)| *c),
        }
    }

    /// The CiA 301 meaning.
    pub fn meaning(self) -> &'static str {
        ABORT_CODES
            .iter()
            .find(|(a, _, _)| *a == self)
            .map_or("unknown abort code", |(_, _, m)| m)
    }
}

impl core::fmt::Display for AbortCode {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "0x{:08X} ({})", self.raw(), self.meaning())
    }
}
