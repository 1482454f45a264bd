//! Why a DBC is refused, and why generation failed.

use std::path::PathBuf;

/// An inconsistency in the DBC: each names the message (and the signal, for signal faults), so
/// a bad edit never yields a codec that silently disagrees with the file.
///
/// Fields are named after what they hold: `message` and `signal` are DBC names, the rest the
/// offending values, as each variant's message spells out.
#[expect(
    missing_docs,
    reason = "variant fields are the DBC names and values the message shows"
)]
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DbcError {
    /// The text is not a DBC file.
    #[error("parse error: {0}")]
    Parse(String),
    /// A 29-bit id: the bus is classic CAN 2.0A.
    #[error("{message}: extended ids are not used on this bus")]
    ExtendedId { message: String },
    /// A standard id above 0x7FF.
    #[error("{message}: id {id:#x} exceeds 11 bits")]
    IdTooWide { message: String, id: u32 },
    /// Two messages with one id.
    #[error("{message} and {other} share id {id:#x}")]
    SharedId {
        message: String,
        other: String,
        id: u32,
    },
    /// More than 8 payload bytes.
    #[error("{message}: DLC {dlc} > 8 (classic CAN only)")]
    Dlc { message: String, dlc: u64 },
    /// No `GenMsgCycleTime` attribute (and no default).
    #[error("{message}: no GenMsgCycleTime")]
    NoCycleTime { message: String },
    /// A `GenMsgCycleTime` that does not fit a `u32`.
    #[error("{message}: GenMsgCycleTime {value} out of range")]
    CycleTime { message: String, value: i64 },
    /// A `HandE2EDataId` that does not fit 16 bits.
    #[error("{message}: HandE2EDataId {value} must fit 16 bits")]
    DataId { message: String, value: i64 },
    /// An E2E message without the fixed CRC/counter layout.
    #[error(
        "{message}: E2E messages need Crc at bits 0..8 and an unsigned full-range Counter of 4 \
         or 8 bits at bit 8"
    )]
    E2eLayout { message: String },
    /// Two protected messages of one length whose CRC registers after the data id are equal:
    /// a frame of one is E2E-valid under the other's id.
    #[error(
        "{message} (data id {data_id:#06x}) and {other} (data id {other_data_id:#06x}): both \
         {dlc} bytes with CRC register {register:#04x} after the data id, so a frame of one is \
         E2E-valid as the other; choose another data id (bump the layout version nibble)"
    )]
    E2eCollision {
        message: String,
        data_id: u16,
        other: String,
        other_data_id: u16,
        dlc: u32,
        register: u8,
    },
    /// A multiplexed or multiplexor signal.
    #[error("{message}.{signal}: multiplexing is not supported by the generator")]
    Multiplexed { message: String, signal: String },
    /// A big-endian (Motorola, `@0`) signal.
    #[error("{message}.{signal}: only little-endian (@1) signals are supported")]
    ByteOrder { message: String, signal: String },
    /// Bits outside the payload, or a size outside 1..=63.
    #[error(
        "{message}.{signal}: bits {start}..{} do not fit a {dlc}-byte payload (or size not 1..=63)",
        .start + .size
    )]
    Bits {
        message: String,
        signal: String,
        start: u64,
        size: u64,
        dlc: u64,
    },
    /// Two signals share a bit.
    #[error("{message}.{signal}: overlaps another signal")]
    Overlap { message: String, signal: String },
    /// A factor that is not positive and finite, or an offset that is not finite.
    #[error("{message}.{signal}: factor must be positive and finite")]
    Factor { message: String, signal: String },
    /// No usable `[min|max]`.
    #[error("{message}.{signal}: give a range with min < max, got [{min}|{max}]")]
    NoRange {
        message: String,
        signal: String,
        min: f64,
        max: f64,
    },
    /// A `[min|max]` whose raw values the bits cannot hold.
    #[error(
        "{message}.{signal}: range [{min}|{max}] needs raw [{raw_min}|{raw_max}], {size} bits \
         hold [{bit_min}|{bit_max}]"
    )]
    RangeTooWide {
        message: String,
        signal: String,
        min: f64,
        max: f64,
        raw_min: f64,
        raw_max: f64,
        size: u32,
        bit_min: i64,
        bit_max: i64,
    },
    /// A value table on a scaled signal.
    #[error("{message}.{signal}: a value table needs factor 1 and offset 0")]
    ScaledEnum { message: String, signal: String },
    /// A value-table entry outside the signal's range.
    #[error("{message}.{signal}: value {value} {name:?} is outside the range")]
    ValueOutOfRange {
        message: String,
        signal: String,
        value: i64,
        name: String,
    },
    /// Two different value tables that would become one Rust enum.
    #[error("{message}.{signal}: enum {name} defined twice differently")]
    EnumConflict {
        message: String,
        signal: String,
        name: String,
    },
}

/// Why `hand-dbc-gen` could not produce or check the generated file.
#[derive(Debug, thiserror::Error)]
pub enum GenError {
    /// hand.dbc is refused.
    #[error("hand.dbc: {0}")]
    Dbc(#[from] DbcError),
    /// Reading or writing a file failed.
    #[error("{}: {source}", .path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// What failed.
        source: std::io::Error,
    },
    /// rustfmt could not be run or refused the generated code.
    #[error("rustfmt: {0}")]
    Rustfmt(String),
}
