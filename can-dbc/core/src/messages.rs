//! The message types of hand.dbc. The code is generated from hand.dbc by the
//! `hand-dbc-codegen` crate (`can-dbc/codegen`) into the checked-in, reviewed module
//! `core/src/messages/generated.rs`: edit hand.dbc, run
//! `cargo run -p hand-dbc-codegen --bin hand-dbc-gen`, and commit both; never edit the
//! generated file. `cargo test -p hand-dbc-codegen` fails while it is out of date.
//!
//! One type per message, or one type with an instance index for a family of identical
//! per-finger messages (`FINGER_SETPOINT_0..4` -> [`FingerSetpoint`], instance = finger).
//! Every type has `NAME`, `ID` (or `IDS` and `INSTANCES`), `DLC`, `CYCLE_TIME_MS`, per-signal
//! `_MIN`/`_MAX` (and `_FACTOR`/`_OFFSET`/`_RAW_MIN`/`_RAW_MAX` for scaled signals) consts,
//! `E2E` for protected messages, a checked `new`, getters returning physical values (`_raw`
//! for the bus integer), checked setters, `decode`/`encode`,
//! `to_frame`/`to_can_frame`/`try_from_frame`. Value tables become enums. [`decode`]
//! dispatches a payload by id into [`Message`]; [`MESSAGES`] is the DBC as data.
//!
//! Values outside the DBC's `[min, max]` are refused with [`CodecError`] when set and when
//! decoded: the codec never wraps and never saturates.

use embedded_can::{Frame, Id};

pub(crate) use crate::num::round;

pub use crate::error::CodecError;
pub use crate::info::{MessageInfo, SignalInfo};

mod generated;
pub use generated::*;

/// The 11-bit id of a data frame, or why the frame cannot be one of hand.dbc's.
fn standard_data_frame<F: Frame>(frame: &F) -> Result<u32, CodecError> {
    let id = match frame.id() {
        Id::Standard(id) => u32::from(id.as_raw()),
        Id::Extended(id) => return Err(CodecError::ExtendedId { id: id.as_raw() }),
    };
    if frame.is_remote_frame() {
        return Err(CodecError::RemoteFrame { id });
    }
    Ok(id)
}

/// Builds a frame of any type for an id from hand.dbc.
fn to_can_frame<F: Frame>(id: u32, data: &[u8]) -> Result<F, CodecError> {
    let std_id = u16::try_from(id)
        .ok()
        .and_then(embedded_can::StandardId::new)
        .ok_or(CodecError::FrameRejected { id })?;
    F::new(std_id, data).ok_or(CodecError::FrameRejected { id })
}

/// A whole number from a by-name physical value (for integer and enum signals).
fn whole(message: &'static str, signal: &'static str, value: f64) -> Result<i64, CodecError> {
    // 2^63 bounds: every integer signal of hand.dbc is far narrower.
    if !value.is_finite() || crate::num::trunc(value) != value || value.abs() >= 9.2e18 {
        return Err(CodecError::NotInteger {
            message,
            signal,
            value,
        });
    }
    Ok(value as i64)
}
