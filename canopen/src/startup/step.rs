//! The steps of a drive's start-up, as data.

use crate::cia402::Mode;
use crate::sdo::SdoWrite;

/// One start-up step; its `Display` is the name a failure reports.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Step {
    /// NMT reset communication to the drive.
    ResetCommunication,
    /// Wait for its boot-up message.
    AwaitBootUp,
    /// Read 0x1018:sub (1 vendor id, mandatory; 2 product, 3 revision, 4 serial, optional).
    ReadIdentity(u8),
    /// Read 0x6502 and check the mode is listed.
    CheckMode(Mode),
    /// A configuration write.
    Write(SdoWrite),
    /// A target set to zero before enabling.
    ZeroTarget(SdoWrite),
    /// Read back a written object and compare.
    ReadBack(SdoWrite),
    /// NMT start (Operational).
    StartNode,
    /// Walk the power state machine to Operation enabled (controlword/statusword by SDO).
    Enable,
}

impl core::fmt::Display for Step {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::ResetCommunication => write!(f, "NMT reset communication"),
            Self::AwaitBootUp => write!(f, "wait for boot-up"),
            Self::ReadIdentity(s) => write!(f, "read identity 0x1018:{s:02X}"),
            Self::CheckMode(m) => write!(f, "check 0x6502 lists mode {}", m.value()),
            Self::Write(w) => write!(f, "write {} = {:?}", w.addr, w.data),
            Self::ZeroTarget(w) => write!(f, "zero target {}", w.addr),
            Self::ReadBack(w) => write!(f, "read back {} (expect {:?})", w.addr, w.data),
            Self::StartNode => write!(f, "NMT start"),
            Self::Enable => write!(f, "enable (CiA 402 state machine)"),
        }
    }
}
