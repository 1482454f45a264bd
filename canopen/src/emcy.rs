//! EMCY (0x080 + node): error code, error register and five vendor bytes, with the
//! CiA 301 / CiA 402 error code classes named.

use crate::frame::CanFrame;
use crate::ids::NodeId;
use thiserror::Error;

/// The error code class (CiA 301 table 21, by the code's top digit).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ErrorClass {
    /// 0x00xx: error reset or no error.
    NoError,
    /// 0x10xx: generic error (0x11xx..0x1Fxx are reserved).
    Generic,
    /// 0x2xxx: current.
    Current,
    /// 0x3xxx: voltage.
    Voltage,
    /// 0x4xxx: temperature.
    Temperature,
    /// 0x5xxx: device hardware.
    Hardware,
    /// 0x6xxx: device software.
    Software,
    /// 0x7xxx: additional modules (CiA 402: motor, sensors).
    AdditionalModules,
    /// 0x8xxx: monitoring (communication, protocol; CiA 402: control).
    Monitoring,
    /// 0x9xxx: external error.
    External,
    /// 0xF0xx: additional functions.
    AdditionalFunctions,
    /// 0xFFxx: device specific.
    DeviceSpecific,
    /// Any other code (reserved ranges).
    Reserved,
}

impl ErrorClass {
    /// The class of a code.
    pub fn of(code: u16) -> Self {
        match code >> 12 {
            0 if code >> 8 == 0 => Self::NoError,
            1 if code >> 8 == 0x10 => Self::Generic,
            2 => Self::Current,
            3 => Self::Voltage,
            4 => Self::Temperature,
            5 => Self::Hardware,
            6 => Self::Software,
            7 => Self::AdditionalModules,
            8 => Self::Monitoring,
            9 => Self::External,
            0xF if code >> 8 == 0xFF => Self::DeviceSpecific,
            0xF if code >> 8 == 0xF0 => Self::AdditionalFunctions,
            _ => Self::Reserved,
        }
    }
}

/// Named error codes (CiA 301 table 21 and the CiA 402 drive codes), most specific first
/// when looked up: exact code, then its `xx00` group, then its `x000` class.
pub const ERROR_CODES: &[(u16, &str)] = &[
    (0x0000, "error reset or no error"),
    (0x1000, "generic error"),
    (0x2000, "current"),
    (0x2100, "current, device input side"),
    (0x2200, "current inside the device"),
    (0x2300, "current, device output side"),
    (0x2310, "continuous over-current"),
    (0x2320, "short circuit / earth leakage"),
    (0x3000, "voltage"),
    (0x3100, "mains voltage"),
    (0x3200, "voltage inside the device"),
    (0x3210, "DC link over-voltage"),
    (0x3220, "DC link under-voltage"),
    (0x3300, "output voltage"),
    (0x4000, "temperature"),
    (0x4100, "ambient temperature"),
    (0x4200, "device temperature"),
    (0x4210, "excess temperature device"),
    (0x4300, "drive temperature"),
    (0x4310, "excess temperature drive"),
    (0x5000, "device hardware"),
    (0x6000, "device software"),
    (0x6100, "internal software"),
    (0x6200, "user software"),
    (0x6300, "data set"),
    (0x7000, "additional modules"),
    (0x7100, "power"),
    (0x7120, "motor"),
    (0x7121, "motor blocked"),
    (0x7300, "sensor"),
    (0x7305, "incremental sensor 1 fault"),
    (0x8000, "monitoring"),
    (0x8100, "communication"),
    (0x8110, "CAN overrun (objects lost)"),
    (0x8120, "CAN in error passive mode"),
    (0x8130, "life guard error or heartbeat error"),
    (0x8140, "recovered from bus off"),
    (0x8150, "CAN-ID collision"),
    (0x8200, "protocol error"),
    (0x8210, "PDO not processed due to length error"),
    (0x8220, "PDO length exceeded"),
    (
        0x8230,
        "DAM MPDO not processed, destination object not available",
    ),
    (0x8240, "unexpected SYNC data length"),
    (0x8250, "RPDO timeout"),
    (0x8400, "velocity speed controller"),
    (0x8500, "position controller"),
    (0x8600, "positioning controller"),
    (0x8611, "following error"),
    (0x9000, "external error"),
    (0xF000, "additional functions"),
    (0xFF00, "device specific"),
];

/// The most specific meaning known for `code`.
pub fn meaning(code: u16) -> &'static str {
    [code, code & 0xFFF0, code & 0xFF00, code & 0xF000]
        .into_iter()
        .find_map(|c| ERROR_CODES.iter().find(|(k, _)| *k == c).map(|(_, m)| *m))
        .unwrap_or("reserved / unknown error code")
}

/// What can be wrong with an EMCY frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Error)]
pub enum EmcyError {
    /// Not 0x081..=0x0FF.
    #[error("COB-ID 0x{0:03X} is not an EMCY frame")]
    WrongId(u16),
    /// EMCY frames are 8 bytes.
    #[error("EMCY frame of {0} bytes (8 expected)")]
    Length(usize),
}

/// A decoded EMCY message.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Emcy {
    /// The node that sent it.
    pub node: NodeId,
    /// The error code (0x0000: error reset).
    pub code: u16,
    /// The error register (0x1001).
    pub register: u8,
    /// Manufacturer-specific bytes.
    pub vendor: [u8; 5],
}

impl Emcy {
    /// Decodes an EMCY frame.
    pub fn decode(f: &CanFrame) -> Result<Self, EmcyError> {
        let id = f.cob_id();
        if !(0x081..=0x0FF).contains(&id) {
            return Err(EmcyError::WrongId(id));
        }
        let node = NodeId::try_new((id - 0x080) as u8).map_err(|_| EmcyError::WrongId(id))?;
        let p = f.payload();
        if p.len() != 8 {
            return Err(EmcyError::Length(p.len()));
        }
        Ok(Self {
            node,
            code: u16::from_le_bytes([p[0], p[1]]),
            register: p[2],
            vendor: [p[3], p[4], p[5], p[6], p[7]],
        })
    }

    /// The frame.
    pub fn frame(&self) -> CanFrame {
        let c = self.code.to_le_bytes();
        let v = self.vendor;
        CanFrame::from_parts(
            0x080 + u16::from(self.node.get()),
            8,
            [c[0], c[1], self.register, v[0], v[1], v[2], v[3], v[4]],
        )
    }

    /// The class of the code.
    pub fn class(&self) -> ErrorClass {
        ErrorClass::of(self.code)
    }

    /// The meaning of the code.
    pub fn meaning(&self) -> &'static str {
        meaning(self.code)
    }

    /// Whether this is an error reset (code 0x00xx): the node's errors cleared.
    pub fn is_reset(&self) -> bool {
        self.code >> 8 == 0
    }
}

impl core::fmt::Display for Emcy {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(
            f,
            "{} EMCY 0x{:04X} ({}), register 0x{:02X}",
            self.node,
            self.code,
            self.meaning(),
            self.register
        )
    }
}
