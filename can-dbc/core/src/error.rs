//! The codec's error: everything that can be wrong with a value or a frame against hand.dbc.

/// Why a message could not be built, encoded or decoded.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum CodecError {
    /// A physical value outside the DBC's `[min, max]`, or not finite.
    #[error(
        "{message}.{signal}: {value} {unit} is outside the allowed range [{min}, {max}] {unit}"
    )]
    OutOfRange {
        /// DBC message name.
        message: &'static str,
        /// DBC signal name.
        signal: &'static str,
        /// The refused value.
        value: f64,
        /// Smallest allowed value.
        min: f64,
        /// Largest allowed value.
        max: f64,
        /// Unit of the signal.
        unit: &'static str,
    },
    /// A raw (unscaled) value outside the range the DBC allows (from a setter or a frame).
    #[error("{message}.{signal}: raw value {raw} is outside the allowed raw range [{min}, {max}]")]
    RawOutOfRange {
        /// DBC message name.
        message: &'static str,
        /// DBC signal name.
        signal: &'static str,
        /// The refused raw value.
        raw: i64,
        /// Smallest allowed raw value.
        min: i64,
        /// Largest allowed raw value.
        max: i64,
    },
    /// A raw value that the signal's value table does not name.
    #[error("{message}.{signal}: {raw} is not in the signal's value table")]
    UnknownValue {
        /// DBC message name.
        message: &'static str,
        /// DBC signal name.
        signal: &'static str,
        /// The unknown raw value.
        raw: i64,
    },
    /// A whole-number signal given a fractional value.
    #[error("{message}.{signal}: {value} is not a whole number")]
    NotInteger {
        /// DBC message name.
        message: &'static str,
        /// DBC signal name.
        signal: &'static str,
        /// The refused value.
        value: f64,
    },
    /// A signal that a by-name constructor did not get.
    #[error("{message}.{signal}: no value given")]
    MissingSignal {
        /// DBC message name.
        message: &'static str,
        /// DBC signal name.
        signal: &'static str,
    },
    /// An id that hand.dbc does not define.
    #[error("id {id:#05x} is not defined in hand.dbc")]
    UnknownId {
        /// The id.
        id: u32,
    },
    /// A frame whose id is not the id of the message it is decoded as.
    #[error("{message}: frame id {id:#05x} is not this message's id")]
    WrongId {
        /// DBC message name.
        message: &'static str,
        /// The frame's id.
        id: u32,
    },
    /// An extended-id frame: hand.dbc uses 11-bit ids only.
    #[error("extended id {id:#010x}: hand.dbc uses 11-bit ids only")]
    ExtendedId {
        /// The 29-bit id.
        id: u32,
    },
    /// A remote frame where a data frame was expected.
    #[error("id {id:#05x}: remote frame, expected a data frame")]
    RemoteFrame {
        /// The id.
        id: u32,
    },
    /// A payload whose length differs from the DBC's DLC.
    #[error("{message}: payload has {got} bytes, hand.dbc says {expected}")]
    WrongLength {
        /// DBC message name.
        message: &'static str,
        /// DLC from the DBC.
        expected: usize,
        /// Length received.
        got: usize,
    },
    /// A per-instance message (e.g. one per finger) asked for an instance that does not exist.
    #[error("{message}: instance {instance} does not exist (there are {count})")]
    InstanceOutOfRange {
        /// DBC message family name.
        message: &'static str,
        /// The instance asked for.
        instance: usize,
        /// Number of instances.
        count: usize,
    },
    /// The target frame type refused to build a frame (it should never for 11-bit ids and
    /// payloads of at most 8 bytes).
    #[error("id {id:#05x}: the frame type refused a classic CAN frame")]
    FrameRejected {
        /// The id.
        id: u32,
    },
}
