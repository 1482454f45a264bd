//! Expedited SDO: the frame codec (both directions), the abort code table and the client.

pub mod abort;
pub mod client;
pub mod codec;

pub use abort::{AbortCode, ABORT_CODES};
pub use client::{SdoClient, SdoDone, SdoError};
pub use codec::{SdoData, SdoFrameError, SdoReply, SdoRequest};

use crate::ids::ObjectAddr;

/// One expedited write of a configuration plan.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SdoWrite {
    /// The object.
    pub addr: ObjectAddr,
    /// The value.
    pub data: SdoData,
}

impl SdoWrite {
    /// A write.
    pub const fn new(addr: ObjectAddr, data: SdoData) -> Self {
        Self { addr, data }
    }
}
