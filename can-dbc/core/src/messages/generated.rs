// @generated from can-dbc/hand.dbc by `cargo run -p hand-dbc-codegen --bin hand-dbc-gen`.
// Do not edit by hand: edit hand.dbc and rerun that command. Add `-- --check` to only
// compare; `cargo test -p hand-dbc-codegen` fails while this file is out of date.

use super::{round, standard_data_frame, to_can_frame, whole};
use crate::e2e::E2eProfile;
use crate::error::CodecError;
use crate::frame::CanFrame;
use crate::info::{MessageInfo, SignalInfo};

/// Value table `AmpGain` of hand.dbc.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum AmpGain {
    /// `GAIN_1` (raw 0)
    Gain1,
    /// `GAIN_2` (raw 1)
    Gain2,
    /// `GAIN_4` (raw 2)
    Gain4,
    /// `GAIN_8` (raw 3)
    Gain8,
    /// `GAIN_16` (raw 4)
    Gain16,
    /// `GAIN_32` (raw 5)
    Gain32,
    /// `GAIN_64` (raw 6)
    Gain64,
    /// `GAIN_128` (raw 7)
    Gain128,
}

impl AmpGain {
    /// Every value, in raw order.
    pub const ALL: [AmpGain; 8] = [
        AmpGain::Gain1,
        AmpGain::Gain2,
        AmpGain::Gain4,
        AmpGain::Gain8,
        AmpGain::Gain16,
        AmpGain::Gain32,
        AmpGain::Gain64,
        AmpGain::Gain128,
    ];

    /// The raw value on the bus.
    pub const fn raw(self) -> u8 {
        match self {
            AmpGain::Gain1 => 0,
            AmpGain::Gain2 => 1,
            AmpGain::Gain4 => 2,
            AmpGain::Gain8 => 3,
            AmpGain::Gain16 => 4,
            AmpGain::Gain32 => 5,
            AmpGain::Gain64 => 6,
            AmpGain::Gain128 => 7,
        }
    }

    /// The value for a raw value, `None` if the table does not name it.
    pub const fn from_raw(raw: i64) -> Option<Self> {
        match raw {
            0 => Some(AmpGain::Gain1),
            1 => Some(AmpGain::Gain2),
            2 => Some(AmpGain::Gain4),
            3 => Some(AmpGain::Gain8),
            4 => Some(AmpGain::Gain16),
            5 => Some(AmpGain::Gain32),
            6 => Some(AmpGain::Gain64),
            7 => Some(AmpGain::Gain128),
            _ => None,
        }
    }

    /// The name hand.dbc gives this value.
    pub const fn dbc_name(self) -> &'static str {
        match self {
            AmpGain::Gain1 => "GAIN_1",
            AmpGain::Gain2 => "GAIN_2",
            AmpGain::Gain4 => "GAIN_4",
            AmpGain::Gain8 => "GAIN_8",
            AmpGain::Gain16 => "GAIN_16",
            AmpGain::Gain32 => "GAIN_32",
            AmpGain::Gain64 => "GAIN_64",
            AmpGain::Gain128 => "GAIN_128",
        }
    }
}

/// Value table `AmpSampleRate` of hand.dbc.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum AmpSampleRate {
    /// `SR_500_HZ` (raw 0)
    Sr500Hz,
    /// `SR_1000_HZ` (raw 1)
    Sr1000Hz,
    /// `SR_2000_HZ` (raw 2)
    Sr2000Hz,
}

impl AmpSampleRate {
    /// Every value, in raw order.
    pub const ALL: [AmpSampleRate; 3] = [
        AmpSampleRate::Sr500Hz,
        AmpSampleRate::Sr1000Hz,
        AmpSampleRate::Sr2000Hz,
    ];

    /// The raw value on the bus.
    pub const fn raw(self) -> u8 {
        match self {
            AmpSampleRate::Sr500Hz => 0,
            AmpSampleRate::Sr1000Hz => 1,
            AmpSampleRate::Sr2000Hz => 2,
        }
    }

    /// The value for a raw value, `None` if the table does not name it.
    pub const fn from_raw(raw: i64) -> Option<Self> {
        match raw {
            0 => Some(AmpSampleRate::Sr500Hz),
            1 => Some(AmpSampleRate::Sr1000Hz),
            2 => Some(AmpSampleRate::Sr2000Hz),
            _ => None,
        }
    }

    /// The name hand.dbc gives this value.
    pub const fn dbc_name(self) -> &'static str {
        match self {
            AmpSampleRate::Sr500Hz => "SR_500_HZ",
            AmpSampleRate::Sr1000Hz => "SR_1000_HZ",
            AmpSampleRate::Sr2000Hz => "SR_2000_HZ",
        }
    }
}

/// Value table `AmpState` of hand.dbc.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum AmpState {
    /// `INIT` (raw 0)
    Init,
    /// `RUNNING` (raw 1)
    Running,
    /// `CALIBRATING` (raw 2)
    Calibrating,
    /// `FAULT` (raw 3)
    Fault,
}

impl AmpState {
    /// Every value, in raw order.
    pub const ALL: [AmpState; 4] = [
        AmpState::Init,
        AmpState::Running,
        AmpState::Calibrating,
        AmpState::Fault,
    ];

    /// The raw value on the bus.
    pub const fn raw(self) -> u8 {
        match self {
            AmpState::Init => 0,
            AmpState::Running => 1,
            AmpState::Calibrating => 2,
            AmpState::Fault => 3,
        }
    }

    /// The value for a raw value, `None` if the table does not name it.
    pub const fn from_raw(raw: i64) -> Option<Self> {
        match raw {
            0 => Some(AmpState::Init),
            1 => Some(AmpState::Running),
            2 => Some(AmpState::Calibrating),
            3 => Some(AmpState::Fault),
            _ => None,
        }
    }

    /// The name hand.dbc gives this value.
    pub const fn dbc_name(self) -> &'static str {
        match self {
            AmpState::Init => "INIT",
            AmpState::Running => "RUNNING",
            AmpState::Calibrating => "CALIBRATING",
            AmpState::Fault => "FAULT",
        }
    }
}

/// Value table `CueKind` of hand.dbc.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum CueKind {
    /// `REST` (raw 0)
    Rest,
    /// `FLEXION` (raw 1)
    Flexion,
    /// `EXTENSION` (raw 2)
    Extension,
}

impl CueKind {
    /// Every value, in raw order.
    pub const ALL: [CueKind; 3] = [CueKind::Rest, CueKind::Flexion, CueKind::Extension];

    /// The raw value on the bus.
    pub const fn raw(self) -> u8 {
        match self {
            CueKind::Rest => 0,
            CueKind::Flexion => 1,
            CueKind::Extension => 2,
        }
    }

    /// The value for a raw value, `None` if the table does not name it.
    pub const fn from_raw(raw: i64) -> Option<Self> {
        match raw {
            0 => Some(CueKind::Rest),
            1 => Some(CueKind::Flexion),
            2 => Some(CueKind::Extension),
            _ => None,
        }
    }

    /// The name hand.dbc gives this value.
    pub const fn dbc_name(self) -> &'static str {
        match self {
            CueKind::Rest => "REST",
            CueKind::Flexion => "FLEXION",
            CueKind::Extension => "EXTENSION",
        }
    }
}

/// Value table `CuePhase` of hand.dbc.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum CuePhase {
    /// `IDLE` (raw 0)
    Idle,
    /// `PREPARE` (raw 1)
    Prepare,
    /// `HOLD` (raw 2)
    Hold,
    /// `RELAX` (raw 3)
    Relax,
    /// `DONE` (raw 4)
    Done,
    /// `ABORTED` (raw 5)
    Aborted,
}

impl CuePhase {
    /// Every value, in raw order.
    pub const ALL: [CuePhase; 6] = [
        CuePhase::Idle,
        CuePhase::Prepare,
        CuePhase::Hold,
        CuePhase::Relax,
        CuePhase::Done,
        CuePhase::Aborted,
    ];

    /// The raw value on the bus.
    pub const fn raw(self) -> u8 {
        match self {
            CuePhase::Idle => 0,
            CuePhase::Prepare => 1,
            CuePhase::Hold => 2,
            CuePhase::Relax => 3,
            CuePhase::Done => 4,
            CuePhase::Aborted => 5,
        }
    }

    /// The value for a raw value, `None` if the table does not name it.
    pub const fn from_raw(raw: i64) -> Option<Self> {
        match raw {
            0 => Some(CuePhase::Idle),
            1 => Some(CuePhase::Prepare),
            2 => Some(CuePhase::Hold),
            3 => Some(CuePhase::Relax),
            4 => Some(CuePhase::Done),
            5 => Some(CuePhase::Aborted),
            _ => None,
        }
    }

    /// The name hand.dbc gives this value.
    pub const fn dbc_name(self) -> &'static str {
        match self {
            CuePhase::Idle => "IDLE",
            CuePhase::Prepare => "PREPARE",
            CuePhase::Hold => "HOLD",
            CuePhase::Relax => "RELAX",
            CuePhase::Done => "DONE",
            CuePhase::Aborted => "ABORTED",
        }
    }
}

/// Value table `DaemonState` of hand.dbc.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum DaemonState {
    /// `BOOT` (raw 0)
    Boot,
    /// `READY` (raw 1)
    Ready,
    /// `RUNNING` (raw 2)
    Running,
    /// `SAFE` (raw 3)
    Safe,
}

impl DaemonState {
    /// Every value, in raw order.
    pub const ALL: [DaemonState; 4] = [
        DaemonState::Boot,
        DaemonState::Ready,
        DaemonState::Running,
        DaemonState::Safe,
    ];

    /// The raw value on the bus.
    pub const fn raw(self) -> u8 {
        match self {
            DaemonState::Boot => 0,
            DaemonState::Ready => 1,
            DaemonState::Running => 2,
            DaemonState::Safe => 3,
        }
    }

    /// The value for a raw value, `None` if the table does not name it.
    pub const fn from_raw(raw: i64) -> Option<Self> {
        match raw {
            0 => Some(DaemonState::Boot),
            1 => Some(DaemonState::Ready),
            2 => Some(DaemonState::Running),
            3 => Some(DaemonState::Safe),
            _ => None,
        }
    }

    /// The name hand.dbc gives this value.
    pub const fn dbc_name(self) -> &'static str {
        match self {
            DaemonState::Boot => "BOOT",
            DaemonState::Ready => "READY",
            DaemonState::Running => "RUNNING",
            DaemonState::Safe => "SAFE",
        }
    }
}

/// Value table `EstopReason` of hand.dbc.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum EstopReason {
    /// `USER` (raw 0)
    User,
    /// `TECHNICIAN` (raw 1)
    Technician,
    /// `FAULT` (raw 2)
    Fault,
    /// `WATCHDOG` (raw 3)
    Watchdog,
    /// `COMM_LOSS` (raw 4)
    CommLoss,
}

impl EstopReason {
    /// Every value, in raw order.
    pub const ALL: [EstopReason; 5] = [
        EstopReason::User,
        EstopReason::Technician,
        EstopReason::Fault,
        EstopReason::Watchdog,
        EstopReason::CommLoss,
    ];

    /// The raw value on the bus.
    pub const fn raw(self) -> u8 {
        match self {
            EstopReason::User => 0,
            EstopReason::Technician => 1,
            EstopReason::Fault => 2,
            EstopReason::Watchdog => 3,
            EstopReason::CommLoss => 4,
        }
    }

    /// The value for a raw value, `None` if the table does not name it.
    pub const fn from_raw(raw: i64) -> Option<Self> {
        match raw {
            0 => Some(EstopReason::User),
            1 => Some(EstopReason::Technician),
            2 => Some(EstopReason::Fault),
            3 => Some(EstopReason::Watchdog),
            4 => Some(EstopReason::CommLoss),
            _ => None,
        }
    }

    /// The name hand.dbc gives this value.
    pub const fn dbc_name(self) -> &'static str {
        match self {
            EstopReason::User => "USER",
            EstopReason::Technician => "TECHNICIAN",
            EstopReason::Fault => "FAULT",
            EstopReason::Watchdog => "WATCHDOG",
            EstopReason::CommLoss => "COMM_LOSS",
        }
    }
}

/// Value table `EstopRequest` of hand.dbc.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum EstopRequest {
    /// `RELEASE` (raw 0)
    Release,
    /// `STOP` (raw 1)
    Stop,
}

impl EstopRequest {
    /// Every value, in raw order.
    pub const ALL: [EstopRequest; 2] = [EstopRequest::Release, EstopRequest::Stop];

    /// The raw value on the bus.
    pub const fn raw(self) -> u8 {
        match self {
            EstopRequest::Release => 0,
            EstopRequest::Stop => 1,
        }
    }

    /// The value for a raw value, `None` if the table does not name it.
    pub const fn from_raw(raw: i64) -> Option<Self> {
        match raw {
            0 => Some(EstopRequest::Release),
            1 => Some(EstopRequest::Stop),
            _ => None,
        }
    }

    /// The name hand.dbc gives this value.
    pub const fn dbc_name(self) -> &'static str {
        match self {
            EstopRequest::Release => "RELEASE",
            EstopRequest::Stop => "STOP",
        }
    }
}

/// Value table `EstopSource` of hand.dbc.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum EstopSource {
    /// `HAND` (raw 0)
    Hand,
    /// `AMP` (raw 1)
    Amp,
    /// `MC_0` (raw 2)
    Mc0,
    /// `MC_1` (raw 3)
    Mc1,
    /// `MC_2` (raw 4)
    Mc2,
    /// `MC_3` (raw 5)
    Mc3,
    /// `MC_4` (raw 6)
    Mc4,
    /// `TOOL` (raw 7)
    Tool,
    /// `USER_BUTTON` (raw 8)
    UserButton,
}

impl EstopSource {
    /// Every value, in raw order.
    pub const ALL: [EstopSource; 9] = [
        EstopSource::Hand,
        EstopSource::Amp,
        EstopSource::Mc0,
        EstopSource::Mc1,
        EstopSource::Mc2,
        EstopSource::Mc3,
        EstopSource::Mc4,
        EstopSource::Tool,
        EstopSource::UserButton,
    ];

    /// The raw value on the bus.
    pub const fn raw(self) -> u8 {
        match self {
            EstopSource::Hand => 0,
            EstopSource::Amp => 1,
            EstopSource::Mc0 => 2,
            EstopSource::Mc1 => 3,
            EstopSource::Mc2 => 4,
            EstopSource::Mc3 => 5,
            EstopSource::Mc4 => 6,
            EstopSource::Tool => 7,
            EstopSource::UserButton => 8,
        }
    }

    /// The value for a raw value, `None` if the table does not name it.
    pub const fn from_raw(raw: i64) -> Option<Self> {
        match raw {
            0 => Some(EstopSource::Hand),
            1 => Some(EstopSource::Amp),
            2 => Some(EstopSource::Mc0),
            3 => Some(EstopSource::Mc1),
            4 => Some(EstopSource::Mc2),
            5 => Some(EstopSource::Mc3),
            6 => Some(EstopSource::Mc4),
            7 => Some(EstopSource::Tool),
            8 => Some(EstopSource::UserButton),
            _ => None,
        }
    }

    /// The name hand.dbc gives this value.
    pub const fn dbc_name(self) -> &'static str {
        match self {
            EstopSource::Hand => "HAND",
            EstopSource::Amp => "AMP",
            EstopSource::Mc0 => "MC_0",
            EstopSource::Mc1 => "MC_1",
            EstopSource::Mc2 => "MC_2",
            EstopSource::Mc3 => "MC_3",
            EstopSource::Mc4 => "MC_4",
            EstopSource::Tool => "TOOL",
            EstopSource::UserButton => "USER_BUTTON",
        }
    }
}

/// Value table `FingerMode` of hand.dbc.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum FingerMode {
    /// `DISABLED` (raw 0)
    Disabled,
    /// `ACTIVE` (raw 1)
    Active,
    /// `HOLD` (raw 2)
    Hold,
    /// `SAFE_STOP` (raw 3)
    SafeStop,
}

impl FingerMode {
    /// Every value, in raw order.
    pub const ALL: [FingerMode; 4] = [
        FingerMode::Disabled,
        FingerMode::Active,
        FingerMode::Hold,
        FingerMode::SafeStop,
    ];

    /// The raw value on the bus.
    pub const fn raw(self) -> u8 {
        match self {
            FingerMode::Disabled => 0,
            FingerMode::Active => 1,
            FingerMode::Hold => 2,
            FingerMode::SafeStop => 3,
        }
    }

    /// The value for a raw value, `None` if the table does not name it.
    pub const fn from_raw(raw: i64) -> Option<Self> {
        match raw {
            0 => Some(FingerMode::Disabled),
            1 => Some(FingerMode::Active),
            2 => Some(FingerMode::Hold),
            3 => Some(FingerMode::SafeStop),
            _ => None,
        }
    }

    /// The name hand.dbc gives this value.
    pub const fn dbc_name(self) -> &'static str {
        match self {
            FingerMode::Disabled => "DISABLED",
            FingerMode::Active => "ACTIVE",
            FingerMode::Hold => "HOLD",
            FingerMode::SafeStop => "SAFE_STOP",
        }
    }
}

/// Value table `FingerState` of hand.dbc.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum FingerState {
    /// `DISABLED` (raw 0)
    Disabled,
    /// `ACTIVE` (raw 1)
    Active,
    /// `HOLD` (raw 2)
    Hold,
    /// `SAFE_STOP` (raw 3)
    SafeStop,
    /// `BRAKED` (raw 4)
    Braked,
    /// `FAULT` (raw 5)
    Fault,
}

impl FingerState {
    /// Every value, in raw order.
    pub const ALL: [FingerState; 6] = [
        FingerState::Disabled,
        FingerState::Active,
        FingerState::Hold,
        FingerState::SafeStop,
        FingerState::Braked,
        FingerState::Fault,
    ];

    /// The raw value on the bus.
    pub const fn raw(self) -> u8 {
        match self {
            FingerState::Disabled => 0,
            FingerState::Active => 1,
            FingerState::Hold => 2,
            FingerState::SafeStop => 3,
            FingerState::Braked => 4,
            FingerState::Fault => 5,
        }
    }

    /// The value for a raw value, `None` if the table does not name it.
    pub const fn from_raw(raw: i64) -> Option<Self> {
        match raw {
            0 => Some(FingerState::Disabled),
            1 => Some(FingerState::Active),
            2 => Some(FingerState::Hold),
            3 => Some(FingerState::SafeStop),
            4 => Some(FingerState::Braked),
            5 => Some(FingerState::Fault),
            _ => None,
        }
    }

    /// The name hand.dbc gives this value.
    pub const fn dbc_name(self) -> &'static str {
        match self {
            FingerState::Disabled => "DISABLED",
            FingerState::Active => "ACTIVE",
            FingerState::Hold => "HOLD",
            FingerState::SafeStop => "SAFE_STOP",
            FingerState::Braked => "BRAKED",
            FingerState::Fault => "FAULT",
        }
    }
}

/// Message HAND_ESTOP (id 0x080).
///
/// Emergency stop. Any node may send it (see BO_TX_BU_); it is event-driven but repeated every 10 ms while a stop is asserted, and the bus-load sum counts it at that rate as the worst case. Several senders interleave their alive counters, so receivers latch a stop on any frame whose CRC is valid; the counter only classifies repetitions. Highest priority id on the bus.
///
/// DLC 3, every 10 ms, sent by HAND, AMP, MC_0, MC_1, MC_2, MC_3, MC_4, TOOL, received by HAND, AMP, MC_0, MC_1, MC_2, MC_3, MC_4, TOOL. E2E protected: CRC-8 in byte 0, 4-bit alive counter (data id 0x1080)
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct HandEstop {
    crc: u8,
    counter: u8,
    request: EstopRequest,
    source: EstopSource,
    reason: EstopReason,
}

impl HandEstop {
    /// Name in hand.dbc.
    pub const NAME: &'static str = "HAND_ESTOP";
    /// CAN id (11-bit).
    pub const ID: u32 = 0x080;
    /// Payload length in bytes.
    pub const DLC: usize = 3;
    /// Send period from `GenMsgCycleTime` (ms).
    pub const CYCLE_TIME_MS: u32 = 10;
    /// E2E profile.
    pub const E2E: E2eProfile = E2eProfile::from_dbc(0x1080, 4, 3);
    /// Smallest allowed `Crc` (crc).
    pub const CRC_MIN: u8 = 0;
    /// Largest allowed `Crc` (crc).
    pub const CRC_MAX: u8 = 255;
    /// Smallest allowed `Counter` (count).
    pub const COUNTER_MIN: u8 = 0;
    /// Largest allowed `Counter` (count).
    pub const COUNTER_MAX: u8 = 15;

    /// Builds the message from physical values, each checked against hand.dbc. Crc and Counter start at 0: an [`crate::e2e::E2eProtector`] fills them when sending.
    pub fn new(
        request: EstopRequest,
        source: EstopSource,
        reason: EstopReason,
    ) -> Result<Self, CodecError> {
        let mut msg = Self {
            crc: 0,
            counter: 0,
            request: EstopRequest::ALL[0],
            source: EstopSource::ALL[0],
            reason: EstopReason::ALL[0],
        };
        msg.set_request(request);
        msg.set_source(source);
        msg.set_reason(reason);
        Ok(msg)
    }

    /// CAN id.
    pub fn id(&self) -> u32 {
        Self::ID
    }

    /// DBC name.
    pub fn name(&self) -> &'static str {
        Self::NAME
    }

    /// E2E profile.
    pub fn e2e(&self) -> E2eProfile {
        Self::E2E
    }

    /// `Crc` (crc): CRC-8 SAE J1850 over data id 0x1080 and bytes 1..2.
    pub fn crc(&self) -> u8 {
        self.crc
    }

    /// Sets `Crc`; refuses values outside [0, 255].
    pub fn set_crc(&mut self, value: u8) -> Result<(), CodecError> {
        self.crc = value;
        Ok(())
    }

    /// `Counter` (count): 4-bit alive counter of the sender.
    pub fn counter(&self) -> u8 {
        self.counter
    }

    /// Sets `Counter`; refuses values outside [0, 15].
    pub fn set_counter(&mut self, value: u8) -> Result<(), CodecError> {
        if value > 15 {
            return Err(CodecError::RawOutOfRange {
                message: Self::NAME,
                signal: "Counter",
                raw: i64::from(value),
                min: 0,
                max: 15,
            });
        }
        self.counter = value;
        Ok(())
    }

    /// `Request` (enum): STOP latches the stop in every receiver; RELEASE is only a request: handd leaves SAFE only on an explicit handctl arm.
    pub fn request(&self) -> EstopRequest {
        self.request
    }

    /// Sets `Request` (every enum value is in range).
    pub fn set_request(&mut self, value: EstopRequest) {
        self.request = value;
    }

    /// `Source` (enum): Node that raised the stop.
    pub fn source(&self) -> EstopSource {
        self.source
    }

    /// Sets `Source` (every enum value is in range).
    pub fn set_source(&mut self, value: EstopSource) {
        self.source = value;
    }

    /// `Reason` (enum): Why the stop was raised.
    pub fn reason(&self) -> EstopReason {
        self.reason
    }

    /// Sets `Reason` (every enum value is in range).
    pub fn set_reason(&mut self, value: EstopReason) {
        self.reason = value;
    }

    /// Decodes a payload; refuses a wrong length, raw values outside the DBC range and values the value tables do not name. The CRC is not checked here: that is [`crate::e2e::E2eChecker`]'s job.
    #[inline]
    pub fn decode(data: &[u8]) -> Result<Self, CodecError> {
        let message = Self::NAME;
        if data.len() != Self::DLC {
            return Err(CodecError::WrongLength {
                message,
                expected: Self::DLC,
                got: data.len(),
            });
        }
        let mut bytes = [0u8; 8];
        bytes[..Self::DLC].copy_from_slice(data);
        let bits = u64::from_le_bytes(bytes);
        let crc = (bits & 0xff) as u8;
        let counter = ((bits >> 8) & 0xf) as u8;
        let request = ((bits >> 12) & 0x3) as u8;
        let Some(request) = EstopRequest::from_raw(i64::from(request)) else {
            return Err(CodecError::UnknownValue {
                message,
                signal: "Request",
                raw: i64::from(request),
            });
        };
        let source = ((bits >> 16) & 0xf) as u8;
        let Some(source) = EstopSource::from_raw(i64::from(source)) else {
            return Err(CodecError::UnknownValue {
                message,
                signal: "Source",
                raw: i64::from(source),
            });
        };
        let reason = ((bits >> 20) & 0xf) as u8;
        let Some(reason) = EstopReason::from_raw(i64::from(reason)) else {
            return Err(CodecError::UnknownValue {
                message,
                signal: "Reason",
                raw: i64::from(reason),
            });
        };
        Ok(Self {
            crc,
            counter,
            request,
            source,
            reason,
        })
    }

    /// The payload bytes (values were range-checked when set, so this cannot fail).
    #[inline]
    pub fn encode(&self) -> [u8; 3] {
        let mut bits = 0u64;
        bits |= u64::from(self.crc) & 0xff;
        bits |= (u64::from(self.counter) & 0xf) << 8;
        bits |= (u64::from(self.request.raw()) & 0x3) << 12;
        bits |= (u64::from(self.source.raw()) & 0xf) << 16;
        bits |= (u64::from(self.reason.raw()) & 0xf) << 20;
        let mut out = [0u8; 3];
        out.copy_from_slice(&bits.to_le_bytes()[..3]);
        out
    }

    /// The message as a [`CanFrame`].
    pub fn to_frame(&self) -> CanFrame {
        CanFrame::from_dbc(self.id(), &self.encode())
    }

    /// The message as any [`embedded_can::Frame`] (e.g. a SocketCAN frame).
    pub fn to_can_frame<F: embedded_can::Frame>(&self) -> Result<F, CodecError> {
        to_can_frame(self.id(), &self.encode())
    }

    /// Decodes any [`embedded_can::Frame`]; refuses remote frames, extended ids and other messages' ids.
    pub fn try_from_frame<F: embedded_can::Frame>(frame: &F) -> Result<Self, CodecError> {
        let id = standard_data_frame(frame)?;
        if id != Self::ID {
            return Err(CodecError::WrongId {
                message: Self::NAME,
                id,
            });
        }
        Self::decode(frame.data())
    }

    /// Calls `f` with each signal's DBC name and physical value (enums as their raw value).
    pub fn for_each_signal(&self, f: &mut dyn FnMut(&'static str, f64)) {
        f("Crc", f64::from(self.crc));
        f("Counter", f64::from(self.counter));
        f("Request", f64::from(self.request.raw()));
        f("Source", f64::from(self.source.raw()));
        f("Reason", f64::from(self.reason.raw()));
    }

    /// Builds the message from physical values looked up by DBC signal name (enums by raw value), each checked; E2E signals included.
    pub fn from_signals(get: &mut dyn FnMut(&str) -> Option<f64>) -> Result<Self, CodecError> {
        let message = Self::NAME;
        let mut msg = Self {
            crc: 0,
            counter: 0,
            request: EstopRequest::ALL[0],
            source: EstopSource::ALL[0],
            reason: EstopReason::ALL[0],
        };
        let v = get("Crc").ok_or(CodecError::MissingSignal {
            message,
            signal: "Crc",
        })?;
        let raw = whole(message, "Crc", v)?;
        let raw = u8::try_from(raw).map_err(|_| CodecError::RawOutOfRange {
            message,
            signal: "Crc",
            raw,
            min: 0,
            max: 255,
        })?;
        msg.set_crc(raw)?;
        let v = get("Counter").ok_or(CodecError::MissingSignal {
            message,
            signal: "Counter",
        })?;
        let raw = whole(message, "Counter", v)?;
        let raw = u8::try_from(raw).map_err(|_| CodecError::RawOutOfRange {
            message,
            signal: "Counter",
            raw,
            min: 0,
            max: 15,
        })?;
        msg.set_counter(raw)?;
        let v = get("Request").ok_or(CodecError::MissingSignal {
            message,
            signal: "Request",
        })?;
        let raw = whole(message, "Request", v)?;
        msg.request = EstopRequest::from_raw(raw).ok_or(CodecError::UnknownValue {
            message,
            signal: "Request",
            raw,
        })?;
        let v = get("Source").ok_or(CodecError::MissingSignal {
            message,
            signal: "Source",
        })?;
        let raw = whole(message, "Source", v)?;
        msg.source = EstopSource::from_raw(raw).ok_or(CodecError::UnknownValue {
            message,
            signal: "Source",
            raw,
        })?;
        let v = get("Reason").ok_or(CodecError::MissingSignal {
            message,
            signal: "Reason",
        })?;
        let raw = whole(message, "Reason", v)?;
        msg.reason = EstopReason::from_raw(raw).ok_or(CodecError::UnknownValue {
            message,
            signal: "Reason",
            raw,
        })?;
        Ok(msg)
    }
}

impl crate::e2e::Protected for HandEstop {
    fn e2e_profile(&self) -> E2eProfile {
        self.e2e()
    }
    fn to_frame(&self) -> CanFrame {
        HandEstop::to_frame(self)
    }
}

/// Message EMG_SAMPLES_G0 (id 0x100).
///
/// sEMG channels 0..3 of one sample. 12 channels at 1 kHz are split into three groups of four 12-bit samples (G0..G2 on consecutive ids), each frame carrying the sample counter and a CRC: 3 frames per sample keep every frame self-contained (a lost frame loses 4 channels of one sample, never misaligns the rest). The group is given by the CAN id, so no group signal is needed.
///
/// DLC 8, every 1 ms, sent by AMP, received by HAND. E2E protected: CRC-8 in byte 0, 8-bit alive counter (data id 0x1100)
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct EmgSamplesG0 {
    crc: u8,
    counter: u8,
    emg0: i16,
    emg1: i16,
    emg2: i16,
    emg3: i16,
}

impl EmgSamplesG0 {
    /// Name in hand.dbc.
    pub const NAME: &'static str = "EMG_SAMPLES_G0";
    /// CAN id (11-bit).
    pub const ID: u32 = 0x100;
    /// Payload length in bytes.
    pub const DLC: usize = 8;
    /// Send period from `GenMsgCycleTime` (ms).
    pub const CYCLE_TIME_MS: u32 = 1;
    /// E2E profile.
    pub const E2E: E2eProfile = E2eProfile::from_dbc(0x1100, 8, 8);
    /// Smallest allowed `Crc` (crc).
    pub const CRC_MIN: u8 = 0;
    /// Largest allowed `Crc` (crc).
    pub const CRC_MAX: u8 = 255;
    /// Smallest allowed `Counter` (count).
    pub const COUNTER_MIN: u8 = 0;
    /// Largest allowed `Counter` (count).
    pub const COUNTER_MAX: u8 = 255;
    /// Smallest allowed `Emg0` (uV).
    pub const EMG0_MIN: f64 = -5120.0;
    /// Largest allowed `Emg0` (uV).
    pub const EMG0_MAX: f64 = 5117.5;
    /// `Emg0`: uV per raw step.
    pub const EMG0_FACTOR: f64 = 2.5;
    /// `Emg0`: physical value of raw 0 (uV).
    pub const EMG0_OFFSET: f64 = 0.0;
    /// Smallest allowed raw `Emg0` on the bus.
    pub const EMG0_RAW_MIN: i16 = -2048;
    /// Largest allowed raw `Emg0` on the bus.
    pub const EMG0_RAW_MAX: i16 = 2047;
    /// Smallest allowed `Emg1` (uV).
    pub const EMG1_MIN: f64 = -5120.0;
    /// Largest allowed `Emg1` (uV).
    pub const EMG1_MAX: f64 = 5117.5;
    /// `Emg1`: uV per raw step.
    pub const EMG1_FACTOR: f64 = 2.5;
    /// `Emg1`: physical value of raw 0 (uV).
    pub const EMG1_OFFSET: f64 = 0.0;
    /// Smallest allowed raw `Emg1` on the bus.
    pub const EMG1_RAW_MIN: i16 = -2048;
    /// Largest allowed raw `Emg1` on the bus.
    pub const EMG1_RAW_MAX: i16 = 2047;
    /// Smallest allowed `Emg2` (uV).
    pub const EMG2_MIN: f64 = -5120.0;
    /// Largest allowed `Emg2` (uV).
    pub const EMG2_MAX: f64 = 5117.5;
    /// `Emg2`: uV per raw step.
    pub const EMG2_FACTOR: f64 = 2.5;
    /// `Emg2`: physical value of raw 0 (uV).
    pub const EMG2_OFFSET: f64 = 0.0;
    /// Smallest allowed raw `Emg2` on the bus.
    pub const EMG2_RAW_MIN: i16 = -2048;
    /// Largest allowed raw `Emg2` on the bus.
    pub const EMG2_RAW_MAX: i16 = 2047;
    /// Smallest allowed `Emg3` (uV).
    pub const EMG3_MIN: f64 = -5120.0;
    /// Largest allowed `Emg3` (uV).
    pub const EMG3_MAX: f64 = 5117.5;
    /// `Emg3`: uV per raw step.
    pub const EMG3_FACTOR: f64 = 2.5;
    /// `Emg3`: physical value of raw 0 (uV).
    pub const EMG3_OFFSET: f64 = 0.0;
    /// Smallest allowed raw `Emg3` on the bus.
    pub const EMG3_RAW_MIN: i16 = -2048;
    /// Largest allowed raw `Emg3` on the bus.
    pub const EMG3_RAW_MAX: i16 = 2047;

    /// Builds the message from physical values, each checked against hand.dbc. Crc and Counter start at 0: an [`crate::e2e::E2eProtector`] fills them when sending.
    pub fn new(emg0: f64, emg1: f64, emg2: f64, emg3: f64) -> Result<Self, CodecError> {
        let mut msg = Self {
            crc: 0,
            counter: 0,
            emg0: 0,
            emg1: 0,
            emg2: 0,
            emg3: 0,
        };
        msg.set_emg0(emg0)?;
        msg.set_emg1(emg1)?;
        msg.set_emg2(emg2)?;
        msg.set_emg3(emg3)?;
        Ok(msg)
    }

    /// CAN id.
    pub fn id(&self) -> u32 {
        Self::ID
    }

    /// DBC name.
    pub fn name(&self) -> &'static str {
        Self::NAME
    }

    /// E2E profile.
    pub fn e2e(&self) -> E2eProfile {
        Self::E2E
    }

    /// `Crc` (crc): CRC-8 SAE J1850 over data id 0x1100 and bytes 1..7.
    pub fn crc(&self) -> u8 {
        self.crc
    }

    /// Sets `Crc`; refuses values outside [0, 255].
    pub fn set_crc(&mut self, value: u8) -> Result<(), CodecError> {
        self.crc = value;
        Ok(())
    }

    /// `Counter` (count): Sample counter, the same in G0, G1 and G2 for one sample instant; it doubles as the 8-bit E2E alive counter. Wraps every 256 samples (256 ms), far beyond the 20 ms gap after which a window is invalid.
    pub fn counter(&self) -> u8 {
        self.counter
    }

    /// Sets `Counter`; refuses values outside [0, 255].
    pub fn set_counter(&mut self, value: u8) -> Result<(), CodecError> {
        self.counter = value;
        Ok(())
    }

    /// `Emg0` (uV): Channel 0, referred to the electrode input: 2.5 uV per LSB, signed 12 bit, +-5.12 mV full scale.
    pub fn emg0(&self) -> f64 {
        f64::from(self.emg0) * 2.5
    }

    /// `Emg0` as the raw integer on the bus.
    pub fn emg0_raw(&self) -> i16 {
        self.emg0
    }

    /// Sets `Emg0` from a physical value, rounded to the nearest raw step; refuses non-finite values and values outside [-5120, 5117.5] uV (never wraps or saturates).
    pub fn set_emg0(&mut self, value: f64) -> Result<(), CodecError> {
        let tol = 2.4999999999999998e-6;
        if !value.is_finite() || value < Self::EMG0_MIN - tol || value > Self::EMG0_MAX + tol {
            return Err(CodecError::OutOfRange {
                message: Self::NAME,
                signal: "Emg0",
                value,
                min: Self::EMG0_MIN,
                max: Self::EMG0_MAX,
                unit: "uV",
            });
        }
        let raw = round((value - 0.0) / 2.5) as i64;
        if !(-2048..=2047).contains(&raw) {
            return Err(CodecError::OutOfRange {
                message: Self::NAME,
                signal: "Emg0",
                value,
                min: Self::EMG0_MIN,
                max: Self::EMG0_MAX,
                unit: "uV",
            });
        }
        self.emg0 = raw as i16;
        Ok(())
    }

    /// Sets `Emg0` from a raw value; refuses raw values outside [-2048, 2047].
    pub fn set_emg0_raw(&mut self, raw: i16) -> Result<(), CodecError> {
        if !(-2048..=2047).contains(&raw) {
            return Err(CodecError::RawOutOfRange {
                message: Self::NAME,
                signal: "Emg0",
                raw: i64::from(raw),
                min: -2048,
                max: 2047,
            });
        }
        self.emg0 = raw;
        Ok(())
    }

    /// `Emg1` (uV): Channel 1, 2.5 uV per LSB.
    pub fn emg1(&self) -> f64 {
        f64::from(self.emg1) * 2.5
    }

    /// `Emg1` as the raw integer on the bus.
    pub fn emg1_raw(&self) -> i16 {
        self.emg1
    }

    /// Sets `Emg1` from a physical value, rounded to the nearest raw step; refuses non-finite values and values outside [-5120, 5117.5] uV (never wraps or saturates).
    pub fn set_emg1(&mut self, value: f64) -> Result<(), CodecError> {
        let tol = 2.4999999999999998e-6;
        if !value.is_finite() || value < Self::EMG1_MIN - tol || value > Self::EMG1_MAX + tol {
            return Err(CodecError::OutOfRange {
                message: Self::NAME,
                signal: "Emg1",
                value,
                min: Self::EMG1_MIN,
                max: Self::EMG1_MAX,
                unit: "uV",
            });
        }
        let raw = round((value - 0.0) / 2.5) as i64;
        if !(-2048..=2047).contains(&raw) {
            return Err(CodecError::OutOfRange {
                message: Self::NAME,
                signal: "Emg1",
                value,
                min: Self::EMG1_MIN,
                max: Self::EMG1_MAX,
                unit: "uV",
            });
        }
        self.emg1 = raw as i16;
        Ok(())
    }

    /// Sets `Emg1` from a raw value; refuses raw values outside [-2048, 2047].
    pub fn set_emg1_raw(&mut self, raw: i16) -> Result<(), CodecError> {
        if !(-2048..=2047).contains(&raw) {
            return Err(CodecError::RawOutOfRange {
                message: Self::NAME,
                signal: "Emg1",
                raw: i64::from(raw),
                min: -2048,
                max: 2047,
            });
        }
        self.emg1 = raw;
        Ok(())
    }

    /// `Emg2` (uV): Channel 2, 2.5 uV per LSB.
    pub fn emg2(&self) -> f64 {
        f64::from(self.emg2) * 2.5
    }

    /// `Emg2` as the raw integer on the bus.
    pub fn emg2_raw(&self) -> i16 {
        self.emg2
    }

    /// Sets `Emg2` from a physical value, rounded to the nearest raw step; refuses non-finite values and values outside [-5120, 5117.5] uV (never wraps or saturates).
    pub fn set_emg2(&mut self, value: f64) -> Result<(), CodecError> {
        let tol = 2.4999999999999998e-6;
        if !value.is_finite() || value < Self::EMG2_MIN - tol || value > Self::EMG2_MAX + tol {
            return Err(CodecError::OutOfRange {
                message: Self::NAME,
                signal: "Emg2",
                value,
                min: Self::EMG2_MIN,
                max: Self::EMG2_MAX,
                unit: "uV",
            });
        }
        let raw = round((value - 0.0) / 2.5) as i64;
        if !(-2048..=2047).contains(&raw) {
            return Err(CodecError::OutOfRange {
                message: Self::NAME,
                signal: "Emg2",
                value,
                min: Self::EMG2_MIN,
                max: Self::EMG2_MAX,
                unit: "uV",
            });
        }
        self.emg2 = raw as i16;
        Ok(())
    }

    /// Sets `Emg2` from a raw value; refuses raw values outside [-2048, 2047].
    pub fn set_emg2_raw(&mut self, raw: i16) -> Result<(), CodecError> {
        if !(-2048..=2047).contains(&raw) {
            return Err(CodecError::RawOutOfRange {
                message: Self::NAME,
                signal: "Emg2",
                raw: i64::from(raw),
                min: -2048,
                max: 2047,
            });
        }
        self.emg2 = raw;
        Ok(())
    }

    /// `Emg3` (uV): Channel 3, 2.5 uV per LSB.
    pub fn emg3(&self) -> f64 {
        f64::from(self.emg3) * 2.5
    }

    /// `Emg3` as the raw integer on the bus.
    pub fn emg3_raw(&self) -> i16 {
        self.emg3
    }

    /// Sets `Emg3` from a physical value, rounded to the nearest raw step; refuses non-finite values and values outside [-5120, 5117.5] uV (never wraps or saturates).
    pub fn set_emg3(&mut self, value: f64) -> Result<(), CodecError> {
        let tol = 2.4999999999999998e-6;
        if !value.is_finite() || value < Self::EMG3_MIN - tol || value > Self::EMG3_MAX + tol {
            return Err(CodecError::OutOfRange {
                message: Self::NAME,
                signal: "Emg3",
                value,
                min: Self::EMG3_MIN,
                max: Self::EMG3_MAX,
                unit: "uV",
            });
        }
        let raw = round((value - 0.0) / 2.5) as i64;
        if !(-2048..=2047).contains(&raw) {
            return Err(CodecError::OutOfRange {
                message: Self::NAME,
                signal: "Emg3",
                value,
                min: Self::EMG3_MIN,
                max: Self::EMG3_MAX,
                unit: "uV",
            });
        }
        self.emg3 = raw as i16;
        Ok(())
    }

    /// Sets `Emg3` from a raw value; refuses raw values outside [-2048, 2047].
    pub fn set_emg3_raw(&mut self, raw: i16) -> Result<(), CodecError> {
        if !(-2048..=2047).contains(&raw) {
            return Err(CodecError::RawOutOfRange {
                message: Self::NAME,
                signal: "Emg3",
                raw: i64::from(raw),
                min: -2048,
                max: 2047,
            });
        }
        self.emg3 = raw;
        Ok(())
    }

    /// Decodes a payload; refuses a wrong length, raw values outside the DBC range and values the value tables do not name. The CRC is not checked here: that is [`crate::e2e::E2eChecker`]'s job.
    #[inline]
    pub fn decode(data: &[u8]) -> Result<Self, CodecError> {
        let message = Self::NAME;
        if data.len() != Self::DLC {
            return Err(CodecError::WrongLength {
                message,
                expected: Self::DLC,
                got: data.len(),
            });
        }
        let mut bytes = [0u8; 8];
        bytes[..Self::DLC].copy_from_slice(data);
        let bits = u64::from_le_bytes(bytes);
        let crc = (bits & 0xff) as u8;
        let counter = ((bits >> 8) & 0xff) as u8;
        let emg0 = (((bits << 36) as i64) >> 52) as i16;
        let emg1 = (((bits << 24) as i64) >> 52) as i16;
        let emg2 = (((bits << 12) as i64) >> 52) as i16;
        let emg3 = ((bits as i64) >> 52) as i16;
        Ok(Self {
            crc,
            counter,
            emg0,
            emg1,
            emg2,
            emg3,
        })
    }

    /// The payload bytes (values were range-checked when set, so this cannot fail).
    #[inline]
    pub fn encode(&self) -> [u8; 8] {
        let mut bits = 0u64;
        bits |= u64::from(self.crc) & 0xff;
        bits |= (u64::from(self.counter) & 0xff) << 8;
        bits |= ((i64::from(self.emg0) as u64) & 0xfff) << 16;
        bits |= ((i64::from(self.emg1) as u64) & 0xfff) << 28;
        bits |= ((i64::from(self.emg2) as u64) & 0xfff) << 40;
        bits |= ((i64::from(self.emg3) as u64) & 0xfff) << 52;
        bits.to_le_bytes()
    }

    /// The message as a [`CanFrame`].
    pub fn to_frame(&self) -> CanFrame {
        CanFrame::from_dbc(self.id(), &self.encode())
    }

    /// The message as any [`embedded_can::Frame`] (e.g. a SocketCAN frame).
    pub fn to_can_frame<F: embedded_can::Frame>(&self) -> Result<F, CodecError> {
        to_can_frame(self.id(), &self.encode())
    }

    /// Decodes any [`embedded_can::Frame`]; refuses remote frames, extended ids and other messages' ids.
    pub fn try_from_frame<F: embedded_can::Frame>(frame: &F) -> Result<Self, CodecError> {
        let id = standard_data_frame(frame)?;
        if id != Self::ID {
            return Err(CodecError::WrongId {
                message: Self::NAME,
                id,
            });
        }
        Self::decode(frame.data())
    }

    /// Calls `f` with each signal's DBC name and physical value (enums as their raw value).
    pub fn for_each_signal(&self, f: &mut dyn FnMut(&'static str, f64)) {
        f("Crc", f64::from(self.crc));
        f("Counter", f64::from(self.counter));
        f("Emg0", self.emg0());
        f("Emg1", self.emg1());
        f("Emg2", self.emg2());
        f("Emg3", self.emg3());
    }

    /// Builds the message from physical values looked up by DBC signal name (enums by raw value), each checked; E2E signals included.
    pub fn from_signals(get: &mut dyn FnMut(&str) -> Option<f64>) -> Result<Self, CodecError> {
        let message = Self::NAME;
        let mut msg = Self {
            crc: 0,
            counter: 0,
            emg0: 0,
            emg1: 0,
            emg2: 0,
            emg3: 0,
        };
        let v = get("Crc").ok_or(CodecError::MissingSignal {
            message,
            signal: "Crc",
        })?;
        let raw = whole(message, "Crc", v)?;
        let raw = u8::try_from(raw).map_err(|_| CodecError::RawOutOfRange {
            message,
            signal: "Crc",
            raw,
            min: 0,
            max: 255,
        })?;
        msg.set_crc(raw)?;
        let v = get("Counter").ok_or(CodecError::MissingSignal {
            message,
            signal: "Counter",
        })?;
        let raw = whole(message, "Counter", v)?;
        let raw = u8::try_from(raw).map_err(|_| CodecError::RawOutOfRange {
            message,
            signal: "Counter",
            raw,
            min: 0,
            max: 255,
        })?;
        msg.set_counter(raw)?;
        let v = get("Emg0").ok_or(CodecError::MissingSignal {
            message,
            signal: "Emg0",
        })?;
        msg.set_emg0(v)?;
        let v = get("Emg1").ok_or(CodecError::MissingSignal {
            message,
            signal: "Emg1",
        })?;
        msg.set_emg1(v)?;
        let v = get("Emg2").ok_or(CodecError::MissingSignal {
            message,
            signal: "Emg2",
        })?;
        msg.set_emg2(v)?;
        let v = get("Emg3").ok_or(CodecError::MissingSignal {
            message,
            signal: "Emg3",
        })?;
        msg.set_emg3(v)?;
        Ok(msg)
    }
}

impl crate::e2e::Protected for EmgSamplesG0 {
    fn e2e_profile(&self) -> E2eProfile {
        self.e2e()
    }
    fn to_frame(&self) -> CanFrame {
        EmgSamplesG0::to_frame(self)
    }
}

/// Message EMG_SAMPLES_G1 (id 0x101).
///
/// sEMG channels 4..7 of one sample (see EMG_SAMPLES_G0).
///
/// DLC 8, every 1 ms, sent by AMP, received by HAND. E2E protected: CRC-8 in byte 0, 8-bit alive counter (data id 0x1101)
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct EmgSamplesG1 {
    crc: u8,
    counter: u8,
    emg4: i16,
    emg5: i16,
    emg6: i16,
    emg7: i16,
}

impl EmgSamplesG1 {
    /// Name in hand.dbc.
    pub const NAME: &'static str = "EMG_SAMPLES_G1";
    /// CAN id (11-bit).
    pub const ID: u32 = 0x101;
    /// Payload length in bytes.
    pub const DLC: usize = 8;
    /// Send period from `GenMsgCycleTime` (ms).
    pub const CYCLE_TIME_MS: u32 = 1;
    /// E2E profile.
    pub const E2E: E2eProfile = E2eProfile::from_dbc(0x1101, 8, 8);
    /// Smallest allowed `Crc` (crc).
    pub const CRC_MIN: u8 = 0;
    /// Largest allowed `Crc` (crc).
    pub const CRC_MAX: u8 = 255;
    /// Smallest allowed `Counter` (count).
    pub const COUNTER_MIN: u8 = 0;
    /// Largest allowed `Counter` (count).
    pub const COUNTER_MAX: u8 = 255;
    /// Smallest allowed `Emg4` (uV).
    pub const EMG4_MIN: f64 = -5120.0;
    /// Largest allowed `Emg4` (uV).
    pub const EMG4_MAX: f64 = 5117.5;
    /// `Emg4`: uV per raw step.
    pub const EMG4_FACTOR: f64 = 2.5;
    /// `Emg4`: physical value of raw 0 (uV).
    pub const EMG4_OFFSET: f64 = 0.0;
    /// Smallest allowed raw `Emg4` on the bus.
    pub const EMG4_RAW_MIN: i16 = -2048;
    /// Largest allowed raw `Emg4` on the bus.
    pub const EMG4_RAW_MAX: i16 = 2047;
    /// Smallest allowed `Emg5` (uV).
    pub const EMG5_MIN: f64 = -5120.0;
    /// Largest allowed `Emg5` (uV).
    pub const EMG5_MAX: f64 = 5117.5;
    /// `Emg5`: uV per raw step.
    pub const EMG5_FACTOR: f64 = 2.5;
    /// `Emg5`: physical value of raw 0 (uV).
    pub const EMG5_OFFSET: f64 = 0.0;
    /// Smallest allowed raw `Emg5` on the bus.
    pub const EMG5_RAW_MIN: i16 = -2048;
    /// Largest allowed raw `Emg5` on the bus.
    pub const EMG5_RAW_MAX: i16 = 2047;
    /// Smallest allowed `Emg6` (uV).
    pub const EMG6_MIN: f64 = -5120.0;
    /// Largest allowed `Emg6` (uV).
    pub const EMG6_MAX: f64 = 5117.5;
    /// `Emg6`: uV per raw step.
    pub const EMG6_FACTOR: f64 = 2.5;
    /// `Emg6`: physical value of raw 0 (uV).
    pub const EMG6_OFFSET: f64 = 0.0;
    /// Smallest allowed raw `Emg6` on the bus.
    pub const EMG6_RAW_MIN: i16 = -2048;
    /// Largest allowed raw `Emg6` on the bus.
    pub const EMG6_RAW_MAX: i16 = 2047;
    /// Smallest allowed `Emg7` (uV).
    pub const EMG7_MIN: f64 = -5120.0;
    /// Largest allowed `Emg7` (uV).
    pub const EMG7_MAX: f64 = 5117.5;
    /// `Emg7`: uV per raw step.
    pub const EMG7_FACTOR: f64 = 2.5;
    /// `Emg7`: physical value of raw 0 (uV).
    pub const EMG7_OFFSET: f64 = 0.0;
    /// Smallest allowed raw `Emg7` on the bus.
    pub const EMG7_RAW_MIN: i16 = -2048;
    /// Largest allowed raw `Emg7` on the bus.
    pub const EMG7_RAW_MAX: i16 = 2047;

    /// Builds the message from physical values, each checked against hand.dbc. Crc and Counter start at 0: an [`crate::e2e::E2eProtector`] fills them when sending.
    pub fn new(emg4: f64, emg5: f64, emg6: f64, emg7: f64) -> Result<Self, CodecError> {
        let mut msg = Self {
            crc: 0,
            counter: 0,
            emg4: 0,
            emg5: 0,
            emg6: 0,
            emg7: 0,
        };
        msg.set_emg4(emg4)?;
        msg.set_emg5(emg5)?;
        msg.set_emg6(emg6)?;
        msg.set_emg7(emg7)?;
        Ok(msg)
    }

    /// CAN id.
    pub fn id(&self) -> u32 {
        Self::ID
    }

    /// DBC name.
    pub fn name(&self) -> &'static str {
        Self::NAME
    }

    /// E2E profile.
    pub fn e2e(&self) -> E2eProfile {
        Self::E2E
    }

    /// `Crc` (crc): CRC-8 SAE J1850 over data id 0x1101 and bytes 1..7.
    pub fn crc(&self) -> u8 {
        self.crc
    }

    /// Sets `Crc`; refuses values outside [0, 255].
    pub fn set_crc(&mut self, value: u8) -> Result<(), CodecError> {
        self.crc = value;
        Ok(())
    }

    /// `Counter` (count): Sample counter, equal to G0's for the same sample; 8-bit E2E alive counter.
    pub fn counter(&self) -> u8 {
        self.counter
    }

    /// Sets `Counter`; refuses values outside [0, 255].
    pub fn set_counter(&mut self, value: u8) -> Result<(), CodecError> {
        self.counter = value;
        Ok(())
    }

    /// `Emg4` (uV): Channel 4, 2.5 uV per LSB.
    pub fn emg4(&self) -> f64 {
        f64::from(self.emg4) * 2.5
    }

    /// `Emg4` as the raw integer on the bus.
    pub fn emg4_raw(&self) -> i16 {
        self.emg4
    }

    /// Sets `Emg4` from a physical value, rounded to the nearest raw step; refuses non-finite values and values outside [-5120, 5117.5] uV (never wraps or saturates).
    pub fn set_emg4(&mut self, value: f64) -> Result<(), CodecError> {
        let tol = 2.4999999999999998e-6;
        if !value.is_finite() || value < Self::EMG4_MIN - tol || value > Self::EMG4_MAX + tol {
            return Err(CodecError::OutOfRange {
                message: Self::NAME,
                signal: "Emg4",
                value,
                min: Self::EMG4_MIN,
                max: Self::EMG4_MAX,
                unit: "uV",
            });
        }
        let raw = round((value - 0.0) / 2.5) as i64;
        if !(-2048..=2047).contains(&raw) {
            return Err(CodecError::OutOfRange {
                message: Self::NAME,
                signal: "Emg4",
                value,
                min: Self::EMG4_MIN,
                max: Self::EMG4_MAX,
                unit: "uV",
            });
        }
        self.emg4 = raw as i16;
        Ok(())
    }

    /// Sets `Emg4` from a raw value; refuses raw values outside [-2048, 2047].
    pub fn set_emg4_raw(&mut self, raw: i16) -> Result<(), CodecError> {
        if !(-2048..=2047).contains(&raw) {
            return Err(CodecError::RawOutOfRange {
                message: Self::NAME,
                signal: "Emg4",
                raw: i64::from(raw),
                min: -2048,
                max: 2047,
            });
        }
        self.emg4 = raw;
        Ok(())
    }

    /// `Emg5` (uV): Channel 5, 2.5 uV per LSB.
    pub fn emg5(&self) -> f64 {
        f64::from(self.emg5) * 2.5
    }

    /// `Emg5` as the raw integer on the bus.
    pub fn emg5_raw(&self) -> i16 {
        self.emg5
    }

    /// Sets `Emg5` from a physical value, rounded to the nearest raw step; refuses non-finite values and values outside [-5120, 5117.5] uV (never wraps or saturates).
    pub fn set_emg5(&mut self, value: f64) -> Result<(), CodecError> {
        let tol = 2.4999999999999998e-6;
        if !value.is_finite() || value < Self::EMG5_MIN - tol || value > Self::EMG5_MAX + tol {
            return Err(CodecError::OutOfRange {
                message: Self::NAME,
                signal: "Emg5",
                value,
                min: Self::EMG5_MIN,
                max: Self::EMG5_MAX,
                unit: "uV",
            });
        }
        let raw = round((value - 0.0) / 2.5) as i64;
        if !(-2048..=2047).contains(&raw) {
            return Err(CodecError::OutOfRange {
                message: Self::NAME,
                signal: "Emg5",
                value,
                min: Self::EMG5_MIN,
                max: Self::EMG5_MAX,
                unit: "uV",
            });
        }
        self.emg5 = raw as i16;
        Ok(())
    }

    /// Sets `Emg5` from a raw value; refuses raw values outside [-2048, 2047].
    pub fn set_emg5_raw(&mut self, raw: i16) -> Result<(), CodecError> {
        if !(-2048..=2047).contains(&raw) {
            return Err(CodecError::RawOutOfRange {
                message: Self::NAME,
                signal: "Emg5",
                raw: i64::from(raw),
                min: -2048,
                max: 2047,
            });
        }
        self.emg5 = raw;
        Ok(())
    }

    /// `Emg6` (uV): Channel 6, 2.5 uV per LSB.
    pub fn emg6(&self) -> f64 {
        f64::from(self.emg6) * 2.5
    }

    /// `Emg6` as the raw integer on the bus.
    pub fn emg6_raw(&self) -> i16 {
        self.emg6
    }

    /// Sets `Emg6` from a physical value, rounded to the nearest raw step; refuses non-finite values and values outside [-5120, 5117.5] uV (never wraps or saturates).
    pub fn set_emg6(&mut self, value: f64) -> Result<(), CodecError> {
        let tol = 2.4999999999999998e-6;
        if !value.is_finite() || value < Self::EMG6_MIN - tol || value > Self::EMG6_MAX + tol {
            return Err(CodecError::OutOfRange {
                message: Self::NAME,
                signal: "Emg6",
                value,
                min: Self::EMG6_MIN,
                max: Self::EMG6_MAX,
                unit: "uV",
            });
        }
        let raw = round((value - 0.0) / 2.5) as i64;
        if !(-2048..=2047).contains(&raw) {
            return Err(CodecError::OutOfRange {
                message: Self::NAME,
                signal: "Emg6",
                value,
                min: Self::EMG6_MIN,
                max: Self::EMG6_MAX,
                unit: "uV",
            });
        }
        self.emg6 = raw as i16;
        Ok(())
    }

    /// Sets `Emg6` from a raw value; refuses raw values outside [-2048, 2047].
    pub fn set_emg6_raw(&mut self, raw: i16) -> Result<(), CodecError> {
        if !(-2048..=2047).contains(&raw) {
            return Err(CodecError::RawOutOfRange {
                message: Self::NAME,
                signal: "Emg6",
                raw: i64::from(raw),
                min: -2048,
                max: 2047,
            });
        }
        self.emg6 = raw;
        Ok(())
    }

    /// `Emg7` (uV): Channel 7, 2.5 uV per LSB.
    pub fn emg7(&self) -> f64 {
        f64::from(self.emg7) * 2.5
    }

    /// `Emg7` as the raw integer on the bus.
    pub fn emg7_raw(&self) -> i16 {
        self.emg7
    }

    /// Sets `Emg7` from a physical value, rounded to the nearest raw step; refuses non-finite values and values outside [-5120, 5117.5] uV (never wraps or saturates).
    pub fn set_emg7(&mut self, value: f64) -> Result<(), CodecError> {
        let tol = 2.4999999999999998e-6;
        if !value.is_finite() || value < Self::EMG7_MIN - tol || value > Self::EMG7_MAX + tol {
            return Err(CodecError::OutOfRange {
                message: Self::NAME,
                signal: "Emg7",
                value,
                min: Self::EMG7_MIN,
                max: Self::EMG7_MAX,
                unit: "uV",
            });
        }
        let raw = round((value - 0.0) / 2.5) as i64;
        if !(-2048..=2047).contains(&raw) {
            return Err(CodecError::OutOfRange {
                message: Self::NAME,
                signal: "Emg7",
                value,
                min: Self::EMG7_MIN,
                max: Self::EMG7_MAX,
                unit: "uV",
            });
        }
        self.emg7 = raw as i16;
        Ok(())
    }

    /// Sets `Emg7` from a raw value; refuses raw values outside [-2048, 2047].
    pub fn set_emg7_raw(&mut self, raw: i16) -> Result<(), CodecError> {
        if !(-2048..=2047).contains(&raw) {
            return Err(CodecError::RawOutOfRange {
                message: Self::NAME,
                signal: "Emg7",
                raw: i64::from(raw),
                min: -2048,
                max: 2047,
            });
        }
        self.emg7 = raw;
        Ok(())
    }

    /// Decodes a payload; refuses a wrong length, raw values outside the DBC range and values the value tables do not name. The CRC is not checked here: that is [`crate::e2e::E2eChecker`]'s job.
    #[inline]
    pub fn decode(data: &[u8]) -> Result<Self, CodecError> {
        let message = Self::NAME;
        if data.len() != Self::DLC {
            return Err(CodecError::WrongLength {
                message,
                expected: Self::DLC,
                got: data.len(),
            });
        }
        let mut bytes = [0u8; 8];
        bytes[..Self::DLC].copy_from_slice(data);
        let bits = u64::from_le_bytes(bytes);
        let crc = (bits & 0xff) as u8;
        let counter = ((bits >> 8) & 0xff) as u8;
        let emg4 = (((bits << 36) as i64) >> 52) as i16;
        let emg5 = (((bits << 24) as i64) >> 52) as i16;
        let emg6 = (((bits << 12) as i64) >> 52) as i16;
        let emg7 = ((bits as i64) >> 52) as i16;
        Ok(Self {
            crc,
            counter,
            emg4,
            emg5,
            emg6,
            emg7,
        })
    }

    /// The payload bytes (values were range-checked when set, so this cannot fail).
    #[inline]
    pub fn encode(&self) -> [u8; 8] {
        let mut bits = 0u64;
        bits |= u64::from(self.crc) & 0xff;
        bits |= (u64::from(self.counter) & 0xff) << 8;
        bits |= ((i64::from(self.emg4) as u64) & 0xfff) << 16;
        bits |= ((i64::from(self.emg5) as u64) & 0xfff) << 28;
        bits |= ((i64::from(self.emg6) as u64) & 0xfff) << 40;
        bits |= ((i64::from(self.emg7) as u64) & 0xfff) << 52;
        bits.to_le_bytes()
    }

    /// The message as a [`CanFrame`].
    pub fn to_frame(&self) -> CanFrame {
        CanFrame::from_dbc(self.id(), &self.encode())
    }

    /// The message as any [`embedded_can::Frame`] (e.g. a SocketCAN frame).
    pub fn to_can_frame<F: embedded_can::Frame>(&self) -> Result<F, CodecError> {
        to_can_frame(self.id(), &self.encode())
    }

    /// Decodes any [`embedded_can::Frame`]; refuses remote frames, extended ids and other messages' ids.
    pub fn try_from_frame<F: embedded_can::Frame>(frame: &F) -> Result<Self, CodecError> {
        let id = standard_data_frame(frame)?;
        if id != Self::ID {
            return Err(CodecError::WrongId {
                message: Self::NAME,
                id,
            });
        }
        Self::decode(frame.data())
    }

    /// Calls `f` with each signal's DBC name and physical value (enums as their raw value).
    pub fn for_each_signal(&self, f: &mut dyn FnMut(&'static str, f64)) {
        f("Crc", f64::from(self.crc));
        f("Counter", f64::from(self.counter));
        f("Emg4", self.emg4());
        f("Emg5", self.emg5());
        f("Emg6", self.emg6());
        f("Emg7", self.emg7());
    }

    /// Builds the message from physical values looked up by DBC signal name (enums by raw value), each checked; E2E signals included.
    pub fn from_signals(get: &mut dyn FnMut(&str) -> Option<f64>) -> Result<Self, CodecError> {
        let message = Self::NAME;
        let mut msg = Self {
            crc: 0,
            counter: 0,
            emg4: 0,
            emg5: 0,
            emg6: 0,
            emg7: 0,
        };
        let v = get("Crc").ok_or(CodecError::MissingSignal {
            message,
            signal: "Crc",
        })?;
        let raw = whole(message, "Crc", v)?;
        let raw = u8::try_from(raw).map_err(|_| CodecError::RawOutOfRange {
            message,
            signal: "Crc",
            raw,
            min: 0,
            max: 255,
        })?;
        msg.set_crc(raw)?;
        let v = get("Counter").ok_or(CodecError::MissingSignal {
            message,
            signal: "Counter",
        })?;
        let raw = whole(message, "Counter", v)?;
        let raw = u8::try_from(raw).map_err(|_| CodecError::RawOutOfRange {
            message,
            signal: "Counter",
            raw,
            min: 0,
            max: 255,
        })?;
        msg.set_counter(raw)?;
        let v = get("Emg4").ok_or(CodecError::MissingSignal {
            message,
            signal: "Emg4",
        })?;
        msg.set_emg4(v)?;
        let v = get("Emg5").ok_or(CodecError::MissingSignal {
            message,
            signal: "Emg5",
        })?;
        msg.set_emg5(v)?;
        let v = get("Emg6").ok_or(CodecError::MissingSignal {
            message,
            signal: "Emg6",
        })?;
        msg.set_emg6(v)?;
        let v = get("Emg7").ok_or(CodecError::MissingSignal {
            message,
            signal: "Emg7",
        })?;
        msg.set_emg7(v)?;
        Ok(msg)
    }
}

impl crate::e2e::Protected for EmgSamplesG1 {
    fn e2e_profile(&self) -> E2eProfile {
        self.e2e()
    }
    fn to_frame(&self) -> CanFrame {
        EmgSamplesG1::to_frame(self)
    }
}

/// Message EMG_SAMPLES_G2 (id 0x102).
///
/// sEMG channels 8..11 of one sample (see EMG_SAMPLES_G0).
///
/// DLC 8, every 1 ms, sent by AMP, received by HAND. E2E protected: CRC-8 in byte 0, 8-bit alive counter (data id 0x1102)
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct EmgSamplesG2 {
    crc: u8,
    counter: u8,
    emg8: i16,
    emg9: i16,
    emg10: i16,
    emg11: i16,
}

impl EmgSamplesG2 {
    /// Name in hand.dbc.
    pub const NAME: &'static str = "EMG_SAMPLES_G2";
    /// CAN id (11-bit).
    pub const ID: u32 = 0x102;
    /// Payload length in bytes.
    pub const DLC: usize = 8;
    /// Send period from `GenMsgCycleTime` (ms).
    pub const CYCLE_TIME_MS: u32 = 1;
    /// E2E profile.
    pub const E2E: E2eProfile = E2eProfile::from_dbc(0x1102, 8, 8);
    /// Smallest allowed `Crc` (crc).
    pub const CRC_MIN: u8 = 0;
    /// Largest allowed `Crc` (crc).
    pub const CRC_MAX: u8 = 255;
    /// Smallest allowed `Counter` (count).
    pub const COUNTER_MIN: u8 = 0;
    /// Largest allowed `Counter` (count).
    pub const COUNTER_MAX: u8 = 255;
    /// Smallest allowed `Emg8` (uV).
    pub const EMG8_MIN: f64 = -5120.0;
    /// Largest allowed `Emg8` (uV).
    pub const EMG8_MAX: f64 = 5117.5;
    /// `Emg8`: uV per raw step.
    pub const EMG8_FACTOR: f64 = 2.5;
    /// `Emg8`: physical value of raw 0 (uV).
    pub const EMG8_OFFSET: f64 = 0.0;
    /// Smallest allowed raw `Emg8` on the bus.
    pub const EMG8_RAW_MIN: i16 = -2048;
    /// Largest allowed raw `Emg8` on the bus.
    pub const EMG8_RAW_MAX: i16 = 2047;
    /// Smallest allowed `Emg9` (uV).
    pub const EMG9_MIN: f64 = -5120.0;
    /// Largest allowed `Emg9` (uV).
    pub const EMG9_MAX: f64 = 5117.5;
    /// `Emg9`: uV per raw step.
    pub const EMG9_FACTOR: f64 = 2.5;
    /// `Emg9`: physical value of raw 0 (uV).
    pub const EMG9_OFFSET: f64 = 0.0;
    /// Smallest allowed raw `Emg9` on the bus.
    pub const EMG9_RAW_MIN: i16 = -2048;
    /// Largest allowed raw `Emg9` on the bus.
    pub const EMG9_RAW_MAX: i16 = 2047;
    /// Smallest allowed `Emg10` (uV).
    pub const EMG10_MIN: f64 = -5120.0;
    /// Largest allowed `Emg10` (uV).
    pub const EMG10_MAX: f64 = 5117.5;
    /// `Emg10`: uV per raw step.
    pub const EMG10_FACTOR: f64 = 2.5;
    /// `Emg10`: physical value of raw 0 (uV).
    pub const EMG10_OFFSET: f64 = 0.0;
    /// Smallest allowed raw `Emg10` on the bus.
    pub const EMG10_RAW_MIN: i16 = -2048;
    /// Largest allowed raw `Emg10` on the bus.
    pub const EMG10_RAW_MAX: i16 = 2047;
    /// Smallest allowed `Emg11` (uV).
    pub const EMG11_MIN: f64 = -5120.0;
    /// Largest allowed `Emg11` (uV).
    pub const EMG11_MAX: f64 = 5117.5;
    /// `Emg11`: uV per raw step.
    pub const EMG11_FACTOR: f64 = 2.5;
    /// `Emg11`: physical value of raw 0 (uV).
    pub const EMG11_OFFSET: f64 = 0.0;
    /// Smallest allowed raw `Emg11` on the bus.
    pub const EMG11_RAW_MIN: i16 = -2048;
    /// Largest allowed raw `Emg11` on the bus.
    pub const EMG11_RAW_MAX: i16 = 2047;

    /// Builds the message from physical values, each checked against hand.dbc. Crc and Counter start at 0: an [`crate::e2e::E2eProtector`] fills them when sending.
    pub fn new(emg8: f64, emg9: f64, emg10: f64, emg11: f64) -> Result<Self, CodecError> {
        let mut msg = Self {
            crc: 0,
            counter: 0,
            emg8: 0,
            emg9: 0,
            emg10: 0,
            emg11: 0,
        };
        msg.set_emg8(emg8)?;
        msg.set_emg9(emg9)?;
        msg.set_emg10(emg10)?;
        msg.set_emg11(emg11)?;
        Ok(msg)
    }

    /// CAN id.
    pub fn id(&self) -> u32 {
        Self::ID
    }

    /// DBC name.
    pub fn name(&self) -> &'static str {
        Self::NAME
    }

    /// E2E profile.
    pub fn e2e(&self) -> E2eProfile {
        Self::E2E
    }

    /// `Crc` (crc): CRC-8 SAE J1850 over data id 0x1102 and bytes 1..7.
    pub fn crc(&self) -> u8 {
        self.crc
    }

    /// Sets `Crc`; refuses values outside [0, 255].
    pub fn set_crc(&mut self, value: u8) -> Result<(), CodecError> {
        self.crc = value;
        Ok(())
    }

    /// `Counter` (count): Sample counter, equal to G0's for the same sample; 8-bit E2E alive counter.
    pub fn counter(&self) -> u8 {
        self.counter
    }

    /// Sets `Counter`; refuses values outside [0, 255].
    pub fn set_counter(&mut self, value: u8) -> Result<(), CodecError> {
        self.counter = value;
        Ok(())
    }

    /// `Emg8` (uV): Channel 8, 2.5 uV per LSB.
    pub fn emg8(&self) -> f64 {
        f64::from(self.emg8) * 2.5
    }

    /// `Emg8` as the raw integer on the bus.
    pub fn emg8_raw(&self) -> i16 {
        self.emg8
    }

    /// Sets `Emg8` from a physical value, rounded to the nearest raw step; refuses non-finite values and values outside [-5120, 5117.5] uV (never wraps or saturates).
    pub fn set_emg8(&mut self, value: f64) -> Result<(), CodecError> {
        let tol = 2.4999999999999998e-6;
        if !value.is_finite() || value < Self::EMG8_MIN - tol || value > Self::EMG8_MAX + tol {
            return Err(CodecError::OutOfRange {
                message: Self::NAME,
                signal: "Emg8",
                value,
                min: Self::EMG8_MIN,
                max: Self::EMG8_MAX,
                unit: "uV",
            });
        }
        let raw = round((value - 0.0) / 2.5) as i64;
        if !(-2048..=2047).contains(&raw) {
            return Err(CodecError::OutOfRange {
                message: Self::NAME,
                signal: "Emg8",
                value,
                min: Self::EMG8_MIN,
                max: Self::EMG8_MAX,
                unit: "uV",
            });
        }
        self.emg8 = raw as i16;
        Ok(())
    }

    /// Sets `Emg8` from a raw value; refuses raw values outside [-2048, 2047].
    pub fn set_emg8_raw(&mut self, raw: i16) -> Result<(), CodecError> {
        if !(-2048..=2047).contains(&raw) {
            return Err(CodecError::RawOutOfRange {
                message: Self::NAME,
                signal: "Emg8",
                raw: i64::from(raw),
                min: -2048,
                max: 2047,
            });
        }
        self.emg8 = raw;
        Ok(())
    }

    /// `Emg9` (uV): Channel 9, 2.5 uV per LSB.
    pub fn emg9(&self) -> f64 {
        f64::from(self.emg9) * 2.5
    }

    /// `Emg9` as the raw integer on the bus.
    pub fn emg9_raw(&self) -> i16 {
        self.emg9
    }

    /// Sets `Emg9` from a physical value, rounded to the nearest raw step; refuses non-finite values and values outside [-5120, 5117.5] uV (never wraps or saturates).
    pub fn set_emg9(&mut self, value: f64) -> Result<(), CodecError> {
        let tol = 2.4999999999999998e-6;
        if !value.is_finite() || value < Self::EMG9_MIN - tol || value > Self::EMG9_MAX + tol {
            return Err(CodecError::OutOfRange {
                message: Self::NAME,
                signal: "Emg9",
                value,
                min: Self::EMG9_MIN,
                max: Self::EMG9_MAX,
                unit: "uV",
            });
        }
        let raw = round((value - 0.0) / 2.5) as i64;
        if !(-2048..=2047).contains(&raw) {
            return Err(CodecError::OutOfRange {
                message: Self::NAME,
                signal: "Emg9",
                value,
                min: Self::EMG9_MIN,
                max: Self::EMG9_MAX,
                unit: "uV",
            });
        }
        self.emg9 = raw as i16;
        Ok(())
    }

    /// Sets `Emg9` from a raw value; refuses raw values outside [-2048, 2047].
    pub fn set_emg9_raw(&mut self, raw: i16) -> Result<(), CodecError> {
        if !(-2048..=2047).contains(&raw) {
            return Err(CodecError::RawOutOfRange {
                message: Self::NAME,
                signal: "Emg9",
                raw: i64::from(raw),
                min: -2048,
                max: 2047,
            });
        }
        self.emg9 = raw;
        Ok(())
    }

    /// `Emg10` (uV): Channel 10, 2.5 uV per LSB.
    pub fn emg10(&self) -> f64 {
        f64::from(self.emg10) * 2.5
    }

    /// `Emg10` as the raw integer on the bus.
    pub fn emg10_raw(&self) -> i16 {
        self.emg10
    }

    /// Sets `Emg10` from a physical value, rounded to the nearest raw step; refuses non-finite values and values outside [-5120, 5117.5] uV (never wraps or saturates).
    pub fn set_emg10(&mut self, value: f64) -> Result<(), CodecError> {
        let tol = 2.4999999999999998e-6;
        if !value.is_finite() || value < Self::EMG10_MIN - tol || value > Self::EMG10_MAX + tol {
            return Err(CodecError::OutOfRange {
                message: Self::NAME,
                signal: "Emg10",
                value,
                min: Self::EMG10_MIN,
                max: Self::EMG10_MAX,
                unit: "uV",
            });
        }
        let raw = round((value - 0.0) / 2.5) as i64;
        if !(-2048..=2047).contains(&raw) {
            return Err(CodecError::OutOfRange {
                message: Self::NAME,
                signal: "Emg10",
                value,
                min: Self::EMG10_MIN,
                max: Self::EMG10_MAX,
                unit: "uV",
            });
        }
        self.emg10 = raw as i16;
        Ok(())
    }

    /// Sets `Emg10` from a raw value; refuses raw values outside [-2048, 2047].
    pub fn set_emg10_raw(&mut self, raw: i16) -> Result<(), CodecError> {
        if !(-2048..=2047).contains(&raw) {
            return Err(CodecError::RawOutOfRange {
                message: Self::NAME,
                signal: "Emg10",
                raw: i64::from(raw),
                min: -2048,
                max: 2047,
            });
        }
        self.emg10 = raw;
        Ok(())
    }

    /// `Emg11` (uV): Channel 11, 2.5 uV per LSB.
    pub fn emg11(&self) -> f64 {
        f64::from(self.emg11) * 2.5
    }

    /// `Emg11` as the raw integer on the bus.
    pub fn emg11_raw(&self) -> i16 {
        self.emg11
    }

    /// Sets `Emg11` from a physical value, rounded to the nearest raw step; refuses non-finite values and values outside [-5120, 5117.5] uV (never wraps or saturates).
    pub fn set_emg11(&mut self, value: f64) -> Result<(), CodecError> {
        let tol = 2.4999999999999998e-6;
        if !value.is_finite() || value < Self::EMG11_MIN - tol || value > Self::EMG11_MAX + tol {
            return Err(CodecError::OutOfRange {
                message: Self::NAME,
                signal: "Emg11",
                value,
                min: Self::EMG11_MIN,
                max: Self::EMG11_MAX,
                unit: "uV",
            });
        }
        let raw = round((value - 0.0) / 2.5) as i64;
        if !(-2048..=2047).contains(&raw) {
            return Err(CodecError::OutOfRange {
                message: Self::NAME,
                signal: "Emg11",
                value,
                min: Self::EMG11_MIN,
                max: Self::EMG11_MAX,
                unit: "uV",
            });
        }
        self.emg11 = raw as i16;
        Ok(())
    }

    /// Sets `Emg11` from a raw value; refuses raw values outside [-2048, 2047].
    pub fn set_emg11_raw(&mut self, raw: i16) -> Result<(), CodecError> {
        if !(-2048..=2047).contains(&raw) {
            return Err(CodecError::RawOutOfRange {
                message: Self::NAME,
                signal: "Emg11",
                raw: i64::from(raw),
                min: -2048,
                max: 2047,
            });
        }
        self.emg11 = raw;
        Ok(())
    }

    /// Decodes a payload; refuses a wrong length, raw values outside the DBC range and values the value tables do not name. The CRC is not checked here: that is [`crate::e2e::E2eChecker`]'s job.
    #[inline]
    pub fn decode(data: &[u8]) -> Result<Self, CodecError> {
        let message = Self::NAME;
        if data.len() != Self::DLC {
            return Err(CodecError::WrongLength {
                message,
                expected: Self::DLC,
                got: data.len(),
            });
        }
        let mut bytes = [0u8; 8];
        bytes[..Self::DLC].copy_from_slice(data);
        let bits = u64::from_le_bytes(bytes);
        let crc = (bits & 0xff) as u8;
        let counter = ((bits >> 8) & 0xff) as u8;
        let emg8 = (((bits << 36) as i64) >> 52) as i16;
        let emg9 = (((bits << 24) as i64) >> 52) as i16;
        let emg10 = (((bits << 12) as i64) >> 52) as i16;
        let emg11 = ((bits as i64) >> 52) as i16;
        Ok(Self {
            crc,
            counter,
            emg8,
            emg9,
            emg10,
            emg11,
        })
    }

    /// The payload bytes (values were range-checked when set, so this cannot fail).
    #[inline]
    pub fn encode(&self) -> [u8; 8] {
        let mut bits = 0u64;
        bits |= u64::from(self.crc) & 0xff;
        bits |= (u64::from(self.counter) & 0xff) << 8;
        bits |= ((i64::from(self.emg8) as u64) & 0xfff) << 16;
        bits |= ((i64::from(self.emg9) as u64) & 0xfff) << 28;
        bits |= ((i64::from(self.emg10) as u64) & 0xfff) << 40;
        bits |= ((i64::from(self.emg11) as u64) & 0xfff) << 52;
        bits.to_le_bytes()
    }

    /// The message as a [`CanFrame`].
    pub fn to_frame(&self) -> CanFrame {
        CanFrame::from_dbc(self.id(), &self.encode())
    }

    /// The message as any [`embedded_can::Frame`] (e.g. a SocketCAN frame).
    pub fn to_can_frame<F: embedded_can::Frame>(&self) -> Result<F, CodecError> {
        to_can_frame(self.id(), &self.encode())
    }

    /// Decodes any [`embedded_can::Frame`]; refuses remote frames, extended ids and other messages' ids.
    pub fn try_from_frame<F: embedded_can::Frame>(frame: &F) -> Result<Self, CodecError> {
        let id = standard_data_frame(frame)?;
        if id != Self::ID {
            return Err(CodecError::WrongId {
                message: Self::NAME,
                id,
            });
        }
        Self::decode(frame.data())
    }

    /// Calls `f` with each signal's DBC name and physical value (enums as their raw value).
    pub fn for_each_signal(&self, f: &mut dyn FnMut(&'static str, f64)) {
        f("Crc", f64::from(self.crc));
        f("Counter", f64::from(self.counter));
        f("Emg8", self.emg8());
        f("Emg9", self.emg9());
        f("Emg10", self.emg10());
        f("Emg11", self.emg11());
    }

    /// Builds the message from physical values looked up by DBC signal name (enums by raw value), each checked; E2E signals included.
    pub fn from_signals(get: &mut dyn FnMut(&str) -> Option<f64>) -> Result<Self, CodecError> {
        let message = Self::NAME;
        let mut msg = Self {
            crc: 0,
            counter: 0,
            emg8: 0,
            emg9: 0,
            emg10: 0,
            emg11: 0,
        };
        let v = get("Crc").ok_or(CodecError::MissingSignal {
            message,
            signal: "Crc",
        })?;
        let raw = whole(message, "Crc", v)?;
        let raw = u8::try_from(raw).map_err(|_| CodecError::RawOutOfRange {
            message,
            signal: "Crc",
            raw,
            min: 0,
            max: 255,
        })?;
        msg.set_crc(raw)?;
        let v = get("Counter").ok_or(CodecError::MissingSignal {
            message,
            signal: "Counter",
        })?;
        let raw = whole(message, "Counter", v)?;
        let raw = u8::try_from(raw).map_err(|_| CodecError::RawOutOfRange {
            message,
            signal: "Counter",
            raw,
            min: 0,
            max: 255,
        })?;
        msg.set_counter(raw)?;
        let v = get("Emg8").ok_or(CodecError::MissingSignal {
            message,
            signal: "Emg8",
        })?;
        msg.set_emg8(v)?;
        let v = get("Emg9").ok_or(CodecError::MissingSignal {
            message,
            signal: "Emg9",
        })?;
        msg.set_emg9(v)?;
        let v = get("Emg10").ok_or(CodecError::MissingSignal {
            message,
            signal: "Emg10",
        })?;
        msg.set_emg10(v)?;
        let v = get("Emg11").ok_or(CodecError::MissingSignal {
            message,
            signal: "Emg11",
        })?;
        msg.set_emg11(v)?;
        Ok(msg)
    }
}

impl crate::e2e::Protected for EmgSamplesG2 {
    fn e2e_profile(&self) -> E2eProfile {
        self.e2e()
    }
    fn to_frame(&self) -> CanFrame {
        EmgSamplesG2::to_frame(self)
    }
}

/// Message EMG_STATUS (id 0x180).
///
/// Amplifier status at 10 Hz.
///
/// DLC 7, every 100 ms, sent by AMP, received by HAND. E2E protected: CRC-8 in byte 0, 4-bit alive counter (data id 0x1180)
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct EmgStatus {
    crc: u8,
    counter: u8,
    state: AmpState,
    sample_rate: AmpSampleRate,
    gain: AmpGain,
    lead_off_mask: u16,
    saturation_mask: u16,
    faults: u8,
}

impl EmgStatus {
    /// Name in hand.dbc.
    pub const NAME: &'static str = "EMG_STATUS";
    /// CAN id (11-bit).
    pub const ID: u32 = 0x180;
    /// Payload length in bytes.
    pub const DLC: usize = 7;
    /// Send period from `GenMsgCycleTime` (ms).
    pub const CYCLE_TIME_MS: u32 = 100;
    /// E2E profile.
    pub const E2E: E2eProfile = E2eProfile::from_dbc(0x1180, 4, 7);
    /// Smallest allowed `Crc` (crc).
    pub const CRC_MIN: u8 = 0;
    /// Largest allowed `Crc` (crc).
    pub const CRC_MAX: u8 = 255;
    /// Smallest allowed `Counter` (count).
    pub const COUNTER_MIN: u8 = 0;
    /// Largest allowed `Counter` (count).
    pub const COUNTER_MAX: u8 = 15;
    /// Smallest allowed `LeadOffMask` (bitmask).
    pub const LEAD_OFF_MASK_MIN: u16 = 0;
    /// Largest allowed `LeadOffMask` (bitmask).
    pub const LEAD_OFF_MASK_MAX: u16 = 4095;
    /// Smallest allowed `SaturationMask` (bitmask).
    pub const SATURATION_MASK_MIN: u16 = 0;
    /// Largest allowed `SaturationMask` (bitmask).
    pub const SATURATION_MASK_MAX: u16 = 4095;
    /// Smallest allowed `Faults` (bitmask).
    pub const FAULTS_MIN: u8 = 0;
    /// Largest allowed `Faults` (bitmask).
    pub const FAULTS_MAX: u8 = 255;

    /// Builds the message from physical values, each checked against hand.dbc. Crc and Counter start at 0: an [`crate::e2e::E2eProtector`] fills them when sending.
    pub fn new(
        state: AmpState,
        sample_rate: AmpSampleRate,
        gain: AmpGain,
        lead_off_mask: u16,
        saturation_mask: u16,
        faults: u8,
    ) -> Result<Self, CodecError> {
        let mut msg = Self {
            crc: 0,
            counter: 0,
            state: AmpState::ALL[0],
            sample_rate: AmpSampleRate::ALL[0],
            gain: AmpGain::ALL[0],
            lead_off_mask: 0,
            saturation_mask: 0,
            faults: 0,
        };
        msg.set_state(state);
        msg.set_sample_rate(sample_rate);
        msg.set_gain(gain);
        msg.set_lead_off_mask(lead_off_mask)?;
        msg.set_saturation_mask(saturation_mask)?;
        msg.set_faults(faults)?;
        Ok(msg)
    }

    /// CAN id.
    pub fn id(&self) -> u32 {
        Self::ID
    }

    /// DBC name.
    pub fn name(&self) -> &'static str {
        Self::NAME
    }

    /// E2E profile.
    pub fn e2e(&self) -> E2eProfile {
        Self::E2E
    }

    /// `Crc` (crc): CRC-8 SAE J1850 over data id 0x1180 and bytes 1..6.
    pub fn crc(&self) -> u8 {
        self.crc
    }

    /// Sets `Crc`; refuses values outside [0, 255].
    pub fn set_crc(&mut self, value: u8) -> Result<(), CodecError> {
        self.crc = value;
        Ok(())
    }

    /// `Counter` (count): 4-bit alive counter.
    pub fn counter(&self) -> u8 {
        self.counter
    }

    /// Sets `Counter`; refuses values outside [0, 15].
    pub fn set_counter(&mut self, value: u8) -> Result<(), CodecError> {
        if value > 15 {
            return Err(CodecError::RawOutOfRange {
                message: Self::NAME,
                signal: "Counter",
                raw: i64::from(value),
                min: 0,
                max: 15,
            });
        }
        self.counter = value;
        Ok(())
    }

    /// `State` (enum): Amplifier state; samples are only meaningful while RUNNING.
    pub fn state(&self) -> AmpState {
        self.state
    }

    /// Sets `State` (every enum value is in range).
    pub fn set_state(&mut self, value: AmpState) {
        self.state = value;
    }

    /// `SampleRate` (enum): Sample rate of EMG_SAMPLES (the default and the decoder's default is 1000 Hz).
    pub fn sample_rate(&self) -> AmpSampleRate {
        self.sample_rate
    }

    /// Sets `SampleRate` (every enum value is in range).
    pub fn set_sample_rate(&mut self, value: AmpSampleRate) {
        self.sample_rate = value;
    }

    /// `Gain` (enum): Programmable gain; the EMG LSB stays 2.5 uV referred to the input whatever the gain.
    pub fn gain(&self) -> AmpGain {
        self.gain
    }

    /// Sets `Gain` (every enum value is in range).
    pub fn set_gain(&mut self, value: AmpGain) {
        self.gain = value;
    }

    /// `LeadOffMask` (bitmask): Bit c set: electrode of channel c is off the skin.
    pub fn lead_off_mask(&self) -> u16 {
        self.lead_off_mask
    }

    /// Sets `LeadOffMask`; refuses values outside [0, 4095].
    pub fn set_lead_off_mask(&mut self, value: u16) -> Result<(), CodecError> {
        if value > 4095 {
            return Err(CodecError::RawOutOfRange {
                message: Self::NAME,
                signal: "LeadOffMask",
                raw: i64::from(value),
                min: 0,
                max: 4095,
            });
        }
        self.lead_off_mask = value;
        Ok(())
    }

    /// `SaturationMask` (bitmask): Bit c set: channel c clipped since the previous status.
    pub fn saturation_mask(&self) -> u16 {
        self.saturation_mask
    }

    /// Sets `SaturationMask`; refuses values outside [0, 4095].
    pub fn set_saturation_mask(&mut self, value: u16) -> Result<(), CodecError> {
        if value > 4095 {
            return Err(CodecError::RawOutOfRange {
                message: Self::NAME,
                signal: "SaturationMask",
                raw: i64::from(value),
                min: 0,
                max: 4095,
            });
        }
        self.saturation_mask = value;
        Ok(())
    }

    /// `Faults` (bitmask): bit 0 ADC, bit 1 supply, bit 2 over-temperature, bit 3 clock, bit 4 transmit overrun (samples dropped in the amplifier).
    pub fn faults(&self) -> u8 {
        self.faults
    }

    /// Sets `Faults`; refuses values outside [0, 255].
    pub fn set_faults(&mut self, value: u8) -> Result<(), CodecError> {
        self.faults = value;
        Ok(())
    }

    /// Decodes a payload; refuses a wrong length, raw values outside the DBC range and values the value tables do not name. The CRC is not checked here: that is [`crate::e2e::E2eChecker`]'s job.
    #[inline]
    pub fn decode(data: &[u8]) -> Result<Self, CodecError> {
        let message = Self::NAME;
        if data.len() != Self::DLC {
            return Err(CodecError::WrongLength {
                message,
                expected: Self::DLC,
                got: data.len(),
            });
        }
        let mut bytes = [0u8; 8];
        bytes[..Self::DLC].copy_from_slice(data);
        let bits = u64::from_le_bytes(bytes);
        let crc = (bits & 0xff) as u8;
        let counter = ((bits >> 8) & 0xf) as u8;
        let state = ((bits >> 12) & 0xf) as u8;
        let Some(state) = AmpState::from_raw(i64::from(state)) else {
            return Err(CodecError::UnknownValue {
                message,
                signal: "State",
                raw: i64::from(state),
            });
        };
        let sample_rate = ((bits >> 16) & 0xf) as u8;
        let Some(sample_rate) = AmpSampleRate::from_raw(i64::from(sample_rate)) else {
            return Err(CodecError::UnknownValue {
                message,
                signal: "SampleRate",
                raw: i64::from(sample_rate),
            });
        };
        let gain = ((bits >> 20) & 0xf) as u8;
        let Some(gain) = AmpGain::from_raw(i64::from(gain)) else {
            return Err(CodecError::UnknownValue {
                message,
                signal: "Gain",
                raw: i64::from(gain),
            });
        };
        let lead_off_mask = ((bits >> 24) & 0xfff) as u16;
        let saturation_mask = ((bits >> 36) & 0xfff) as u16;
        let faults = ((bits >> 48) & 0xff) as u8;
        Ok(Self {
            crc,
            counter,
            state,
            sample_rate,
            gain,
            lead_off_mask,
            saturation_mask,
            faults,
        })
    }

    /// The payload bytes (values were range-checked when set, so this cannot fail).
    #[inline]
    pub fn encode(&self) -> [u8; 7] {
        let mut bits = 0u64;
        bits |= u64::from(self.crc) & 0xff;
        bits |= (u64::from(self.counter) & 0xf) << 8;
        bits |= (u64::from(self.state.raw()) & 0xf) << 12;
        bits |= (u64::from(self.sample_rate.raw()) & 0xf) << 16;
        bits |= (u64::from(self.gain.raw()) & 0xf) << 20;
        bits |= (u64::from(self.lead_off_mask) & 0xfff) << 24;
        bits |= (u64::from(self.saturation_mask) & 0xfff) << 36;
        bits |= (u64::from(self.faults) & 0xff) << 48;
        let mut out = [0u8; 7];
        out.copy_from_slice(&bits.to_le_bytes()[..7]);
        out
    }

    /// The message as a [`CanFrame`].
    pub fn to_frame(&self) -> CanFrame {
        CanFrame::from_dbc(self.id(), &self.encode())
    }

    /// The message as any [`embedded_can::Frame`] (e.g. a SocketCAN frame).
    pub fn to_can_frame<F: embedded_can::Frame>(&self) -> Result<F, CodecError> {
        to_can_frame(self.id(), &self.encode())
    }

    /// Decodes any [`embedded_can::Frame`]; refuses remote frames, extended ids and other messages' ids.
    pub fn try_from_frame<F: embedded_can::Frame>(frame: &F) -> Result<Self, CodecError> {
        let id = standard_data_frame(frame)?;
        if id != Self::ID {
            return Err(CodecError::WrongId {
                message: Self::NAME,
                id,
            });
        }
        Self::decode(frame.data())
    }

    /// Calls `f` with each signal's DBC name and physical value (enums as their raw value).
    pub fn for_each_signal(&self, f: &mut dyn FnMut(&'static str, f64)) {
        f("Crc", f64::from(self.crc));
        f("Counter", f64::from(self.counter));
        f("State", f64::from(self.state.raw()));
        f("SampleRate", f64::from(self.sample_rate.raw()));
        f("Gain", f64::from(self.gain.raw()));
        f("LeadOffMask", f64::from(self.lead_off_mask));
        f("SaturationMask", f64::from(self.saturation_mask));
        f("Faults", f64::from(self.faults));
    }

    /// Builds the message from physical values looked up by DBC signal name (enums by raw value), each checked; E2E signals included.
    pub fn from_signals(get: &mut dyn FnMut(&str) -> Option<f64>) -> Result<Self, CodecError> {
        let message = Self::NAME;
        let mut msg = Self {
            crc: 0,
            counter: 0,
            state: AmpState::ALL[0],
            sample_rate: AmpSampleRate::ALL[0],
            gain: AmpGain::ALL[0],
            lead_off_mask: 0,
            saturation_mask: 0,
            faults: 0,
        };
        let v = get("Crc").ok_or(CodecError::MissingSignal {
            message,
            signal: "Crc",
        })?;
        let raw = whole(message, "Crc", v)?;
        let raw = u8::try_from(raw).map_err(|_| CodecError::RawOutOfRange {
            message,
            signal: "Crc",
            raw,
            min: 0,
            max: 255,
        })?;
        msg.set_crc(raw)?;
        let v = get("Counter").ok_or(CodecError::MissingSignal {
            message,
            signal: "Counter",
        })?;
        let raw = whole(message, "Counter", v)?;
        let raw = u8::try_from(raw).map_err(|_| CodecError::RawOutOfRange {
            message,
            signal: "Counter",
            raw,
            min: 0,
            max: 15,
        })?;
        msg.set_counter(raw)?;
        let v = get("State").ok_or(CodecError::MissingSignal {
            message,
            signal: "State",
        })?;
        let raw = whole(message, "State", v)?;
        msg.state = AmpState::from_raw(raw).ok_or(CodecError::UnknownValue {
            message,
            signal: "State",
            raw,
        })?;
        let v = get("SampleRate").ok_or(CodecError::MissingSignal {
            message,
            signal: "SampleRate",
        })?;
        let raw = whole(message, "SampleRate", v)?;
        msg.sample_rate = AmpSampleRate::from_raw(raw).ok_or(CodecError::UnknownValue {
            message,
            signal: "SampleRate",
            raw,
        })?;
        let v = get("Gain").ok_or(CodecError::MissingSignal {
            message,
            signal: "Gain",
        })?;
        let raw = whole(message, "Gain", v)?;
        msg.gain = AmpGain::from_raw(raw).ok_or(CodecError::UnknownValue {
            message,
            signal: "Gain",
            raw,
        })?;
        let v = get("LeadOffMask").ok_or(CodecError::MissingSignal {
            message,
            signal: "LeadOffMask",
        })?;
        let raw = whole(message, "LeadOffMask", v)?;
        let raw = u16::try_from(raw).map_err(|_| CodecError::RawOutOfRange {
            message,
            signal: "LeadOffMask",
            raw,
            min: 0,
            max: 4095,
        })?;
        msg.set_lead_off_mask(raw)?;
        let v = get("SaturationMask").ok_or(CodecError::MissingSignal {
            message,
            signal: "SaturationMask",
        })?;
        let raw = whole(message, "SaturationMask", v)?;
        let raw = u16::try_from(raw).map_err(|_| CodecError::RawOutOfRange {
            message,
            signal: "SaturationMask",
            raw,
            min: 0,
            max: 4095,
        })?;
        msg.set_saturation_mask(raw)?;
        let v = get("Faults").ok_or(CodecError::MissingSignal {
            message,
            signal: "Faults",
        })?;
        let raw = whole(message, "Faults", v)?;
        let raw = u8::try_from(raw).map_err(|_| CodecError::RawOutOfRange {
            message,
            signal: "Faults",
            raw,
            min: 0,
            max: 255,
        })?;
        msg.set_faults(raw)?;
        Ok(msg)
    }
}

impl crate::e2e::Protected for EmgStatus {
    fn e2e_profile(&self) -> E2eProfile {
        self.e2e()
    }
    fn to_frame(&self) -> CanFrame {
        EmgStatus::to_frame(self)
    }
}

/// Messages FINGER_SETPOINT_0, FINGER_SETPOINT_1, FINGER_SETPOINT_2, FINGER_SETPOINT_3, FINGER_SETPOINT_4 (one per instance, ids 0x200, 0x201, 0x202, 0x203, 0x204), as one type with an instance index.
///
/// Setpoint for finger 0 (thumb), 20 Hz, one per handd tick (50 ms). The motor controller brakes by itself when setpoints stop for 150 ms. No stale setpoint can move a finger: every setpoint carries handd's epoch (signal Epoch), and the controller follows a setpoint only in the epoch it is bound to, which only a SAFE_STOP setpoint opens (rule at signal Epoch; can-dbc/README.md, section The setpoint epoch).
///
/// DLC 8, every 50 ms, sent by HAND, received by MC_0. E2E protected: CRC-8 in byte 0, 4-bit alive counter (data id 0x2200 for instance 0)
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct FingerSetpoint {
    instance: u8,
    crc: u8,
    counter: u8,
    mode: FingerMode,
    force: i16,
    velocity: i16,
    epoch: u16,
}

impl FingerSetpoint {
    /// Number of instances (e.g. one per finger).
    pub const INSTANCES: usize = 5;
    /// Family name in hand.dbc (member names add `_<instance>`).
    pub const NAME: &'static str = "FINGER_SETPOINT";
    /// DBC name of each instance.
    pub const NAMES: [&'static str; 5] = [
        "FINGER_SETPOINT_0",
        "FINGER_SETPOINT_1",
        "FINGER_SETPOINT_2",
        "FINGER_SETPOINT_3",
        "FINGER_SETPOINT_4",
    ];
    /// CAN id of each instance.
    pub const IDS: [u32; 5] = [0x200, 0x201, 0x202, 0x203, 0x204];
    /// Payload length in bytes.
    pub const DLC: usize = 8;
    /// Send period from `GenMsgCycleTime` (ms).
    pub const CYCLE_TIME_MS: u32 = 50;
    /// E2E profile of each instance.
    pub const E2E: [E2eProfile; 5] = [
        E2eProfile::from_dbc(0x2200, 4, 8),
        E2eProfile::from_dbc(0x2201, 4, 8),
        E2eProfile::from_dbc(0x2202, 4, 8),
        E2eProfile::from_dbc(0x2203, 4, 8),
        E2eProfile::from_dbc(0x2204, 4, 8),
    ];
    /// Smallest allowed `Crc` (crc).
    pub const CRC_MIN: u8 = 0;
    /// Largest allowed `Crc` (crc).
    pub const CRC_MAX: u8 = 255;
    /// Smallest allowed `Counter` (count).
    pub const COUNTER_MIN: u8 = 0;
    /// Largest allowed `Counter` (count).
    pub const COUNTER_MAX: u8 = 15;
    /// Smallest allowed `Force` (N).
    pub const FORCE_MIN: f64 = -50.0;
    /// Largest allowed `Force` (N).
    pub const FORCE_MAX: f64 = 50.0;
    /// `Force`: N per raw step.
    pub const FORCE_FACTOR: f64 = 0.01;
    /// `Force`: physical value of raw 0 (N).
    pub const FORCE_OFFSET: f64 = 0.0;
    /// Smallest allowed raw `Force` on the bus.
    pub const FORCE_RAW_MIN: i16 = -5000;
    /// Largest allowed raw `Force` on the bus.
    pub const FORCE_RAW_MAX: i16 = 5000;
    /// Smallest allowed `Velocity` (rad/s).
    pub const VELOCITY_MIN: f64 = -20.0;
    /// Largest allowed `Velocity` (rad/s).
    pub const VELOCITY_MAX: f64 = 20.0;
    /// `Velocity`: rad/s per raw step.
    pub const VELOCITY_FACTOR: f64 = 0.001;
    /// `Velocity`: physical value of raw 0 (rad/s).
    pub const VELOCITY_OFFSET: f64 = 0.0;
    /// Smallest allowed raw `Velocity` on the bus.
    pub const VELOCITY_RAW_MIN: i16 = -20000;
    /// Largest allowed raw `Velocity` on the bus.
    pub const VELOCITY_RAW_MAX: i16 = 20000;
    /// Smallest allowed `Epoch` (epoch).
    pub const EPOCH_MIN: u16 = 0;
    /// Largest allowed `Epoch` (epoch).
    pub const EPOCH_MAX: u16 = 65535;

    /// Builds the message from physical values, each checked against hand.dbc. Crc and Counter start at 0: an [`crate::e2e::E2eProtector`] fills them when sending.
    pub fn new(
        instance: usize,
        mode: FingerMode,
        force: f64,
        velocity: f64,
        epoch: u16,
    ) -> Result<Self, CodecError> {
        if instance >= 5 {
            return Err(CodecError::InstanceOutOfRange {
                message: Self::NAME,
                instance,
                count: 5,
            });
        }
        let mut msg = Self {
            instance: instance as u8,
            crc: 0,
            counter: 0,
            mode: FingerMode::ALL[0],
            force: 0,
            velocity: 0,
            epoch: 0,
        };
        msg.set_mode(mode);
        msg.set_force(force)?;
        msg.set_velocity(velocity)?;
        msg.set_epoch(epoch)?;
        Ok(msg)
    }

    /// Instance index (e.g. the finger).
    pub fn instance(&self) -> usize {
        usize::from(self.instance)
    }

    /// CAN id of this instance.
    pub fn id(&self) -> u32 {
        Self::IDS[usize::from(self.instance)]
    }

    /// DBC name of this instance.
    pub fn name(&self) -> &'static str {
        Self::NAMES[usize::from(self.instance)]
    }

    /// The instance a CAN id belongs to, if any.
    pub fn instance_of(id: u32) -> Option<usize> {
        Self::IDS.iter().position(|&i| i == id)
    }

    /// E2E profile of this instance.
    pub fn e2e(&self) -> E2eProfile {
        Self::E2E[usize::from(self.instance)]
    }

    /// `Crc` (crc)
    pub fn crc(&self) -> u8 {
        self.crc
    }

    /// Sets `Crc`; refuses values outside [0, 255].
    pub fn set_crc(&mut self, value: u8) -> Result<(), CodecError> {
        self.crc = value;
        Ok(())
    }

    /// `Counter` (count)
    pub fn counter(&self) -> u8 {
        self.counter
    }

    /// Sets `Counter`; refuses values outside [0, 15].
    pub fn set_counter(&mut self, value: u8) -> Result<(), CodecError> {
        if value > 15 {
            return Err(CodecError::RawOutOfRange {
                message: Self::NAMES[usize::from(self.instance)],
                signal: "Counter",
                raw: i64::from(value),
                min: 0,
                max: 15,
            });
        }
        self.counter = value;
        Ok(())
    }

    /// `Mode` (enum): DISABLED: motor off, no brake, the finger is free (handd never sends it: every stop of handd's, a finger it lost included, is SAFE_STOP); ACTIVE: follow Force and Velocity (rule at Velocity); HOLD: keep position; SAFE_STOP: zero force, zero velocity, brake. On HAND_ESTOP STOP the controller brakes and retires its epoch: RELEASE does not resume anything, the finger moves again only after a SAFE_STOP of a new epoch (rule at Epoch).
    pub fn mode(&self) -> FingerMode {
        self.mode
    }

    /// Sets `Mode` (every enum value is in range).
    pub fn set_mode(&mut self, value: FingerMode) {
        self.mode = value;
    }

    /// `Force` (N): The most force the finger may push with at the fingertip, flexion positive; its sign must agree with Velocity's for the finger to move (rule at Velocity). handd sends 0 in SAFE_STOP.
    pub fn force(&self) -> f64 {
        f64::from(self.force) * 0.01
    }

    /// `Force` as the raw integer on the bus.
    pub fn force_raw(&self) -> i16 {
        self.force
    }

    /// Sets `Force` from a physical value, rounded to the nearest raw step; refuses non-finite values and values outside [-50, 50] N (never wraps or saturates).
    pub fn set_force(&mut self, value: f64) -> Result<(), CodecError> {
        let tol = 1e-8;
        if !value.is_finite() || value < Self::FORCE_MIN - tol || value > Self::FORCE_MAX + tol {
            return Err(CodecError::OutOfRange {
                message: Self::NAMES[usize::from(self.instance)],
                signal: "Force",
                value,
                min: Self::FORCE_MIN,
                max: Self::FORCE_MAX,
                unit: "N",
            });
        }
        let raw = round((value - 0.0) / 0.01) as i64;
        if !(-5000..=5000).contains(&raw) {
            return Err(CodecError::OutOfRange {
                message: Self::NAMES[usize::from(self.instance)],
                signal: "Force",
                value,
                min: Self::FORCE_MIN,
                max: Self::FORCE_MAX,
                unit: "N",
            });
        }
        self.force = raw as i16;
        Ok(())
    }

    /// Sets `Force` from a raw value; refuses raw values outside [-5000, 5000].
    pub fn set_force_raw(&mut self, raw: i16) -> Result<(), CodecError> {
        if !(-5000..=5000).contains(&raw) {
            return Err(CodecError::RawOutOfRange {
                message: Self::NAMES[usize::from(self.instance)],
                signal: "Force",
                raw: i64::from(raw),
                min: -5000,
                max: 5000,
            });
        }
        self.force = raw;
        Ok(())
    }

    /// `Velocity` (rad/s): Commanded joint velocity, flexion positive. In ACTIVE the controller drives the joint at Velocity, pushing with at most |Force|, when Force and Velocity are both non-zero and of the same sign; when they differ in sign, or either is zero, it holds the finger still (as HOLD). A finger blocked by an object or by its joint stop pushes with at most |Force|. A controller that cannot reach Velocity or |Force| within its own limits saturates and reports it (it never exceeds them).
    pub fn velocity(&self) -> f64 {
        f64::from(self.velocity) * 0.001
    }

    /// `Velocity` as the raw integer on the bus.
    pub fn velocity_raw(&self) -> i16 {
        self.velocity
    }

    /// Sets `Velocity` from a physical value, rounded to the nearest raw step; refuses non-finite values and values outside [-20, 20] rad/s (never wraps or saturates).
    pub fn set_velocity(&mut self, value: f64) -> Result<(), CodecError> {
        let tol = 1e-9;
        if !value.is_finite()
            || value < Self::VELOCITY_MIN - tol
            || value > Self::VELOCITY_MAX + tol
        {
            return Err(CodecError::OutOfRange {
                message: Self::NAMES[usize::from(self.instance)],
                signal: "Velocity",
                value,
                min: Self::VELOCITY_MIN,
                max: Self::VELOCITY_MAX,
                unit: "rad/s",
            });
        }
        let raw = round((value - 0.0) / 0.001) as i64;
        if !(-20000..=20000).contains(&raw) {
            return Err(CodecError::OutOfRange {
                message: Self::NAMES[usize::from(self.instance)],
                signal: "Velocity",
                value,
                min: Self::VELOCITY_MIN,
                max: Self::VELOCITY_MAX,
                unit: "rad/s",
            });
        }
        self.velocity = raw as i16;
        Ok(())
    }

    /// Sets `Velocity` from a raw value; refuses raw values outside [-20000, 20000].
    pub fn set_velocity_raw(&mut self, raw: i16) -> Result<(), CodecError> {
        if !(-20000..=20000).contains(&raw) {
            return Err(CodecError::RawOutOfRange {
                message: Self::NAMES[usize::from(self.instance)],
                signal: "Velocity",
                raw: i64::from(raw),
                min: -20000,
                max: 20000,
            });
        }
        self.velocity = raw;
        Ok(())
    }

    /// `Epoch` (epoch): Setpoint epoch, one per finger. handd draws a fresh, unpredictable epoch for each finger at every start and moves every finger to its next one (+1 modulo 65536) on every bus recovery (reopen after bus-off or link down), every change of state into SAFE and in its last round of safe stops before it exits (so the controller retires the epoch it ran in at once), but only finger f on a report of finger f's controller that it braked by itself (the others keep their epoch and their force); in each of its epochs a finger gets SAFE_STOP before anything else. The controller is bound to at most one epoch and remembers the last one it left (retired). A valid SAFE_STOP of an epoch that is not retired binds the controller to it (retiring the previous one); every other setpoint (ACTIVE, HOLD, DISABLED) is followed only if its epoch is the bound one, and a setpoint of the retired epoch, or of any epoch but the bound one, is ignored and counted. At power-up the controller is bound to none; when it brakes by itself (no valid setpoint for 150 ms) or on HAND_ESTOP STOP it retires its epoch and is bound to none, so it moves again only after a SAFE_STOP of a new epoch. Epochs are compared for equality only, so the counter wraps freely; within one run of handd an epoch repeats only after 65536 changes.
    pub fn epoch(&self) -> u16 {
        self.epoch
    }

    /// Sets `Epoch`; refuses values outside [0, 65535].
    pub fn set_epoch(&mut self, value: u16) -> Result<(), CodecError> {
        self.epoch = value;
        Ok(())
    }

    /// Decodes a payload; refuses a wrong length, raw values outside the DBC range and values the value tables do not name. The CRC is not checked here: that is [`crate::e2e::E2eChecker`]'s job.
    #[inline]
    pub fn decode(id: u32, data: &[u8]) -> Result<Self, CodecError> {
        let Some(instance) = Self::instance_of(id) else {
            return Err(CodecError::WrongId {
                message: Self::NAME,
                id,
            });
        };
        let message = Self::NAMES[instance];
        if data.len() != Self::DLC {
            return Err(CodecError::WrongLength {
                message,
                expected: Self::DLC,
                got: data.len(),
            });
        }
        let mut bytes = [0u8; 8];
        bytes[..Self::DLC].copy_from_slice(data);
        let bits = u64::from_le_bytes(bytes);
        let crc = (bits & 0xff) as u8;
        let counter = ((bits >> 8) & 0xf) as u8;
        let mode = ((bits >> 12) & 0xf) as u8;
        let Some(mode) = FingerMode::from_raw(i64::from(mode)) else {
            return Err(CodecError::UnknownValue {
                message,
                signal: "Mode",
                raw: i64::from(mode),
            });
        };
        let force = (((bits << 32) as i64) >> 48) as i16;
        if !(-5000..=5000).contains(&force) {
            return Err(CodecError::RawOutOfRange {
                message,
                signal: "Force",
                raw: i64::from(force),
                min: -5000,
                max: 5000,
            });
        }
        let velocity = (((bits << 16) as i64) >> 48) as i16;
        if !(-20000..=20000).contains(&velocity) {
            return Err(CodecError::RawOutOfRange {
                message,
                signal: "Velocity",
                raw: i64::from(velocity),
                min: -20000,
                max: 20000,
            });
        }
        let epoch = ((bits >> 48) & 0xffff) as u16;
        Ok(Self {
            instance: instance as u8,
            crc,
            counter,
            mode,
            force,
            velocity,
            epoch,
        })
    }

    /// The payload bytes (values were range-checked when set, so this cannot fail).
    #[inline]
    pub fn encode(&self) -> [u8; 8] {
        let mut bits = 0u64;
        bits |= u64::from(self.crc) & 0xff;
        bits |= (u64::from(self.counter) & 0xf) << 8;
        bits |= (u64::from(self.mode.raw()) & 0xf) << 12;
        bits |= ((i64::from(self.force) as u64) & 0xffff) << 16;
        bits |= ((i64::from(self.velocity) as u64) & 0xffff) << 32;
        bits |= (u64::from(self.epoch) & 0xffff) << 48;
        bits.to_le_bytes()
    }

    /// The message as a [`CanFrame`].
    pub fn to_frame(&self) -> CanFrame {
        CanFrame::from_dbc(self.id(), &self.encode())
    }

    /// The message as any [`embedded_can::Frame`] (e.g. a SocketCAN frame).
    pub fn to_can_frame<F: embedded_can::Frame>(&self) -> Result<F, CodecError> {
        to_can_frame(self.id(), &self.encode())
    }

    /// Decodes any [`embedded_can::Frame`]; refuses remote frames, extended ids and other messages' ids.
    pub fn try_from_frame<F: embedded_can::Frame>(frame: &F) -> Result<Self, CodecError> {
        let id = standard_data_frame(frame)?;
        Self::decode(id, frame.data())
    }

    /// Calls `f` with each signal's DBC name and physical value (enums as their raw value).
    pub fn for_each_signal(&self, f: &mut dyn FnMut(&'static str, f64)) {
        f("Crc", f64::from(self.crc));
        f("Counter", f64::from(self.counter));
        f("Mode", f64::from(self.mode.raw()));
        f("Force", self.force());
        f("Velocity", self.velocity());
        f("Epoch", f64::from(self.epoch));
    }

    /// Builds the message from physical values looked up by DBC signal name (enums by raw value), each checked; E2E signals included.
    pub fn from_signals(
        instance: usize,
        get: &mut dyn FnMut(&str) -> Option<f64>,
    ) -> Result<Self, CodecError> {
        if instance >= 5 {
            return Err(CodecError::InstanceOutOfRange {
                message: Self::NAME,
                instance,
                count: 5,
            });
        }
        let message = Self::NAMES[instance];
        let mut msg = Self {
            instance: instance as u8,
            crc: 0,
            counter: 0,
            mode: FingerMode::ALL[0],
            force: 0,
            velocity: 0,
            epoch: 0,
        };
        let v = get("Crc").ok_or(CodecError::MissingSignal {
            message,
            signal: "Crc",
        })?;
        let raw = whole(message, "Crc", v)?;
        let raw = u8::try_from(raw).map_err(|_| CodecError::RawOutOfRange {
            message,
            signal: "Crc",
            raw,
            min: 0,
            max: 255,
        })?;
        msg.set_crc(raw)?;
        let v = get("Counter").ok_or(CodecError::MissingSignal {
            message,
            signal: "Counter",
        })?;
        let raw = whole(message, "Counter", v)?;
        let raw = u8::try_from(raw).map_err(|_| CodecError::RawOutOfRange {
            message,
            signal: "Counter",
            raw,
            min: 0,
            max: 15,
        })?;
        msg.set_counter(raw)?;
        let v = get("Mode").ok_or(CodecError::MissingSignal {
            message,
            signal: "Mode",
        })?;
        let raw = whole(message, "Mode", v)?;
        msg.mode = FingerMode::from_raw(raw).ok_or(CodecError::UnknownValue {
            message,
            signal: "Mode",
            raw,
        })?;
        let v = get("Force").ok_or(CodecError::MissingSignal {
            message,
            signal: "Force",
        })?;
        msg.set_force(v)?;
        let v = get("Velocity").ok_or(CodecError::MissingSignal {
            message,
            signal: "Velocity",
        })?;
        msg.set_velocity(v)?;
        let v = get("Epoch").ok_or(CodecError::MissingSignal {
            message,
            signal: "Epoch",
        })?;
        let raw = whole(message, "Epoch", v)?;
        let raw = u16::try_from(raw).map_err(|_| CodecError::RawOutOfRange {
            message,
            signal: "Epoch",
            raw,
            min: 0,
            max: 65535,
        })?;
        msg.set_epoch(raw)?;
        Ok(msg)
    }
}

impl crate::e2e::Protected for FingerSetpoint {
    fn e2e_profile(&self) -> E2eProfile {
        self.e2e()
    }
    fn to_frame(&self) -> CanFrame {
        FingerSetpoint::to_frame(self)
    }
}

/// Messages FINGER_STATUS_0, FINGER_STATUS_1, FINGER_STATUS_2, FINGER_STATUS_3, FINGER_STATUS_4 (one per instance, ids 0x280, 0x281, 0x282, 0x283, 0x284), as one type with an instance index.
///
/// Status of finger 0 (thumb), 50 Hz.
///
/// DLC 8, every 20 ms, sent by MC_0, received by HAND. E2E protected: CRC-8 in byte 0, 4-bit alive counter (data id 0x1280 for instance 0)
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct FingerStatus {
    instance: u8,
    crc: u8,
    counter: u8,
    state: FingerState,
    position: u16,
    velocity: i16,
    force: i16,
    faults: u8,
}

impl FingerStatus {
    /// Number of instances (e.g. one per finger).
    pub const INSTANCES: usize = 5;
    /// Family name in hand.dbc (member names add `_<instance>`).
    pub const NAME: &'static str = "FINGER_STATUS";
    /// DBC name of each instance.
    pub const NAMES: [&'static str; 5] = [
        "FINGER_STATUS_0",
        "FINGER_STATUS_1",
        "FINGER_STATUS_2",
        "FINGER_STATUS_3",
        "FINGER_STATUS_4",
    ];
    /// CAN id of each instance.
    pub const IDS: [u32; 5] = [0x280, 0x281, 0x282, 0x283, 0x284];
    /// Payload length in bytes.
    pub const DLC: usize = 8;
    /// Send period from `GenMsgCycleTime` (ms).
    pub const CYCLE_TIME_MS: u32 = 20;
    /// E2E profile of each instance.
    pub const E2E: [E2eProfile; 5] = [
        E2eProfile::from_dbc(0x1280, 4, 8),
        E2eProfile::from_dbc(0x1281, 4, 8),
        E2eProfile::from_dbc(0x1282, 4, 8),
        E2eProfile::from_dbc(0x1283, 4, 8),
        E2eProfile::from_dbc(0x1284, 4, 8),
    ];
    /// Smallest allowed `Crc` (crc).
    pub const CRC_MIN: u8 = 0;
    /// Largest allowed `Crc` (crc).
    pub const CRC_MAX: u8 = 255;
    /// Smallest allowed `Counter` (count).
    pub const COUNTER_MIN: u8 = 0;
    /// Largest allowed `Counter` (count).
    pub const COUNTER_MAX: u8 = 15;
    /// Smallest allowed `Position` (rad).
    pub const POSITION_MIN: f64 = -0.5;
    /// Largest allowed `Position` (rad).
    pub const POSITION_MAX: f64 = 2.0;
    /// `Position`: rad per raw step.
    pub const POSITION_FACTOR: f64 = 0.001;
    /// `Position`: physical value of raw 0 (rad).
    pub const POSITION_OFFSET: f64 = -0.5;
    /// Smallest allowed raw `Position` on the bus.
    pub const POSITION_RAW_MIN: u16 = 0;
    /// Largest allowed raw `Position` on the bus.
    pub const POSITION_RAW_MAX: u16 = 2500;
    /// Smallest allowed `Velocity` (rad/s).
    pub const VELOCITY_MIN: f64 = -20.0;
    /// Largest allowed `Velocity` (rad/s).
    pub const VELOCITY_MAX: f64 = 20.0;
    /// `Velocity`: rad/s per raw step.
    pub const VELOCITY_FACTOR: f64 = 0.01;
    /// `Velocity`: physical value of raw 0 (rad/s).
    pub const VELOCITY_OFFSET: f64 = 0.0;
    /// Smallest allowed raw `Velocity` on the bus.
    pub const VELOCITY_RAW_MIN: i16 = -2000;
    /// Largest allowed raw `Velocity` on the bus.
    pub const VELOCITY_RAW_MAX: i16 = 2000;
    /// Smallest allowed `Force` (N).
    pub const FORCE_MIN: f64 = -50.0;
    /// Largest allowed `Force` (N).
    pub const FORCE_MAX: f64 = 50.0;
    /// `Force`: N per raw step.
    pub const FORCE_FACTOR: f64 = 0.025;
    /// `Force`: physical value of raw 0 (N).
    pub const FORCE_OFFSET: f64 = 0.0;
    /// Smallest allowed raw `Force` on the bus.
    pub const FORCE_RAW_MIN: i16 = -2000;
    /// Largest allowed raw `Force` on the bus.
    pub const FORCE_RAW_MAX: i16 = 2000;
    /// Smallest allowed `Faults` (bitmask).
    pub const FAULTS_MIN: u8 = 0;
    /// Largest allowed `Faults` (bitmask).
    pub const FAULTS_MAX: u8 = 255;

    /// Builds the message from physical values, each checked against hand.dbc. Crc and Counter start at 0: an [`crate::e2e::E2eProtector`] fills them when sending.
    pub fn new(
        instance: usize,
        state: FingerState,
        position: f64,
        velocity: f64,
        force: f64,
        faults: u8,
    ) -> Result<Self, CodecError> {
        if instance >= 5 {
            return Err(CodecError::InstanceOutOfRange {
                message: Self::NAME,
                instance,
                count: 5,
            });
        }
        let mut msg = Self {
            instance: instance as u8,
            crc: 0,
            counter: 0,
            state: FingerState::ALL[0],
            position: 0,
            velocity: 0,
            force: 0,
            faults: 0,
        };
        msg.set_state(state);
        msg.set_position(position)?;
        msg.set_velocity(velocity)?;
        msg.set_force(force)?;
        msg.set_faults(faults)?;
        Ok(msg)
    }

    /// Instance index (e.g. the finger).
    pub fn instance(&self) -> usize {
        usize::from(self.instance)
    }

    /// CAN id of this instance.
    pub fn id(&self) -> u32 {
        Self::IDS[usize::from(self.instance)]
    }

    /// DBC name of this instance.
    pub fn name(&self) -> &'static str {
        Self::NAMES[usize::from(self.instance)]
    }

    /// The instance a CAN id belongs to, if any.
    pub fn instance_of(id: u32) -> Option<usize> {
        Self::IDS.iter().position(|&i| i == id)
    }

    /// E2E profile of this instance.
    pub fn e2e(&self) -> E2eProfile {
        Self::E2E[usize::from(self.instance)]
    }

    /// `Crc` (crc)
    pub fn crc(&self) -> u8 {
        self.crc
    }

    /// Sets `Crc`; refuses values outside [0, 255].
    pub fn set_crc(&mut self, value: u8) -> Result<(), CodecError> {
        self.crc = value;
        Ok(())
    }

    /// `Counter` (count)
    pub fn counter(&self) -> u8 {
        self.counter
    }

    /// Sets `Counter`; refuses values outside [0, 15].
    pub fn set_counter(&mut self, value: u8) -> Result<(), CodecError> {
        if value > 15 {
            return Err(CodecError::RawOutOfRange {
                message: Self::NAMES[usize::from(self.instance)],
                signal: "Counter",
                raw: i64::from(value),
                min: 0,
                max: 15,
            });
        }
        self.counter = value;
        Ok(())
    }

    /// `State` (enum)
    pub fn state(&self) -> FingerState {
        self.state
    }

    /// Sets `State` (every enum value is in range).
    pub fn set_state(&mut self, value: FingerState) {
        self.state = value;
    }

    /// `Position` (rad): Joint angle, 0 = fully extended, flexion positive.
    pub fn position(&self) -> f64 {
        f64::from(self.position) * 0.001 + -0.5
    }

    /// `Position` as the raw integer on the bus.
    pub fn position_raw(&self) -> u16 {
        self.position
    }

    /// Sets `Position` from a physical value, rounded to the nearest raw step; refuses non-finite values and values outside [-0.5, 2] rad (never wraps or saturates).
    pub fn set_position(&mut self, value: f64) -> Result<(), CodecError> {
        let tol = 1e-9;
        if !value.is_finite()
            || value < Self::POSITION_MIN - tol
            || value > Self::POSITION_MAX + tol
        {
            return Err(CodecError::OutOfRange {
                message: Self::NAMES[usize::from(self.instance)],
                signal: "Position",
                value,
                min: Self::POSITION_MIN,
                max: Self::POSITION_MAX,
                unit: "rad",
            });
        }
        let raw = round((value - -0.5) / 0.001) as i64;
        if !(0..=2500).contains(&raw) {
            return Err(CodecError::OutOfRange {
                message: Self::NAMES[usize::from(self.instance)],
                signal: "Position",
                value,
                min: Self::POSITION_MIN,
                max: Self::POSITION_MAX,
                unit: "rad",
            });
        }
        self.position = raw as u16;
        Ok(())
    }

    /// Sets `Position` from a raw value; refuses raw values outside [0, 2500].
    pub fn set_position_raw(&mut self, raw: u16) -> Result<(), CodecError> {
        if raw > 2500 {
            return Err(CodecError::RawOutOfRange {
                message: Self::NAMES[usize::from(self.instance)],
                signal: "Position",
                raw: i64::from(raw),
                min: 0,
                max: 2500,
            });
        }
        self.position = raw;
        Ok(())
    }

    /// `Velocity` (rad/s)
    pub fn velocity(&self) -> f64 {
        f64::from(self.velocity) * 0.01
    }

    /// `Velocity` as the raw integer on the bus.
    pub fn velocity_raw(&self) -> i16 {
        self.velocity
    }

    /// Sets `Velocity` from a physical value, rounded to the nearest raw step; refuses non-finite values and values outside [-20, 20] rad/s (never wraps or saturates).
    pub fn set_velocity(&mut self, value: f64) -> Result<(), CodecError> {
        let tol = 1e-8;
        if !value.is_finite()
            || value < Self::VELOCITY_MIN - tol
            || value > Self::VELOCITY_MAX + tol
        {
            return Err(CodecError::OutOfRange {
                message: Self::NAMES[usize::from(self.instance)],
                signal: "Velocity",
                value,
                min: Self::VELOCITY_MIN,
                max: Self::VELOCITY_MAX,
                unit: "rad/s",
            });
        }
        let raw = round((value - 0.0) / 0.01) as i64;
        if !(-2000..=2000).contains(&raw) {
            return Err(CodecError::OutOfRange {
                message: Self::NAMES[usize::from(self.instance)],
                signal: "Velocity",
                value,
                min: Self::VELOCITY_MIN,
                max: Self::VELOCITY_MAX,
                unit: "rad/s",
            });
        }
        self.velocity = raw as i16;
        Ok(())
    }

    /// Sets `Velocity` from a raw value; refuses raw values outside [-2000, 2000].
    pub fn set_velocity_raw(&mut self, raw: i16) -> Result<(), CodecError> {
        if !(-2000..=2000).contains(&raw) {
            return Err(CodecError::RawOutOfRange {
                message: Self::NAMES[usize::from(self.instance)],
                signal: "Velocity",
                raw: i64::from(raw),
                min: -2000,
                max: 2000,
            });
        }
        self.velocity = raw;
        Ok(())
    }

    /// `Force` (N)
    pub fn force(&self) -> f64 {
        f64::from(self.force) * 0.025
    }

    /// `Force` as the raw integer on the bus.
    pub fn force_raw(&self) -> i16 {
        self.force
    }

    /// Sets `Force` from a physical value, rounded to the nearest raw step; refuses non-finite values and values outside [-50, 50] N (never wraps or saturates).
    pub fn set_force(&mut self, value: f64) -> Result<(), CodecError> {
        let tol = 2.5e-8;
        if !value.is_finite() || value < Self::FORCE_MIN - tol || value > Self::FORCE_MAX + tol {
            return Err(CodecError::OutOfRange {
                message: Self::NAMES[usize::from(self.instance)],
                signal: "Force",
                value,
                min: Self::FORCE_MIN,
                max: Self::FORCE_MAX,
                unit: "N",
            });
        }
        let raw = round((value - 0.0) / 0.025) as i64;
        if !(-2000..=2000).contains(&raw) {
            return Err(CodecError::OutOfRange {
                message: Self::NAMES[usize::from(self.instance)],
                signal: "Force",
                value,
                min: Self::FORCE_MIN,
                max: Self::FORCE_MAX,
                unit: "N",
            });
        }
        self.force = raw as i16;
        Ok(())
    }

    /// Sets `Force` from a raw value; refuses raw values outside [-2000, 2000].
    pub fn set_force_raw(&mut self, raw: i16) -> Result<(), CodecError> {
        if !(-2000..=2000).contains(&raw) {
            return Err(CodecError::RawOutOfRange {
                message: Self::NAMES[usize::from(self.instance)],
                signal: "Force",
                raw: i64::from(raw),
                min: -2000,
                max: 2000,
            });
        }
        self.force = raw;
        Ok(())
    }

    /// `Faults` (bitmask): bit 0 over-current, bit 1 over-temperature, bit 2 encoder, bit 3 setpoint timeout (braked), bit 4 E2E error on setpoints, bit 5 joint limit (at a joint stop with the command pushing into it: handd stops integrating velocity toward that stop), bit 6 setpoint ignored by the epoch rule (a valid setpoint of a stale or not yet opened epoch, see FINGER_SETPOINT Epoch) since the previous status.
    pub fn faults(&self) -> u8 {
        self.faults
    }

    /// Sets `Faults`; refuses values outside [0, 255].
    pub fn set_faults(&mut self, value: u8) -> Result<(), CodecError> {
        self.faults = value;
        Ok(())
    }

    /// Decodes a payload; refuses a wrong length, raw values outside the DBC range and values the value tables do not name. The CRC is not checked here: that is [`crate::e2e::E2eChecker`]'s job.
    #[inline]
    pub fn decode(id: u32, data: &[u8]) -> Result<Self, CodecError> {
        let Some(instance) = Self::instance_of(id) else {
            return Err(CodecError::WrongId {
                message: Self::NAME,
                id,
            });
        };
        let message = Self::NAMES[instance];
        if data.len() != Self::DLC {
            return Err(CodecError::WrongLength {
                message,
                expected: Self::DLC,
                got: data.len(),
            });
        }
        let mut bytes = [0u8; 8];
        bytes[..Self::DLC].copy_from_slice(data);
        let bits = u64::from_le_bytes(bytes);
        let crc = (bits & 0xff) as u8;
        let counter = ((bits >> 8) & 0xf) as u8;
        let state = ((bits >> 12) & 0xf) as u8;
        let Some(state) = FingerState::from_raw(i64::from(state)) else {
            return Err(CodecError::UnknownValue {
                message,
                signal: "State",
                raw: i64::from(state),
            });
        };
        let position = ((bits >> 16) & 0xfff) as u16;
        if position > 2500 {
            return Err(CodecError::RawOutOfRange {
                message,
                signal: "Position",
                raw: i64::from(position),
                min: 0,
                max: 2500,
            });
        }
        let velocity = (((bits << 24) as i64) >> 52) as i16;
        if !(-2000..=2000).contains(&velocity) {
            return Err(CodecError::RawOutOfRange {
                message,
                signal: "Velocity",
                raw: i64::from(velocity),
                min: -2000,
                max: 2000,
            });
        }
        let force = (((bits << 12) as i64) >> 52) as i16;
        if !(-2000..=2000).contains(&force) {
            return Err(CodecError::RawOutOfRange {
                message,
                signal: "Force",
                raw: i64::from(force),
                min: -2000,
                max: 2000,
            });
        }
        let faults = ((bits >> 52) & 0xff) as u8;
        Ok(Self {
            instance: instance as u8,
            crc,
            counter,
            state,
            position,
            velocity,
            force,
            faults,
        })
    }

    /// The payload bytes (values were range-checked when set, so this cannot fail).
    #[inline]
    pub fn encode(&self) -> [u8; 8] {
        let mut bits = 0u64;
        bits |= u64::from(self.crc) & 0xff;
        bits |= (u64::from(self.counter) & 0xf) << 8;
        bits |= (u64::from(self.state.raw()) & 0xf) << 12;
        bits |= (u64::from(self.position) & 0xfff) << 16;
        bits |= ((i64::from(self.velocity) as u64) & 0xfff) << 28;
        bits |= ((i64::from(self.force) as u64) & 0xfff) << 40;
        bits |= (u64::from(self.faults) & 0xff) << 52;
        bits.to_le_bytes()
    }

    /// The message as a [`CanFrame`].
    pub fn to_frame(&self) -> CanFrame {
        CanFrame::from_dbc(self.id(), &self.encode())
    }

    /// The message as any [`embedded_can::Frame`] (e.g. a SocketCAN frame).
    pub fn to_can_frame<F: embedded_can::Frame>(&self) -> Result<F, CodecError> {
        to_can_frame(self.id(), &self.encode())
    }

    /// Decodes any [`embedded_can::Frame`]; refuses remote frames, extended ids and other messages' ids.
    pub fn try_from_frame<F: embedded_can::Frame>(frame: &F) -> Result<Self, CodecError> {
        let id = standard_data_frame(frame)?;
        Self::decode(id, frame.data())
    }

    /// Calls `f` with each signal's DBC name and physical value (enums as their raw value).
    pub fn for_each_signal(&self, f: &mut dyn FnMut(&'static str, f64)) {
        f("Crc", f64::from(self.crc));
        f("Counter", f64::from(self.counter));
        f("State", f64::from(self.state.raw()));
        f("Position", self.position());
        f("Velocity", self.velocity());
        f("Force", self.force());
        f("Faults", f64::from(self.faults));
    }

    /// Builds the message from physical values looked up by DBC signal name (enums by raw value), each checked; E2E signals included.
    pub fn from_signals(
        instance: usize,
        get: &mut dyn FnMut(&str) -> Option<f64>,
    ) -> Result<Self, CodecError> {
        if instance >= 5 {
            return Err(CodecError::InstanceOutOfRange {
                message: Self::NAME,
                instance,
                count: 5,
            });
        }
        let message = Self::NAMES[instance];
        let mut msg = Self {
            instance: instance as u8,
            crc: 0,
            counter: 0,
            state: FingerState::ALL[0],
            position: 0,
            velocity: 0,
            force: 0,
            faults: 0,
        };
        let v = get("Crc").ok_or(CodecError::MissingSignal {
            message,
            signal: "Crc",
        })?;
        let raw = whole(message, "Crc", v)?;
        let raw = u8::try_from(raw).map_err(|_| CodecError::RawOutOfRange {
            message,
            signal: "Crc",
            raw,
            min: 0,
            max: 255,
        })?;
        msg.set_crc(raw)?;
        let v = get("Counter").ok_or(CodecError::MissingSignal {
            message,
            signal: "Counter",
        })?;
        let raw = whole(message, "Counter", v)?;
        let raw = u8::try_from(raw).map_err(|_| CodecError::RawOutOfRange {
            message,
            signal: "Counter",
            raw,
            min: 0,
            max: 15,
        })?;
        msg.set_counter(raw)?;
        let v = get("State").ok_or(CodecError::MissingSignal {
            message,
            signal: "State",
        })?;
        let raw = whole(message, "State", v)?;
        msg.state = FingerState::from_raw(raw).ok_or(CodecError::UnknownValue {
            message,
            signal: "State",
            raw,
        })?;
        let v = get("Position").ok_or(CodecError::MissingSignal {
            message,
            signal: "Position",
        })?;
        msg.set_position(v)?;
        let v = get("Velocity").ok_or(CodecError::MissingSignal {
            message,
            signal: "Velocity",
        })?;
        msg.set_velocity(v)?;
        let v = get("Force").ok_or(CodecError::MissingSignal {
            message,
            signal: "Force",
        })?;
        msg.set_force(v)?;
        let v = get("Faults").ok_or(CodecError::MissingSignal {
            message,
            signal: "Faults",
        })?;
        let raw = whole(message, "Faults", v)?;
        let raw = u8::try_from(raw).map_err(|_| CodecError::RawOutOfRange {
            message,
            signal: "Faults",
            raw,
            min: 0,
            max: 255,
        })?;
        msg.set_faults(raw)?;
        Ok(msg)
    }
}

impl crate::e2e::Protected for FingerStatus {
    fn e2e_profile(&self) -> E2eProfile {
        self.e2e()
    }
    fn to_frame(&self) -> CanFrame {
        FingerStatus::to_frame(self)
    }
}

/// Message HAND_HEARTBEAT (id 0x300).
///
/// handd heartbeat, 10 Hz.
///
/// DLC 8, every 100 ms, sent by HAND, received by AMP, MC_0, MC_1, MC_2, MC_3, MC_4, TOOL. E2E protected: CRC-8 in byte 0, 4-bit alive counter (data id 0x2300)
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct HandHeartbeat {
    crc: u8,
    counter: u8,
    state: DaemonState,
    fault_mask: u16,
    model_id: u32,
}

impl HandHeartbeat {
    /// Name in hand.dbc.
    pub const NAME: &'static str = "HAND_HEARTBEAT";
    /// CAN id (11-bit).
    pub const ID: u32 = 0x300;
    /// Payload length in bytes.
    pub const DLC: usize = 8;
    /// Send period from `GenMsgCycleTime` (ms).
    pub const CYCLE_TIME_MS: u32 = 100;
    /// E2E profile.
    pub const E2E: E2eProfile = E2eProfile::from_dbc(0x2300, 4, 8);
    /// Smallest allowed `Crc` (crc).
    pub const CRC_MIN: u8 = 0;
    /// Largest allowed `Crc` (crc).
    pub const CRC_MAX: u8 = 255;
    /// Smallest allowed `Counter` (count).
    pub const COUNTER_MIN: u8 = 0;
    /// Largest allowed `Counter` (count).
    pub const COUNTER_MAX: u8 = 15;
    /// Smallest allowed `FaultMask` (bitmask).
    pub const FAULT_MASK_MIN: u16 = 0;
    /// Largest allowed `FaultMask` (bitmask).
    pub const FAULT_MASK_MAX: u16 = 65535;
    /// Smallest allowed `ModelId` (id).
    pub const MODEL_ID_MIN: u32 = 0;
    /// Largest allowed `ModelId` (id).
    pub const MODEL_ID_MAX: u32 = 4294967295;

    /// Builds the message from physical values, each checked against hand.dbc. Crc and Counter start at 0: an [`crate::e2e::E2eProtector`] fills them when sending.
    pub fn new(state: DaemonState, fault_mask: u16, model_id: u32) -> Result<Self, CodecError> {
        let mut msg = Self {
            crc: 0,
            counter: 0,
            state: DaemonState::ALL[0],
            fault_mask: 0,
            model_id: 0,
        };
        msg.set_state(state);
        msg.set_fault_mask(fault_mask)?;
        msg.set_model_id(model_id)?;
        Ok(msg)
    }

    /// CAN id.
    pub fn id(&self) -> u32 {
        Self::ID
    }

    /// DBC name.
    pub fn name(&self) -> &'static str {
        Self::NAME
    }

    /// E2E profile.
    pub fn e2e(&self) -> E2eProfile {
        Self::E2E
    }

    /// `Crc` (crc)
    pub fn crc(&self) -> u8 {
        self.crc
    }

    /// Sets `Crc`; refuses values outside [0, 255].
    pub fn set_crc(&mut self, value: u8) -> Result<(), CodecError> {
        self.crc = value;
        Ok(())
    }

    /// `Counter` (count)
    pub fn counter(&self) -> u8 {
        self.counter
    }

    /// Sets `Counter`; refuses values outside [0, 15].
    pub fn set_counter(&mut self, value: u8) -> Result<(), CodecError> {
        if value > 15 {
            return Err(CodecError::RawOutOfRange {
                message: Self::NAME,
                signal: "Counter",
                raw: i64::from(value),
                min: 0,
                max: 15,
            });
        }
        self.counter = value;
        Ok(())
    }

    /// `State` (enum)
    pub fn state(&self) -> DaemonState {
        self.state
    }

    /// Sets `State` (every enum value is in range).
    pub fn set_state(&mut self, value: DaemonState) {
        self.state = value;
    }

    /// `FaultMask` (bitmask): handd's active faults, one bit each, as handctl status names them: bit 0 emg_silence, bit 1 e2e_error, bit 2 invalid_window, bit 3 non_finite, bit 4 signal_quality, bit 5 estop, bit 6 bus_off, bit 7 interface_down, bit 8 repeated_e2e, bit 9 model_error, bit 10 stop_requested, bit 11 calibrating, bit 12 no_model, bit 13 model_swapped, bit 14 second_master, bit 15 bus_degraded; all 16 bits in use. A finger whose controller fell silent is not a daemon fault: FINGER_STATUS and handctl status show it.
    pub fn fault_mask(&self) -> u16 {
        self.fault_mask
    }

    /// Sets `FaultMask`; refuses values outside [0, 65535].
    pub fn set_fault_mask(&mut self, value: u16) -> Result<(), CodecError> {
        self.fault_mask = value;
        Ok(())
    }

    /// `ModelId` (id): Fingerprint of the loaded model file: the 32-bit FNV-1a hash (offset basis 0x811C9DC5, prime 0x01000193) of the whole file's bytes, as handctl status shows it in hex; 0 when no model is loaded.
    pub fn model_id(&self) -> u32 {
        self.model_id
    }

    /// Sets `ModelId`; refuses values outside [0, 4294967295].
    pub fn set_model_id(&mut self, value: u32) -> Result<(), CodecError> {
        self.model_id = value;
        Ok(())
    }

    /// Decodes a payload; refuses a wrong length, raw values outside the DBC range and values the value tables do not name. The CRC is not checked here: that is [`crate::e2e::E2eChecker`]'s job.
    #[inline]
    pub fn decode(data: &[u8]) -> Result<Self, CodecError> {
        let message = Self::NAME;
        if data.len() != Self::DLC {
            return Err(CodecError::WrongLength {
                message,
                expected: Self::DLC,
                got: data.len(),
            });
        }
        let mut bytes = [0u8; 8];
        bytes[..Self::DLC].copy_from_slice(data);
        let bits = u64::from_le_bytes(bytes);
        let crc = (bits & 0xff) as u8;
        let counter = ((bits >> 8) & 0xf) as u8;
        let state = ((bits >> 12) & 0xf) as u8;
        let Some(state) = DaemonState::from_raw(i64::from(state)) else {
            return Err(CodecError::UnknownValue {
                message,
                signal: "State",
                raw: i64::from(state),
            });
        };
        let fault_mask = ((bits >> 16) & 0xffff) as u16;
        let model_id = ((bits >> 32) & 0xffffffff) as u32;
        Ok(Self {
            crc,
            counter,
            state,
            fault_mask,
            model_id,
        })
    }

    /// The payload bytes (values were range-checked when set, so this cannot fail).
    #[inline]
    pub fn encode(&self) -> [u8; 8] {
        let mut bits = 0u64;
        bits |= u64::from(self.crc) & 0xff;
        bits |= (u64::from(self.counter) & 0xf) << 8;
        bits |= (u64::from(self.state.raw()) & 0xf) << 12;
        bits |= (u64::from(self.fault_mask) & 0xffff) << 16;
        bits |= (u64::from(self.model_id) & 0xffffffff) << 32;
        bits.to_le_bytes()
    }

    /// The message as a [`CanFrame`].
    pub fn to_frame(&self) -> CanFrame {
        CanFrame::from_dbc(self.id(), &self.encode())
    }

    /// The message as any [`embedded_can::Frame`] (e.g. a SocketCAN frame).
    pub fn to_can_frame<F: embedded_can::Frame>(&self) -> Result<F, CodecError> {
        to_can_frame(self.id(), &self.encode())
    }

    /// Decodes any [`embedded_can::Frame`]; refuses remote frames, extended ids and other messages' ids.
    pub fn try_from_frame<F: embedded_can::Frame>(frame: &F) -> Result<Self, CodecError> {
        let id = standard_data_frame(frame)?;
        if id != Self::ID {
            return Err(CodecError::WrongId {
                message: Self::NAME,
                id,
            });
        }
        Self::decode(frame.data())
    }

    /// Calls `f` with each signal's DBC name and physical value (enums as their raw value).
    pub fn for_each_signal(&self, f: &mut dyn FnMut(&'static str, f64)) {
        f("Crc", f64::from(self.crc));
        f("Counter", f64::from(self.counter));
        f("State", f64::from(self.state.raw()));
        f("FaultMask", f64::from(self.fault_mask));
        f("ModelId", f64::from(self.model_id));
    }

    /// Builds the message from physical values looked up by DBC signal name (enums by raw value), each checked; E2E signals included.
    pub fn from_signals(get: &mut dyn FnMut(&str) -> Option<f64>) -> Result<Self, CodecError> {
        let message = Self::NAME;
        let mut msg = Self {
            crc: 0,
            counter: 0,
            state: DaemonState::ALL[0],
            fault_mask: 0,
            model_id: 0,
        };
        let v = get("Crc").ok_or(CodecError::MissingSignal {
            message,
            signal: "Crc",
        })?;
        let raw = whole(message, "Crc", v)?;
        let raw = u8::try_from(raw).map_err(|_| CodecError::RawOutOfRange {
            message,
            signal: "Crc",
            raw,
            min: 0,
            max: 255,
        })?;
        msg.set_crc(raw)?;
        let v = get("Counter").ok_or(CodecError::MissingSignal {
            message,
            signal: "Counter",
        })?;
        let raw = whole(message, "Counter", v)?;
        let raw = u8::try_from(raw).map_err(|_| CodecError::RawOutOfRange {
            message,
            signal: "Counter",
            raw,
            min: 0,
            max: 15,
        })?;
        msg.set_counter(raw)?;
        let v = get("State").ok_or(CodecError::MissingSignal {
            message,
            signal: "State",
        })?;
        let raw = whole(message, "State", v)?;
        msg.state = DaemonState::from_raw(raw).ok_or(CodecError::UnknownValue {
            message,
            signal: "State",
            raw,
        })?;
        let v = get("FaultMask").ok_or(CodecError::MissingSignal {
            message,
            signal: "FaultMask",
        })?;
        let raw = whole(message, "FaultMask", v)?;
        let raw = u16::try_from(raw).map_err(|_| CodecError::RawOutOfRange {
            message,
            signal: "FaultMask",
            raw,
            min: 0,
            max: 65535,
        })?;
        msg.set_fault_mask(raw)?;
        let v = get("ModelId").ok_or(CodecError::MissingSignal {
            message,
            signal: "ModelId",
        })?;
        let raw = whole(message, "ModelId", v)?;
        let raw = u32::try_from(raw).map_err(|_| CodecError::RawOutOfRange {
            message,
            signal: "ModelId",
            raw,
            min: 0,
            max: 4294967295,
        })?;
        msg.set_model_id(raw)?;
        Ok(msg)
    }
}

impl crate::e2e::Protected for HandHeartbeat {
    fn e2e_profile(&self) -> E2eProfile {
        self.e2e()
    }
    fn to_frame(&self) -> CanFrame {
        HandHeartbeat::to_frame(self)
    }
}

/// Message HAND_DIAG (id 0x301).
///
/// handd diagnostics for the technician tool, 20 Hz, one per tick. Not safety relevant, so no E2E.
///
/// DLC 8, every 50 ms, sent by HAND, received by TOOL.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct HandDiag {
    tick_latency: u16,
    deadline_misses: u8,
    emg_samples_lost: u8,
    label0: i8,
    label1: i8,
    label2: i8,
    label3: i8,
    label4: i8,
    newest_sample: u8,
}

impl HandDiag {
    /// Name in hand.dbc.
    pub const NAME: &'static str = "HAND_DIAG";
    /// CAN id (11-bit).
    pub const ID: u32 = 0x301;
    /// Payload length in bytes.
    pub const DLC: usize = 8;
    /// Send period from `GenMsgCycleTime` (ms).
    pub const CYCLE_TIME_MS: u32 = 50;
    /// Smallest allowed `TickLatency` (us).
    pub const TICK_LATENCY_MIN: u16 = 0;
    /// Largest allowed `TickLatency` (us).
    pub const TICK_LATENCY_MAX: u16 = 65535;
    /// Smallest allowed `DeadlineMisses` (count).
    pub const DEADLINE_MISSES_MIN: u8 = 0;
    /// Largest allowed `DeadlineMisses` (count).
    pub const DEADLINE_MISSES_MAX: u8 = 255;
    /// Smallest allowed `EmgSamplesLost` (count).
    pub const EMG_SAMPLES_LOST_MIN: u8 = 0;
    /// Largest allowed `EmgSamplesLost` (count).
    pub const EMG_SAMPLES_LOST_MAX: u8 = 255;
    /// Smallest allowed `Label0` (1).
    pub const LABEL0_MIN: f64 = -1.0;
    /// Largest allowed `Label0` (1).
    pub const LABEL0_MAX: f64 = 1.0;
    /// `Label0`: 1 per raw step.
    pub const LABEL0_FACTOR: f64 = 0.05;
    /// `Label0`: physical value of raw 0 (1).
    pub const LABEL0_OFFSET: f64 = 0.0;
    /// Smallest allowed raw `Label0` on the bus.
    pub const LABEL0_RAW_MIN: i8 = -20;
    /// Largest allowed raw `Label0` on the bus.
    pub const LABEL0_RAW_MAX: i8 = 20;
    /// Smallest allowed `Label1` (1).
    pub const LABEL1_MIN: f64 = -1.0;
    /// Largest allowed `Label1` (1).
    pub const LABEL1_MAX: f64 = 1.0;
    /// `Label1`: 1 per raw step.
    pub const LABEL1_FACTOR: f64 = 0.05;
    /// `Label1`: physical value of raw 0 (1).
    pub const LABEL1_OFFSET: f64 = 0.0;
    /// Smallest allowed raw `Label1` on the bus.
    pub const LABEL1_RAW_MIN: i8 = -20;
    /// Largest allowed raw `Label1` on the bus.
    pub const LABEL1_RAW_MAX: i8 = 20;
    /// Smallest allowed `Label2` (1).
    pub const LABEL2_MIN: f64 = -1.0;
    /// Largest allowed `Label2` (1).
    pub const LABEL2_MAX: f64 = 1.0;
    /// `Label2`: 1 per raw step.
    pub const LABEL2_FACTOR: f64 = 0.05;
    /// `Label2`: physical value of raw 0 (1).
    pub const LABEL2_OFFSET: f64 = 0.0;
    /// Smallest allowed raw `Label2` on the bus.
    pub const LABEL2_RAW_MIN: i8 = -20;
    /// Largest allowed raw `Label2` on the bus.
    pub const LABEL2_RAW_MAX: i8 = 20;
    /// Smallest allowed `Label3` (1).
    pub const LABEL3_MIN: f64 = -1.0;
    /// Largest allowed `Label3` (1).
    pub const LABEL3_MAX: f64 = 1.0;
    /// `Label3`: 1 per raw step.
    pub const LABEL3_FACTOR: f64 = 0.05;
    /// `Label3`: physical value of raw 0 (1).
    pub const LABEL3_OFFSET: f64 = 0.0;
    /// Smallest allowed raw `Label3` on the bus.
    pub const LABEL3_RAW_MIN: i8 = -20;
    /// Largest allowed raw `Label3` on the bus.
    pub const LABEL3_RAW_MAX: i8 = 20;
    /// Smallest allowed `Label4` (1).
    pub const LABEL4_MIN: f64 = -1.0;
    /// Largest allowed `Label4` (1).
    pub const LABEL4_MAX: f64 = 1.0;
    /// `Label4`: 1 per raw step.
    pub const LABEL4_FACTOR: f64 = 0.05;
    /// `Label4`: physical value of raw 0 (1).
    pub const LABEL4_OFFSET: f64 = 0.0;
    /// Smallest allowed raw `Label4` on the bus.
    pub const LABEL4_RAW_MIN: i8 = -20;
    /// Largest allowed raw `Label4` on the bus.
    pub const LABEL4_RAW_MAX: i8 = 20;
    /// Smallest allowed `NewestSample` (count).
    pub const NEWEST_SAMPLE_MIN: u8 = 0;
    /// Largest allowed `NewestSample` (count).
    pub const NEWEST_SAMPLE_MAX: u8 = 3;

    /// Builds the message from physical values, each checked against hand.dbc.
    #[allow(clippy::too_many_arguments, reason = "one argument per DBC signal")]
    pub fn new(
        tick_latency: u16,
        deadline_misses: u8,
        emg_samples_lost: u8,
        label0: f64,
        label1: f64,
        label2: f64,
        label3: f64,
        label4: f64,
        newest_sample: u8,
    ) -> Result<Self, CodecError> {
        let mut msg = Self {
            tick_latency: 0,
            deadline_misses: 0,
            emg_samples_lost: 0,
            label0: 0,
            label1: 0,
            label2: 0,
            label3: 0,
            label4: 0,
            newest_sample: 0,
        };
        msg.set_tick_latency(tick_latency)?;
        msg.set_deadline_misses(deadline_misses)?;
        msg.set_emg_samples_lost(emg_samples_lost)?;
        msg.set_label0(label0)?;
        msg.set_label1(label1)?;
        msg.set_label2(label2)?;
        msg.set_label3(label3)?;
        msg.set_label4(label4)?;
        msg.set_newest_sample(newest_sample)?;
        Ok(msg)
    }

    /// CAN id.
    pub fn id(&self) -> u32 {
        Self::ID
    }

    /// DBC name.
    pub fn name(&self) -> &'static str {
        Self::NAME
    }

    /// `TickLatency` (us): Previous tick (this frame is built before its own tick's setpoints are written): receive time of the newest complete EMG sample it had to its setpoints written, us (sender caps at 65535). A replay finds the samples each tick had from it.
    pub fn tick_latency(&self) -> u16 {
        self.tick_latency
    }

    /// Sets `TickLatency`; refuses values outside [0, 65535].
    pub fn set_tick_latency(&mut self, value: u16) -> Result<(), CodecError> {
        self.tick_latency = value;
        Ok(())
    }

    /// `DeadlineMisses` (count): Deadline misses since handd started, modulo 256 (a wrapping total: 255 is followed by 0). A tool takes the difference of two frames modulo 256, which stays right across lost HAND_DIAG frames as long as fewer than 256 misses fall between them; the full count is in handctl status.
    pub fn deadline_misses(&self) -> u8 {
        self.deadline_misses
    }

    /// Sets `DeadlineMisses`; refuses values outside [0, 255].
    pub fn set_deadline_misses(&mut self, value: u8) -> Result<(), CodecError> {
        self.deadline_misses = value;
        Ok(())
    }

    /// `EmgSamplesLost` (count): EMG samples lost (and bridged) since handd started, modulo 256 (a wrapping total, as DeadlineMisses); the full count is in handctl status.
    pub fn emg_samples_lost(&self) -> u8 {
        self.emg_samples_lost
    }

    /// Sets `EmgSamplesLost`; refuses values outside [0, 255].
    pub fn set_emg_samples_lost(&mut self, value: u8) -> Result<(), CodecError> {
        self.emg_samples_lost = value;
        Ok(())
    }

    /// `Label0` (1): Decoded label of finger 0 (thumb), flexion +1, extension -1, for display (0.05 steps).
    pub fn label0(&self) -> f64 {
        f64::from(self.label0) * 0.05
    }

    /// `Label0` as the raw integer on the bus.
    pub fn label0_raw(&self) -> i8 {
        self.label0
    }

    /// Sets `Label0` from a physical value, rounded to the nearest raw step; refuses non-finite values and values outside [-1, 1] 1 (never wraps or saturates).
    pub fn set_label0(&mut self, value: f64) -> Result<(), CodecError> {
        let tol = 5e-8;
        if !value.is_finite() || value < Self::LABEL0_MIN - tol || value > Self::LABEL0_MAX + tol {
            return Err(CodecError::OutOfRange {
                message: Self::NAME,
                signal: "Label0",
                value,
                min: Self::LABEL0_MIN,
                max: Self::LABEL0_MAX,
                unit: "1",
            });
        }
        let raw = round((value - 0.0) / 0.05) as i64;
        if !(-20..=20).contains(&raw) {
            return Err(CodecError::OutOfRange {
                message: Self::NAME,
                signal: "Label0",
                value,
                min: Self::LABEL0_MIN,
                max: Self::LABEL0_MAX,
                unit: "1",
            });
        }
        self.label0 = raw as i8;
        Ok(())
    }

    /// Sets `Label0` from a raw value; refuses raw values outside [-20, 20].
    pub fn set_label0_raw(&mut self, raw: i8) -> Result<(), CodecError> {
        if !(-20..=20).contains(&raw) {
            return Err(CodecError::RawOutOfRange {
                message: Self::NAME,
                signal: "Label0",
                raw: i64::from(raw),
                min: -20,
                max: 20,
            });
        }
        self.label0 = raw;
        Ok(())
    }

    /// `Label1` (1): Decoded label of finger 1 (index).
    pub fn label1(&self) -> f64 {
        f64::from(self.label1) * 0.05
    }

    /// `Label1` as the raw integer on the bus.
    pub fn label1_raw(&self) -> i8 {
        self.label1
    }

    /// Sets `Label1` from a physical value, rounded to the nearest raw step; refuses non-finite values and values outside [-1, 1] 1 (never wraps or saturates).
    pub fn set_label1(&mut self, value: f64) -> Result<(), CodecError> {
        let tol = 5e-8;
        if !value.is_finite() || value < Self::LABEL1_MIN - tol || value > Self::LABEL1_MAX + tol {
            return Err(CodecError::OutOfRange {
                message: Self::NAME,
                signal: "Label1",
                value,
                min: Self::LABEL1_MIN,
                max: Self::LABEL1_MAX,
                unit: "1",
            });
        }
        let raw = round((value - 0.0) / 0.05) as i64;
        if !(-20..=20).contains(&raw) {
            return Err(CodecError::OutOfRange {
                message: Self::NAME,
                signal: "Label1",
                value,
                min: Self::LABEL1_MIN,
                max: Self::LABEL1_MAX,
                unit: "1",
            });
        }
        self.label1 = raw as i8;
        Ok(())
    }

    /// Sets `Label1` from a raw value; refuses raw values outside [-20, 20].
    pub fn set_label1_raw(&mut self, raw: i8) -> Result<(), CodecError> {
        if !(-20..=20).contains(&raw) {
            return Err(CodecError::RawOutOfRange {
                message: Self::NAME,
                signal: "Label1",
                raw: i64::from(raw),
                min: -20,
                max: 20,
            });
        }
        self.label1 = raw;
        Ok(())
    }

    /// `Label2` (1): Decoded label of finger 2 (middle).
    pub fn label2(&self) -> f64 {
        f64::from(self.label2) * 0.05
    }

    /// `Label2` as the raw integer on the bus.
    pub fn label2_raw(&self) -> i8 {
        self.label2
    }

    /// Sets `Label2` from a physical value, rounded to the nearest raw step; refuses non-finite values and values outside [-1, 1] 1 (never wraps or saturates).
    pub fn set_label2(&mut self, value: f64) -> Result<(), CodecError> {
        let tol = 5e-8;
        if !value.is_finite() || value < Self::LABEL2_MIN - tol || value > Self::LABEL2_MAX + tol {
            return Err(CodecError::OutOfRange {
                message: Self::NAME,
                signal: "Label2",
                value,
                min: Self::LABEL2_MIN,
                max: Self::LABEL2_MAX,
                unit: "1",
            });
        }
        let raw = round((value - 0.0) / 0.05) as i64;
        if !(-20..=20).contains(&raw) {
            return Err(CodecError::OutOfRange {
                message: Self::NAME,
                signal: "Label2",
                value,
                min: Self::LABEL2_MIN,
                max: Self::LABEL2_MAX,
                unit: "1",
            });
        }
        self.label2 = raw as i8;
        Ok(())
    }

    /// Sets `Label2` from a raw value; refuses raw values outside [-20, 20].
    pub fn set_label2_raw(&mut self, raw: i8) -> Result<(), CodecError> {
        if !(-20..=20).contains(&raw) {
            return Err(CodecError::RawOutOfRange {
                message: Self::NAME,
                signal: "Label2",
                raw: i64::from(raw),
                min: -20,
                max: 20,
            });
        }
        self.label2 = raw;
        Ok(())
    }

    /// `Label3` (1): Decoded label of finger 3 (ring).
    pub fn label3(&self) -> f64 {
        f64::from(self.label3) * 0.05
    }

    /// `Label3` as the raw integer on the bus.
    pub fn label3_raw(&self) -> i8 {
        self.label3
    }

    /// Sets `Label3` from a physical value, rounded to the nearest raw step; refuses non-finite values and values outside [-1, 1] 1 (never wraps or saturates).
    pub fn set_label3(&mut self, value: f64) -> Result<(), CodecError> {
        let tol = 5e-8;
        if !value.is_finite() || value < Self::LABEL3_MIN - tol || value > Self::LABEL3_MAX + tol {
            return Err(CodecError::OutOfRange {
                message: Self::NAME,
                signal: "Label3",
                value,
                min: Self::LABEL3_MIN,
                max: Self::LABEL3_MAX,
                unit: "1",
            });
        }
        let raw = round((value - 0.0) / 0.05) as i64;
        if !(-20..=20).contains(&raw) {
            return Err(CodecError::OutOfRange {
                message: Self::NAME,
                signal: "Label3",
                value,
                min: Self::LABEL3_MIN,
                max: Self::LABEL3_MAX,
                unit: "1",
            });
        }
        self.label3 = raw as i8;
        Ok(())
    }

    /// Sets `Label3` from a raw value; refuses raw values outside [-20, 20].
    pub fn set_label3_raw(&mut self, raw: i8) -> Result<(), CodecError> {
        if !(-20..=20).contains(&raw) {
            return Err(CodecError::RawOutOfRange {
                message: Self::NAME,
                signal: "Label3",
                raw: i64::from(raw),
                min: -20,
                max: 20,
            });
        }
        self.label3 = raw;
        Ok(())
    }

    /// `Label4` (1): Decoded label of finger 4 (pinky).
    pub fn label4(&self) -> f64 {
        f64::from(self.label4) * 0.05
    }

    /// `Label4` as the raw integer on the bus.
    pub fn label4_raw(&self) -> i8 {
        self.label4
    }

    /// Sets `Label4` from a physical value, rounded to the nearest raw step; refuses non-finite values and values outside [-1, 1] 1 (never wraps or saturates).
    pub fn set_label4(&mut self, value: f64) -> Result<(), CodecError> {
        let tol = 5e-8;
        if !value.is_finite() || value < Self::LABEL4_MIN - tol || value > Self::LABEL4_MAX + tol {
            return Err(CodecError::OutOfRange {
                message: Self::NAME,
                signal: "Label4",
                value,
                min: Self::LABEL4_MIN,
                max: Self::LABEL4_MAX,
                unit: "1",
            });
        }
        let raw = round((value - 0.0) / 0.05) as i64;
        if !(-20..=20).contains(&raw) {
            return Err(CodecError::OutOfRange {
                message: Self::NAME,
                signal: "Label4",
                value,
                min: Self::LABEL4_MIN,
                max: Self::LABEL4_MAX,
                unit: "1",
            });
        }
        self.label4 = raw as i8;
        Ok(())
    }

    /// Sets `Label4` from a raw value; refuses raw values outside [-20, 20].
    pub fn set_label4_raw(&mut self, raw: i8) -> Result<(), CodecError> {
        if !(-20..=20).contains(&raw) {
            return Err(CodecError::RawOutOfRange {
                message: Self::NAME,
                signal: "Label4",
                raw: i64::from(raw),
                min: -20,
                max: 20,
            });
        }
        self.label4 = raw;
        Ok(())
    }

    /// `NewestSample` (count): Previous tick: the EMG sample counter of the newest complete sample it had, modulo 4. With TickLatency it names that sample exactly, so a replay of a bus log knows which samples each tick had.
    pub fn newest_sample(&self) -> u8 {
        self.newest_sample
    }

    /// Sets `NewestSample`; refuses values outside [0, 3].
    pub fn set_newest_sample(&mut self, value: u8) -> Result<(), CodecError> {
        if value > 3 {
            return Err(CodecError::RawOutOfRange {
                message: Self::NAME,
                signal: "NewestSample",
                raw: i64::from(value),
                min: 0,
                max: 3,
            });
        }
        self.newest_sample = value;
        Ok(())
    }

    /// Decodes a payload; refuses a wrong length, raw values outside the DBC range and values the value tables do not name. The CRC is not checked here: that is [`crate::e2e::E2eChecker`]'s job.
    #[inline]
    pub fn decode(data: &[u8]) -> Result<Self, CodecError> {
        let message = Self::NAME;
        if data.len() != Self::DLC {
            return Err(CodecError::WrongLength {
                message,
                expected: Self::DLC,
                got: data.len(),
            });
        }
        let mut bytes = [0u8; 8];
        bytes[..Self::DLC].copy_from_slice(data);
        let bits = u64::from_le_bytes(bytes);
        let tick_latency = (bits & 0xffff) as u16;
        let deadline_misses = ((bits >> 16) & 0xff) as u8;
        let emg_samples_lost = ((bits >> 24) & 0xff) as u8;
        let label0 = (((bits << 26) as i64) >> 58) as i8;
        if !(-20..=20).contains(&label0) {
            return Err(CodecError::RawOutOfRange {
                message,
                signal: "Label0",
                raw: i64::from(label0),
                min: -20,
                max: 20,
            });
        }
        let label1 = (((bits << 20) as i64) >> 58) as i8;
        if !(-20..=20).contains(&label1) {
            return Err(CodecError::RawOutOfRange {
                message,
                signal: "Label1",
                raw: i64::from(label1),
                min: -20,
                max: 20,
            });
        }
        let label2 = (((bits << 14) as i64) >> 58) as i8;
        if !(-20..=20).contains(&label2) {
            return Err(CodecError::RawOutOfRange {
                message,
                signal: "Label2",
                raw: i64::from(label2),
                min: -20,
                max: 20,
            });
        }
        let label3 = (((bits << 8) as i64) >> 58) as i8;
        if !(-20..=20).contains(&label3) {
            return Err(CodecError::RawOutOfRange {
                message,
                signal: "Label3",
                raw: i64::from(label3),
                min: -20,
                max: 20,
            });
        }
        let label4 = (((bits << 2) as i64) >> 58) as i8;
        if !(-20..=20).contains(&label4) {
            return Err(CodecError::RawOutOfRange {
                message,
                signal: "Label4",
                raw: i64::from(label4),
                min: -20,
                max: 20,
            });
        }
        let newest_sample = ((bits >> 62) & 0x3) as u8;
        Ok(Self {
            tick_latency,
            deadline_misses,
            emg_samples_lost,
            label0,
            label1,
            label2,
            label3,
            label4,
            newest_sample,
        })
    }

    /// The payload bytes (values were range-checked when set, so this cannot fail).
    #[inline]
    pub fn encode(&self) -> [u8; 8] {
        let mut bits = 0u64;
        bits |= u64::from(self.tick_latency) & 0xffff;
        bits |= (u64::from(self.deadline_misses) & 0xff) << 16;
        bits |= (u64::from(self.emg_samples_lost) & 0xff) << 24;
        bits |= ((i64::from(self.label0) as u64) & 0x3f) << 32;
        bits |= ((i64::from(self.label1) as u64) & 0x3f) << 38;
        bits |= ((i64::from(self.label2) as u64) & 0x3f) << 44;
        bits |= ((i64::from(self.label3) as u64) & 0x3f) << 50;
        bits |= ((i64::from(self.label4) as u64) & 0x3f) << 56;
        bits |= (u64::from(self.newest_sample) & 0x3) << 62;
        bits.to_le_bytes()
    }

    /// The message as a [`CanFrame`].
    pub fn to_frame(&self) -> CanFrame {
        CanFrame::from_dbc(self.id(), &self.encode())
    }

    /// The message as any [`embedded_can::Frame`] (e.g. a SocketCAN frame).
    pub fn to_can_frame<F: embedded_can::Frame>(&self) -> Result<F, CodecError> {
        to_can_frame(self.id(), &self.encode())
    }

    /// Decodes any [`embedded_can::Frame`]; refuses remote frames, extended ids and other messages' ids.
    pub fn try_from_frame<F: embedded_can::Frame>(frame: &F) -> Result<Self, CodecError> {
        let id = standard_data_frame(frame)?;
        if id != Self::ID {
            return Err(CodecError::WrongId {
                message: Self::NAME,
                id,
            });
        }
        Self::decode(frame.data())
    }

    /// Calls `f` with each signal's DBC name and physical value (enums as their raw value).
    pub fn for_each_signal(&self, f: &mut dyn FnMut(&'static str, f64)) {
        f("TickLatency", f64::from(self.tick_latency));
        f("DeadlineMisses", f64::from(self.deadline_misses));
        f("EmgSamplesLost", f64::from(self.emg_samples_lost));
        f("Label0", self.label0());
        f("Label1", self.label1());
        f("Label2", self.label2());
        f("Label3", self.label3());
        f("Label4", self.label4());
        f("NewestSample", f64::from(self.newest_sample));
    }

    /// Builds the message from physical values looked up by DBC signal name (enums by raw value), each checked; E2E signals included.
    pub fn from_signals(get: &mut dyn FnMut(&str) -> Option<f64>) -> Result<Self, CodecError> {
        let message = Self::NAME;
        let mut msg = Self {
            tick_latency: 0,
            deadline_misses: 0,
            emg_samples_lost: 0,
            label0: 0,
            label1: 0,
            label2: 0,
            label3: 0,
            label4: 0,
            newest_sample: 0,
        };
        let v = get("TickLatency").ok_or(CodecError::MissingSignal {
            message,
            signal: "TickLatency",
        })?;
        let raw = whole(message, "TickLatency", v)?;
        let raw = u16::try_from(raw).map_err(|_| CodecError::RawOutOfRange {
            message,
            signal: "TickLatency",
            raw,
            min: 0,
            max: 65535,
        })?;
        msg.set_tick_latency(raw)?;
        let v = get("DeadlineMisses").ok_or(CodecError::MissingSignal {
            message,
            signal: "DeadlineMisses",
        })?;
        let raw = whole(message, "DeadlineMisses", v)?;
        let raw = u8::try_from(raw).map_err(|_| CodecError::RawOutOfRange {
            message,
            signal: "DeadlineMisses",
            raw,
            min: 0,
            max: 255,
        })?;
        msg.set_deadline_misses(raw)?;
        let v = get("EmgSamplesLost").ok_or(CodecError::MissingSignal {
            message,
            signal: "EmgSamplesLost",
        })?;
        let raw = whole(message, "EmgSamplesLost", v)?;
        let raw = u8::try_from(raw).map_err(|_| CodecError::RawOutOfRange {
            message,
            signal: "EmgSamplesLost",
            raw,
            min: 0,
            max: 255,
        })?;
        msg.set_emg_samples_lost(raw)?;
        let v = get("Label0").ok_or(CodecError::MissingSignal {
            message,
            signal: "Label0",
        })?;
        msg.set_label0(v)?;
        let v = get("Label1").ok_or(CodecError::MissingSignal {
            message,
            signal: "Label1",
        })?;
        msg.set_label1(v)?;
        let v = get("Label2").ok_or(CodecError::MissingSignal {
            message,
            signal: "Label2",
        })?;
        msg.set_label2(v)?;
        let v = get("Label3").ok_or(CodecError::MissingSignal {
            message,
            signal: "Label3",
        })?;
        msg.set_label3(v)?;
        let v = get("Label4").ok_or(CodecError::MissingSignal {
            message,
            signal: "Label4",
        })?;
        msg.set_label4(v)?;
        let v = get("NewestSample").ok_or(CodecError::MissingSignal {
            message,
            signal: "NewestSample",
        })?;
        let raw = whole(message, "NewestSample", v)?;
        let raw = u8::try_from(raw).map_err(|_| CodecError::RawOutOfRange {
            message,
            signal: "NewestSample",
            raw,
            min: 0,
            max: 3,
        })?;
        msg.set_newest_sample(raw)?;
        Ok(msg)
    }
}

/// Message CALIBRATION_CUE (id 0x380).
///
/// Calibration cue from the technician tool (handctl calibrate) to the patient: what to do now. Sent at 10 Hz and at once on every change of phase, only while a calibration runs. A patient-facing display (AMP side) or the simulated patient follows it; handd ignores it. A receiver that sees no valid cue for 1 s takes the calibration as gone and rests.
///
/// DLC 8, every 100 ms, sent by TOOL, received by HAND, AMP. E2E protected: CRC-8 in byte 0, 4-bit alive counter (data id 0x1380)
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct CalibrationCue {
    crc: u8,
    counter: u8,
    phase: CuePhase,
    trial: u8,
    finger: u8,
    kind: CueKind,
    repetition: u8,
    attempt: u8,
    time_left: u16,
    effort: u8,
}

impl CalibrationCue {
    /// Name in hand.dbc.
    pub const NAME: &'static str = "CALIBRATION_CUE";
    /// CAN id (11-bit).
    pub const ID: u32 = 0x380;
    /// Payload length in bytes.
    pub const DLC: usize = 8;
    /// Send period from `GenMsgCycleTime` (ms).
    pub const CYCLE_TIME_MS: u32 = 100;
    /// E2E profile.
    pub const E2E: E2eProfile = E2eProfile::from_dbc(0x1380, 4, 8);
    /// Smallest allowed `Crc` (crc).
    pub const CRC_MIN: u8 = 0;
    /// Largest allowed `Crc` (crc).
    pub const CRC_MAX: u8 = 255;
    /// Smallest allowed `Counter` (count).
    pub const COUNTER_MIN: u8 = 0;
    /// Largest allowed `Counter` (count).
    pub const COUNTER_MAX: u8 = 15;
    /// Smallest allowed `Trial` (index).
    pub const TRIAL_MIN: u8 = 0;
    /// Largest allowed `Trial` (index).
    pub const TRIAL_MAX: u8 = 255;
    /// Smallest allowed `Finger` (finger).
    pub const FINGER_MIN: u8 = 0;
    /// Largest allowed `Finger` (finger).
    pub const FINGER_MAX: u8 = 15;
    /// Smallest allowed `Repetition` (count).
    pub const REPETITION_MIN: u8 = 0;
    /// Largest allowed `Repetition` (count).
    pub const REPETITION_MAX: u8 = 15;
    /// Smallest allowed `Attempt` (count).
    pub const ATTEMPT_MIN: u8 = 0;
    /// Largest allowed `Attempt` (count).
    pub const ATTEMPT_MAX: u8 = 15;
    /// Smallest allowed `TimeLeft` (s).
    pub const TIME_LEFT_MIN: f64 = 0.0;
    /// Largest allowed `TimeLeft` (s).
    pub const TIME_LEFT_MAX: f64 = 655.35;
    /// `TimeLeft`: s per raw step.
    pub const TIME_LEFT_FACTOR: f64 = 0.01;
    /// `TimeLeft`: physical value of raw 0 (s).
    pub const TIME_LEFT_OFFSET: f64 = 0.0;
    /// Smallest allowed raw `TimeLeft` on the bus.
    pub const TIME_LEFT_RAW_MIN: u16 = 0;
    /// Largest allowed raw `TimeLeft` on the bus.
    pub const TIME_LEFT_RAW_MAX: u16 = 65535;
    /// Smallest allowed `Effort` (%).
    pub const EFFORT_MIN: u8 = 0;
    /// Largest allowed `Effort` (%).
    pub const EFFORT_MAX: u8 = 100;

    /// Builds the message from physical values, each checked against hand.dbc. Crc and Counter start at 0: an [`crate::e2e::E2eProtector`] fills them when sending.
    #[allow(clippy::too_many_arguments, reason = "one argument per DBC signal")]
    pub fn new(
        phase: CuePhase,
        trial: u8,
        finger: u8,
        kind: CueKind,
        repetition: u8,
        attempt: u8,
        time_left: f64,
        effort: u8,
    ) -> Result<Self, CodecError> {
        let mut msg = Self {
            crc: 0,
            counter: 0,
            phase: CuePhase::ALL[0],
            trial: 0,
            finger: 0,
            kind: CueKind::ALL[0],
            repetition: 0,
            attempt: 0,
            time_left: 0,
            effort: 0,
        };
        msg.set_phase(phase);
        msg.set_trial(trial)?;
        msg.set_finger(finger)?;
        msg.set_kind(kind);
        msg.set_repetition(repetition)?;
        msg.set_attempt(attempt)?;
        msg.set_time_left(time_left)?;
        msg.set_effort(effort)?;
        Ok(msg)
    }

    /// CAN id.
    pub fn id(&self) -> u32 {
        Self::ID
    }

    /// DBC name.
    pub fn name(&self) -> &'static str {
        Self::NAME
    }

    /// E2E profile.
    pub fn e2e(&self) -> E2eProfile {
        Self::E2E
    }

    /// `Crc` (crc): CRC-8 SAE J1850 over data id 0x1380 and bytes 1..7.
    pub fn crc(&self) -> u8 {
        self.crc
    }

    /// Sets `Crc`; refuses values outside [0, 255].
    pub fn set_crc(&mut self, value: u8) -> Result<(), CodecError> {
        self.crc = value;
        Ok(())
    }

    /// `Counter` (count): 4-bit alive counter.
    pub fn counter(&self) -> u8 {
        self.counter
    }

    /// Sets `Counter`; refuses values outside [0, 15].
    pub fn set_counter(&mut self, value: u8) -> Result<(), CodecError> {
        if value > 15 {
            return Err(CodecError::RawOutOfRange {
                message: Self::NAME,
                signal: "Counter",
                raw: i64::from(value),
                min: 0,
                max: 15,
            });
        }
        self.counter = value;
        Ok(())
    }

    /// `Phase` (enum): IDLE: no trial yet (or between trials); PREPARE: get ready for the trial named, stay at rest; HOLD: contract now as cued and hold; RELAX: let go, back to rest; DONE: the protocol is finished; ABORTED: the calibration was stopped. Every phase but HOLD means rest.
    pub fn phase(&self) -> CuePhase {
        self.phase
    }

    /// Sets `Phase` (every enum value is in range).
    pub fn set_phase(&mut self, value: CuePhase) {
        self.phase = value;
    }

    /// `Trial` (index): Index of the trial in the protocol (0..254); 255 = none (IDLE, DONE, ABORTED).
    pub fn trial(&self) -> u8 {
        self.trial
    }

    /// Sets `Trial`; refuses values outside [0, 255].
    pub fn set_trial(&mut self, value: u8) -> Result<(), CodecError> {
        self.trial = value;
        Ok(())
    }

    /// `Finger` (finger): Cued finger: 0 thumb, 1 index, 2 middle, 3 ring, 4 pinky, 5 the whole hand (all five), 15 none (rest). 6..14 are not used; a receiver takes them as none.
    pub fn finger(&self) -> u8 {
        self.finger
    }

    /// Sets `Finger`; refuses values outside [0, 15].
    pub fn set_finger(&mut self, value: u8) -> Result<(), CodecError> {
        if value > 15 {
            return Err(CodecError::RawOutOfRange {
                message: Self::NAME,
                signal: "Finger",
                raw: i64::from(value),
                min: 0,
                max: 15,
            });
        }
        self.finger = value;
        Ok(())
    }

    /// `Kind` (enum): REST: stay relaxed; FLEXION: maximal flexion of the cued finger(s) (label +1); EXTENSION: maximal extension (label -1).
    pub fn kind(&self) -> CueKind {
        self.kind
    }

    /// Sets `Kind` (every enum value is in range).
    pub fn set_kind(&mut self, value: CueKind) {
        self.kind = value;
    }

    /// `Repetition` (count): Repetition of this trial's movement in the protocol, 0-based.
    pub fn repetition(&self) -> u8 {
        self.repetition
    }

    /// Sets `Repetition`; refuses values outside [0, 15].
    pub fn set_repetition(&mut self, value: u8) -> Result<(), CodecError> {
        if value > 15 {
            return Err(CodecError::RawOutOfRange {
                message: Self::NAME,
                signal: "Repetition",
                raw: i64::from(value),
                min: 0,
                max: 15,
            });
        }
        self.repetition = value;
        Ok(())
    }

    /// `Attempt` (count): Attempt at this trial, 0 = first; a trial repeated after a failed quality check counts up (modulo 16).
    pub fn attempt(&self) -> u8 {
        self.attempt
    }

    /// Sets `Attempt`; refuses values outside [0, 15].
    pub fn set_attempt(&mut self, value: u8) -> Result<(), CodecError> {
        if value > 15 {
            return Err(CodecError::RawOutOfRange {
                message: Self::NAME,
                signal: "Attempt",
                raw: i64::from(value),
                min: 0,
                max: 15,
            });
        }
        self.attempt = value;
        Ok(())
    }

    /// `TimeLeft` (s): Time left in the current phase, 0.01 s per LSB (0..655.35 s).
    pub fn time_left(&self) -> f64 {
        f64::from(self.time_left) * 0.01
    }

    /// `TimeLeft` as the raw integer on the bus.
    pub fn time_left_raw(&self) -> u16 {
        self.time_left
    }

    /// Sets `TimeLeft` from a physical value, rounded to the nearest raw step; refuses non-finite values and values outside [0, 655.35] s (never wraps or saturates).
    pub fn set_time_left(&mut self, value: f64) -> Result<(), CodecError> {
        let tol = 1e-8;
        if !value.is_finite()
            || value < Self::TIME_LEFT_MIN - tol
            || value > Self::TIME_LEFT_MAX + tol
        {
            return Err(CodecError::OutOfRange {
                message: Self::NAME,
                signal: "TimeLeft",
                value,
                min: Self::TIME_LEFT_MIN,
                max: Self::TIME_LEFT_MAX,
                unit: "s",
            });
        }
        let raw = round((value - 0.0) / 0.01) as i64;
        if !(0..=65535).contains(&raw) {
            return Err(CodecError::OutOfRange {
                message: Self::NAME,
                signal: "TimeLeft",
                value,
                min: Self::TIME_LEFT_MIN,
                max: Self::TIME_LEFT_MAX,
                unit: "s",
            });
        }
        self.time_left = raw as u16;
        Ok(())
    }

    /// Sets `TimeLeft` from a raw value; refuses raw values outside [0, 65535].
    pub fn set_time_left_raw(&mut self, raw: u16) -> Result<(), CodecError> {
        self.time_left = raw;
        Ok(())
    }

    /// `Effort` (%): Requested effort in percent of maximal voluntary contraction; 100 for a normal cue.
    pub fn effort(&self) -> u8 {
        self.effort
    }

    /// Sets `Effort`; refuses values outside [0, 100].
    pub fn set_effort(&mut self, value: u8) -> Result<(), CodecError> {
        if value > 100 {
            return Err(CodecError::RawOutOfRange {
                message: Self::NAME,
                signal: "Effort",
                raw: i64::from(value),
                min: 0,
                max: 100,
            });
        }
        self.effort = value;
        Ok(())
    }

    /// Decodes a payload; refuses a wrong length, raw values outside the DBC range and values the value tables do not name. The CRC is not checked here: that is [`crate::e2e::E2eChecker`]'s job.
    #[inline]
    pub fn decode(data: &[u8]) -> Result<Self, CodecError> {
        let message = Self::NAME;
        if data.len() != Self::DLC {
            return Err(CodecError::WrongLength {
                message,
                expected: Self::DLC,
                got: data.len(),
            });
        }
        let mut bytes = [0u8; 8];
        bytes[..Self::DLC].copy_from_slice(data);
        let bits = u64::from_le_bytes(bytes);
        let crc = (bits & 0xff) as u8;
        let counter = ((bits >> 8) & 0xf) as u8;
        let phase = ((bits >> 12) & 0xf) as u8;
        let Some(phase) = CuePhase::from_raw(i64::from(phase)) else {
            return Err(CodecError::UnknownValue {
                message,
                signal: "Phase",
                raw: i64::from(phase),
            });
        };
        let trial = ((bits >> 16) & 0xff) as u8;
        let finger = ((bits >> 24) & 0xf) as u8;
        let kind = ((bits >> 28) & 0xf) as u8;
        let Some(kind) = CueKind::from_raw(i64::from(kind)) else {
            return Err(CodecError::UnknownValue {
                message,
                signal: "Kind",
                raw: i64::from(kind),
            });
        };
        let repetition = ((bits >> 32) & 0xf) as u8;
        let attempt = ((bits >> 36) & 0xf) as u8;
        let time_left = ((bits >> 40) & 0xffff) as u16;
        let effort = ((bits >> 56) & 0xff) as u8;
        if effort > 100 {
            return Err(CodecError::RawOutOfRange {
                message,
                signal: "Effort",
                raw: i64::from(effort),
                min: 0,
                max: 100,
            });
        }
        Ok(Self {
            crc,
            counter,
            phase,
            trial,
            finger,
            kind,
            repetition,
            attempt,
            time_left,
            effort,
        })
    }

    /// The payload bytes (values were range-checked when set, so this cannot fail).
    #[inline]
    pub fn encode(&self) -> [u8; 8] {
        let mut bits = 0u64;
        bits |= u64::from(self.crc) & 0xff;
        bits |= (u64::from(self.counter) & 0xf) << 8;
        bits |= (u64::from(self.phase.raw()) & 0xf) << 12;
        bits |= (u64::from(self.trial) & 0xff) << 16;
        bits |= (u64::from(self.finger) & 0xf) << 24;
        bits |= (u64::from(self.kind.raw()) & 0xf) << 28;
        bits |= (u64::from(self.repetition) & 0xf) << 32;
        bits |= (u64::from(self.attempt) & 0xf) << 36;
        bits |= (u64::from(self.time_left) & 0xffff) << 40;
        bits |= (u64::from(self.effort) & 0xff) << 56;
        bits.to_le_bytes()
    }

    /// The message as a [`CanFrame`].
    pub fn to_frame(&self) -> CanFrame {
        CanFrame::from_dbc(self.id(), &self.encode())
    }

    /// The message as any [`embedded_can::Frame`] (e.g. a SocketCAN frame).
    pub fn to_can_frame<F: embedded_can::Frame>(&self) -> Result<F, CodecError> {
        to_can_frame(self.id(), &self.encode())
    }

    /// Decodes any [`embedded_can::Frame`]; refuses remote frames, extended ids and other messages' ids.
    pub fn try_from_frame<F: embedded_can::Frame>(frame: &F) -> Result<Self, CodecError> {
        let id = standard_data_frame(frame)?;
        if id != Self::ID {
            return Err(CodecError::WrongId {
                message: Self::NAME,
                id,
            });
        }
        Self::decode(frame.data())
    }

    /// Calls `f` with each signal's DBC name and physical value (enums as their raw value).
    pub fn for_each_signal(&self, f: &mut dyn FnMut(&'static str, f64)) {
        f("Crc", f64::from(self.crc));
        f("Counter", f64::from(self.counter));
        f("Phase", f64::from(self.phase.raw()));
        f("Trial", f64::from(self.trial));
        f("Finger", f64::from(self.finger));
        f("Kind", f64::from(self.kind.raw()));
        f("Repetition", f64::from(self.repetition));
        f("Attempt", f64::from(self.attempt));
        f("TimeLeft", self.time_left());
        f("Effort", f64::from(self.effort));
    }

    /// Builds the message from physical values looked up by DBC signal name (enums by raw value), each checked; E2E signals included.
    pub fn from_signals(get: &mut dyn FnMut(&str) -> Option<f64>) -> Result<Self, CodecError> {
        let message = Self::NAME;
        let mut msg = Self {
            crc: 0,
            counter: 0,
            phase: CuePhase::ALL[0],
            trial: 0,
            finger: 0,
            kind: CueKind::ALL[0],
            repetition: 0,
            attempt: 0,
            time_left: 0,
            effort: 0,
        };
        let v = get("Crc").ok_or(CodecError::MissingSignal {
            message,
            signal: "Crc",
        })?;
        let raw = whole(message, "Crc", v)?;
        let raw = u8::try_from(raw).map_err(|_| CodecError::RawOutOfRange {
            message,
            signal: "Crc",
            raw,
            min: 0,
            max: 255,
        })?;
        msg.set_crc(raw)?;
        let v = get("Counter").ok_or(CodecError::MissingSignal {
            message,
            signal: "Counter",
        })?;
        let raw = whole(message, "Counter", v)?;
        let raw = u8::try_from(raw).map_err(|_| CodecError::RawOutOfRange {
            message,
            signal: "Counter",
            raw,
            min: 0,
            max: 15,
        })?;
        msg.set_counter(raw)?;
        let v = get("Phase").ok_or(CodecError::MissingSignal {
            message,
            signal: "Phase",
        })?;
        let raw = whole(message, "Phase", v)?;
        msg.phase = CuePhase::from_raw(raw).ok_or(CodecError::UnknownValue {
            message,
            signal: "Phase",
            raw,
        })?;
        let v = get("Trial").ok_or(CodecError::MissingSignal {
            message,
            signal: "Trial",
        })?;
        let raw = whole(message, "Trial", v)?;
        let raw = u8::try_from(raw).map_err(|_| CodecError::RawOutOfRange {
            message,
            signal: "Trial",
            raw,
            min: 0,
            max: 255,
        })?;
        msg.set_trial(raw)?;
        let v = get("Finger").ok_or(CodecError::MissingSignal {
            message,
            signal: "Finger",
        })?;
        let raw = whole(message, "Finger", v)?;
        let raw = u8::try_from(raw).map_err(|_| CodecError::RawOutOfRange {
            message,
            signal: "Finger",
            raw,
            min: 0,
            max: 15,
        })?;
        msg.set_finger(raw)?;
        let v = get("Kind").ok_or(CodecError::MissingSignal {
            message,
            signal: "Kind",
        })?;
        let raw = whole(message, "Kind", v)?;
        msg.kind = CueKind::from_raw(raw).ok_or(CodecError::UnknownValue {
            message,
            signal: "Kind",
            raw,
        })?;
        let v = get("Repetition").ok_or(CodecError::MissingSignal {
            message,
            signal: "Repetition",
        })?;
        let raw = whole(message, "Repetition", v)?;
        let raw = u8::try_from(raw).map_err(|_| CodecError::RawOutOfRange {
            message,
            signal: "Repetition",
            raw,
            min: 0,
            max: 15,
        })?;
        msg.set_repetition(raw)?;
        let v = get("Attempt").ok_or(CodecError::MissingSignal {
            message,
            signal: "Attempt",
        })?;
        let raw = whole(message, "Attempt", v)?;
        let raw = u8::try_from(raw).map_err(|_| CodecError::RawOutOfRange {
            message,
            signal: "Attempt",
            raw,
            min: 0,
            max: 15,
        })?;
        msg.set_attempt(raw)?;
        let v = get("TimeLeft").ok_or(CodecError::MissingSignal {
            message,
            signal: "TimeLeft",
        })?;
        msg.set_time_left(v)?;
        let v = get("Effort").ok_or(CodecError::MissingSignal {
            message,
            signal: "Effort",
        })?;
        let raw = whole(message, "Effort", v)?;
        let raw = u8::try_from(raw).map_err(|_| CodecError::RawOutOfRange {
            message,
            signal: "Effort",
            raw,
            min: 0,
            max: 100,
        })?;
        msg.set_effort(raw)?;
        Ok(msg)
    }
}

impl crate::e2e::Protected for CalibrationCue {
    fn e2e_profile(&self) -> E2eProfile {
        self.e2e()
    }
    fn to_frame(&self) -> CanFrame {
        CalibrationCue::to_frame(self)
    }
}

/// Any message of hand.dbc, as decoded by [`decode`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Message {
    /// HAND_ESTOP
    HandEstop(HandEstop),
    /// EMG_SAMPLES_G0
    EmgSamplesG0(EmgSamplesG0),
    /// EMG_SAMPLES_G1
    EmgSamplesG1(EmgSamplesG1),
    /// EMG_SAMPLES_G2
    EmgSamplesG2(EmgSamplesG2),
    /// EMG_STATUS
    EmgStatus(EmgStatus),
    /// FINGER_SETPOINT
    FingerSetpoint(FingerSetpoint),
    /// FINGER_STATUS
    FingerStatus(FingerStatus),
    /// HAND_HEARTBEAT
    HandHeartbeat(HandHeartbeat),
    /// HAND_DIAG
    HandDiag(HandDiag),
    /// CALIBRATION_CUE
    CalibrationCue(CalibrationCue),
}

/// Decodes a payload by CAN id into the matching message; refuses unknown ids, wrong lengths, out-of-range raw values and unnamed enum values. Never panics.
pub fn decode(id: u32, data: &[u8]) -> Result<Message, CodecError> {
    match id {
        0x080 => HandEstop::decode(data).map(Message::HandEstop),
        0x100 => EmgSamplesG0::decode(data).map(Message::EmgSamplesG0),
        0x101 => EmgSamplesG1::decode(data).map(Message::EmgSamplesG1),
        0x102 => EmgSamplesG2::decode(data).map(Message::EmgSamplesG2),
        0x180 => EmgStatus::decode(data).map(Message::EmgStatus),
        0x200..=0x204 => FingerSetpoint::decode(id, data).map(Message::FingerSetpoint),
        0x280..=0x284 => FingerStatus::decode(id, data).map(Message::FingerStatus),
        0x300 => HandHeartbeat::decode(data).map(Message::HandHeartbeat),
        0x301 => HandDiag::decode(data).map(Message::HandDiag),
        0x380 => CalibrationCue::decode(data).map(Message::CalibrationCue),
        _ => Err(CodecError::UnknownId { id }),
    }
}

/// Decodes any [`embedded_can::Frame`]; refuses remote frames and extended ids.
pub fn decode_frame<F: embedded_can::Frame>(frame: &F) -> Result<Message, CodecError> {
    let id = standard_data_frame(frame)?;
    decode(id, frame.data())
}

/// Builds a message from physical values looked up by DBC signal name (see each type's `from_signals`).
pub fn from_signals(
    id: u32,
    get: &mut dyn FnMut(&str) -> Option<f64>,
) -> Result<Message, CodecError> {
    match id {
        0x080 => HandEstop::from_signals(get).map(Message::HandEstop),
        0x100 => EmgSamplesG0::from_signals(get).map(Message::EmgSamplesG0),
        0x101 => EmgSamplesG1::from_signals(get).map(Message::EmgSamplesG1),
        0x102 => EmgSamplesG2::from_signals(get).map(Message::EmgSamplesG2),
        0x180 => EmgStatus::from_signals(get).map(Message::EmgStatus),
        0x200..=0x204 => {
            FingerSetpoint::from_signals(FingerSetpoint::instance_of(id).unwrap_or(usize::MAX), get)
                .map(Message::FingerSetpoint)
        }
        0x280..=0x284 => {
            FingerStatus::from_signals(FingerStatus::instance_of(id).unwrap_or(usize::MAX), get)
                .map(Message::FingerStatus)
        }
        0x300 => HandHeartbeat::from_signals(get).map(Message::HandHeartbeat),
        0x301 => HandDiag::from_signals(get).map(Message::HandDiag),
        0x380 => CalibrationCue::from_signals(get).map(Message::CalibrationCue),
        _ => Err(CodecError::UnknownId { id }),
    }
}

impl Message {
    /// CAN id.
    pub fn id(&self) -> u32 {
        match self {
            Message::HandEstop(m) => m.id(),
            Message::EmgSamplesG0(m) => m.id(),
            Message::EmgSamplesG1(m) => m.id(),
            Message::EmgSamplesG2(m) => m.id(),
            Message::EmgStatus(m) => m.id(),
            Message::FingerSetpoint(m) => m.id(),
            Message::FingerStatus(m) => m.id(),
            Message::HandHeartbeat(m) => m.id(),
            Message::HandDiag(m) => m.id(),
            Message::CalibrationCue(m) => m.id(),
        }
    }

    /// DBC message name.
    pub fn name(&self) -> &'static str {
        match self {
            Message::HandEstop(m) => m.name(),
            Message::EmgSamplesG0(m) => m.name(),
            Message::EmgSamplesG1(m) => m.name(),
            Message::EmgSamplesG2(m) => m.name(),
            Message::EmgStatus(m) => m.name(),
            Message::FingerSetpoint(m) => m.name(),
            Message::FingerStatus(m) => m.name(),
            Message::HandHeartbeat(m) => m.name(),
            Message::HandDiag(m) => m.name(),
            Message::CalibrationCue(m) => m.name(),
        }
    }

    /// The message as a [`CanFrame`].
    pub fn to_frame(&self) -> CanFrame {
        match self {
            Message::HandEstop(m) => m.to_frame(),
            Message::EmgSamplesG0(m) => m.to_frame(),
            Message::EmgSamplesG1(m) => m.to_frame(),
            Message::EmgSamplesG2(m) => m.to_frame(),
            Message::EmgStatus(m) => m.to_frame(),
            Message::FingerSetpoint(m) => m.to_frame(),
            Message::FingerStatus(m) => m.to_frame(),
            Message::HandHeartbeat(m) => m.to_frame(),
            Message::HandDiag(m) => m.to_frame(),
            Message::CalibrationCue(m) => m.to_frame(),
        }
    }

    /// Calls `f` with each signal's DBC name and physical value.
    pub fn for_each_signal(&self, f: &mut dyn FnMut(&'static str, f64)) {
        match self {
            Message::HandEstop(m) => m.for_each_signal(f),
            Message::EmgSamplesG0(m) => m.for_each_signal(f),
            Message::EmgSamplesG1(m) => m.for_each_signal(f),
            Message::EmgSamplesG2(m) => m.for_each_signal(f),
            Message::EmgStatus(m) => m.for_each_signal(f),
            Message::FingerSetpoint(m) => m.for_each_signal(f),
            Message::FingerStatus(m) => m.for_each_signal(f),
            Message::HandHeartbeat(m) => m.for_each_signal(f),
            Message::HandDiag(m) => m.for_each_signal(f),
            Message::CalibrationCue(m) => m.for_each_signal(f),
        }
    }

    /// E2E profile, `None` for unprotected messages.
    pub fn e2e(&self) -> Option<E2eProfile> {
        match self {
            Message::HandEstop(m) => Some(m.e2e()),
            Message::EmgSamplesG0(m) => Some(m.e2e()),
            Message::EmgSamplesG1(m) => Some(m.e2e()),
            Message::EmgSamplesG2(m) => Some(m.e2e()),
            Message::EmgStatus(m) => Some(m.e2e()),
            Message::FingerSetpoint(m) => Some(m.e2e()),
            Message::FingerStatus(m) => Some(m.e2e()),
            Message::HandHeartbeat(m) => Some(m.e2e()),
            Message::HandDiag(_) => None,
            Message::CalibrationCue(m) => Some(m.e2e()),
        }
    }
}

/// Every message of hand.dbc in file order, with its signals: the DBC as data (bus load, tools, cross-checks).
pub const MESSAGES: &[MessageInfo] = &[
    MessageInfo {
        name: "HAND_ESTOP",
        id: 0x080,
        dlc: 3,
        cycle_time_ms: 10,
        senders: &["HAND", "AMP", "MC_0", "MC_1", "MC_2", "MC_3", "MC_4", "TOOL"],
        receivers: &["HAND", "AMP", "MC_0", "MC_1", "MC_2", "MC_3", "MC_4", "TOOL"],
        e2e: Some(E2eProfile::from_dbc(0x1080, 4, 3)),
        comment: "Emergency stop. Any node may send it (see BO_TX_BU_); it is event-driven but repeated every 10 ms while a stop is asserted, and the bus-load sum counts it at that rate as the worst case. Several senders interleave their alive counters, so receivers latch a stop on any frame whose CRC is valid; the counter only classifies repetitions. Highest priority id on the bus.",
        signals: &[
            SignalInfo { name: "Crc", start_bit: 0, size: 8, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 255.0, raw_min: 0, raw_max: 255, unit: "crc", values: &[], comment: "CRC-8 SAE J1850 over data id 0x1080 and bytes 1..2." },
            SignalInfo { name: "Counter", start_bit: 8, size: 4, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 15.0, raw_min: 0, raw_max: 15, unit: "count", values: &[], comment: "4-bit alive counter of the sender." },
            SignalInfo { name: "Request", start_bit: 12, size: 2, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 1.0, raw_min: 0, raw_max: 1, unit: "enum", values: &[(0, "RELEASE"), (1, "STOP")], comment: "STOP latches the stop in every receiver; RELEASE is only a request: handd leaves SAFE only on an explicit handctl arm." },
            SignalInfo { name: "Source", start_bit: 16, size: 4, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 8.0, raw_min: 0, raw_max: 8, unit: "enum", values: &[(0, "HAND"), (1, "AMP"), (2, "MC_0"), (3, "MC_1"), (4, "MC_2"), (5, "MC_3"), (6, "MC_4"), (7, "TOOL"), (8, "USER_BUTTON")], comment: "Node that raised the stop." },
            SignalInfo { name: "Reason", start_bit: 20, size: 4, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 4.0, raw_min: 0, raw_max: 4, unit: "enum", values: &[(0, "USER"), (1, "TECHNICIAN"), (2, "FAULT"), (3, "WATCHDOG"), (4, "COMM_LOSS")], comment: "Why the stop was raised." },
        ],
    },
    MessageInfo {
        name: "EMG_SAMPLES_G0",
        id: 0x100,
        dlc: 8,
        cycle_time_ms: 1,
        senders: &["AMP"],
        receivers: &["HAND"],
        e2e: Some(E2eProfile::from_dbc(0x1100, 8, 8)),
        comment: "sEMG channels 0..3 of one sample. 12 channels at 1 kHz are split into three groups of four 12-bit samples (G0..G2 on consecutive ids), each frame carrying the sample counter and a CRC: 3 frames per sample keep every frame self-contained (a lost frame loses 4 channels of one sample, never misaligns the rest). The group is given by the CAN id, so no group signal is needed.",
        signals: &[
            SignalInfo { name: "Crc", start_bit: 0, size: 8, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 255.0, raw_min: 0, raw_max: 255, unit: "crc", values: &[], comment: "CRC-8 SAE J1850 over data id 0x1100 and bytes 1..7." },
            SignalInfo { name: "Counter", start_bit: 8, size: 8, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 255.0, raw_min: 0, raw_max: 255, unit: "count", values: &[], comment: "Sample counter, the same in G0, G1 and G2 for one sample instant; it doubles as the 8-bit E2E alive counter. Wraps every 256 samples (256 ms), far beyond the 20 ms gap after which a window is invalid." },
            SignalInfo { name: "Emg0", start_bit: 16, size: 12, signed: true, factor: 2.5, offset: 0.0, min: -5120.0, max: 5117.5, raw_min: -2048, raw_max: 2047, unit: "uV", values: &[], comment: "Channel 0, referred to the electrode input: 2.5 uV per LSB, signed 12 bit, +-5.12 mV full scale." },
            SignalInfo { name: "Emg1", start_bit: 28, size: 12, signed: true, factor: 2.5, offset: 0.0, min: -5120.0, max: 5117.5, raw_min: -2048, raw_max: 2047, unit: "uV", values: &[], comment: "Channel 1, 2.5 uV per LSB." },
            SignalInfo { name: "Emg2", start_bit: 40, size: 12, signed: true, factor: 2.5, offset: 0.0, min: -5120.0, max: 5117.5, raw_min: -2048, raw_max: 2047, unit: "uV", values: &[], comment: "Channel 2, 2.5 uV per LSB." },
            SignalInfo { name: "Emg3", start_bit: 52, size: 12, signed: true, factor: 2.5, offset: 0.0, min: -5120.0, max: 5117.5, raw_min: -2048, raw_max: 2047, unit: "uV", values: &[], comment: "Channel 3, 2.5 uV per LSB." },
        ],
    },
    MessageInfo {
        name: "EMG_SAMPLES_G1",
        id: 0x101,
        dlc: 8,
        cycle_time_ms: 1,
        senders: &["AMP"],
        receivers: &["HAND"],
        e2e: Some(E2eProfile::from_dbc(0x1101, 8, 8)),
        comment: "sEMG channels 4..7 of one sample (see EMG_SAMPLES_G0).",
        signals: &[
            SignalInfo { name: "Crc", start_bit: 0, size: 8, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 255.0, raw_min: 0, raw_max: 255, unit: "crc", values: &[], comment: "CRC-8 SAE J1850 over data id 0x1101 and bytes 1..7." },
            SignalInfo { name: "Counter", start_bit: 8, size: 8, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 255.0, raw_min: 0, raw_max: 255, unit: "count", values: &[], comment: "Sample counter, equal to G0's for the same sample; 8-bit E2E alive counter." },
            SignalInfo { name: "Emg4", start_bit: 16, size: 12, signed: true, factor: 2.5, offset: 0.0, min: -5120.0, max: 5117.5, raw_min: -2048, raw_max: 2047, unit: "uV", values: &[], comment: "Channel 4, 2.5 uV per LSB." },
            SignalInfo { name: "Emg5", start_bit: 28, size: 12, signed: true, factor: 2.5, offset: 0.0, min: -5120.0, max: 5117.5, raw_min: -2048, raw_max: 2047, unit: "uV", values: &[], comment: "Channel 5, 2.5 uV per LSB." },
            SignalInfo { name: "Emg6", start_bit: 40, size: 12, signed: true, factor: 2.5, offset: 0.0, min: -5120.0, max: 5117.5, raw_min: -2048, raw_max: 2047, unit: "uV", values: &[], comment: "Channel 6, 2.5 uV per LSB." },
            SignalInfo { name: "Emg7", start_bit: 52, size: 12, signed: true, factor: 2.5, offset: 0.0, min: -5120.0, max: 5117.5, raw_min: -2048, raw_max: 2047, unit: "uV", values: &[], comment: "Channel 7, 2.5 uV per LSB." },
        ],
    },
    MessageInfo {
        name: "EMG_SAMPLES_G2",
        id: 0x102,
        dlc: 8,
        cycle_time_ms: 1,
        senders: &["AMP"],
        receivers: &["HAND"],
        e2e: Some(E2eProfile::from_dbc(0x1102, 8, 8)),
        comment: "sEMG channels 8..11 of one sample (see EMG_SAMPLES_G0).",
        signals: &[
            SignalInfo { name: "Crc", start_bit: 0, size: 8, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 255.0, raw_min: 0, raw_max: 255, unit: "crc", values: &[], comment: "CRC-8 SAE J1850 over data id 0x1102 and bytes 1..7." },
            SignalInfo { name: "Counter", start_bit: 8, size: 8, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 255.0, raw_min: 0, raw_max: 255, unit: "count", values: &[], comment: "Sample counter, equal to G0's for the same sample; 8-bit E2E alive counter." },
            SignalInfo { name: "Emg8", start_bit: 16, size: 12, signed: true, factor: 2.5, offset: 0.0, min: -5120.0, max: 5117.5, raw_min: -2048, raw_max: 2047, unit: "uV", values: &[], comment: "Channel 8, 2.5 uV per LSB." },
            SignalInfo { name: "Emg9", start_bit: 28, size: 12, signed: true, factor: 2.5, offset: 0.0, min: -5120.0, max: 5117.5, raw_min: -2048, raw_max: 2047, unit: "uV", values: &[], comment: "Channel 9, 2.5 uV per LSB." },
            SignalInfo { name: "Emg10", start_bit: 40, size: 12, signed: true, factor: 2.5, offset: 0.0, min: -5120.0, max: 5117.5, raw_min: -2048, raw_max: 2047, unit: "uV", values: &[], comment: "Channel 10, 2.5 uV per LSB." },
            SignalInfo { name: "Emg11", start_bit: 52, size: 12, signed: true, factor: 2.5, offset: 0.0, min: -5120.0, max: 5117.5, raw_min: -2048, raw_max: 2047, unit: "uV", values: &[], comment: "Channel 11, 2.5 uV per LSB." },
        ],
    },
    MessageInfo {
        name: "EMG_STATUS",
        id: 0x180,
        dlc: 7,
        cycle_time_ms: 100,
        senders: &["AMP"],
        receivers: &["HAND"],
        e2e: Some(E2eProfile::from_dbc(0x1180, 4, 7)),
        comment: "Amplifier status at 10 Hz.",
        signals: &[
            SignalInfo { name: "Crc", start_bit: 0, size: 8, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 255.0, raw_min: 0, raw_max: 255, unit: "crc", values: &[], comment: "CRC-8 SAE J1850 over data id 0x1180 and bytes 1..6." },
            SignalInfo { name: "Counter", start_bit: 8, size: 4, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 15.0, raw_min: 0, raw_max: 15, unit: "count", values: &[], comment: "4-bit alive counter." },
            SignalInfo { name: "State", start_bit: 12, size: 4, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 3.0, raw_min: 0, raw_max: 3, unit: "enum", values: &[(0, "INIT"), (1, "RUNNING"), (2, "CALIBRATING"), (3, "FAULT")], comment: "Amplifier state; samples are only meaningful while RUNNING." },
            SignalInfo { name: "SampleRate", start_bit: 16, size: 4, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 2.0, raw_min: 0, raw_max: 2, unit: "enum", values: &[(0, "SR_500_HZ"), (1, "SR_1000_HZ"), (2, "SR_2000_HZ")], comment: "Sample rate of EMG_SAMPLES (the default and the decoder's default is 1000 Hz)." },
            SignalInfo { name: "Gain", start_bit: 20, size: 4, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 7.0, raw_min: 0, raw_max: 7, unit: "enum", values: &[(0, "GAIN_1"), (1, "GAIN_2"), (2, "GAIN_4"), (3, "GAIN_8"), (4, "GAIN_16"), (5, "GAIN_32"), (6, "GAIN_64"), (7, "GAIN_128")], comment: "Programmable gain; the EMG LSB stays 2.5 uV referred to the input whatever the gain." },
            SignalInfo { name: "LeadOffMask", start_bit: 24, size: 12, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 4095.0, raw_min: 0, raw_max: 4095, unit: "bitmask", values: &[], comment: "Bit c set: electrode of channel c is off the skin." },
            SignalInfo { name: "SaturationMask", start_bit: 36, size: 12, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 4095.0, raw_min: 0, raw_max: 4095, unit: "bitmask", values: &[], comment: "Bit c set: channel c clipped since the previous status." },
            SignalInfo { name: "Faults", start_bit: 48, size: 8, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 255.0, raw_min: 0, raw_max: 255, unit: "bitmask", values: &[], comment: "bit 0 ADC, bit 1 supply, bit 2 over-temperature, bit 3 clock, bit 4 transmit overrun (samples dropped in the amplifier)." },
        ],
    },
    MessageInfo {
        name: "FINGER_SETPOINT_0",
        id: 0x200,
        dlc: 8,
        cycle_time_ms: 50,
        senders: &["HAND"],
        receivers: &["MC_0"],
        e2e: Some(E2eProfile::from_dbc(0x2200, 4, 8)),
        comment: "Setpoint for finger 0 (thumb), 20 Hz, one per handd tick (50 ms). The motor controller brakes by itself when setpoints stop for 150 ms. No stale setpoint can move a finger: every setpoint carries handd's epoch (signal Epoch), and the controller follows a setpoint only in the epoch it is bound to, which only a SAFE_STOP setpoint opens (rule at signal Epoch; can-dbc/README.md, section The setpoint epoch).",
        signals: &[
            SignalInfo { name: "Crc", start_bit: 0, size: 8, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 255.0, raw_min: 0, raw_max: 255, unit: "crc", values: &[], comment: "" },
            SignalInfo { name: "Counter", start_bit: 8, size: 4, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 15.0, raw_min: 0, raw_max: 15, unit: "count", values: &[], comment: "" },
            SignalInfo { name: "Mode", start_bit: 12, size: 4, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 3.0, raw_min: 0, raw_max: 3, unit: "enum", values: &[(0, "DISABLED"), (1, "ACTIVE"), (2, "HOLD"), (3, "SAFE_STOP")], comment: "DISABLED: motor off, no brake, the finger is free (handd never sends it: every stop of handd's, a finger it lost included, is SAFE_STOP); ACTIVE: follow Force and Velocity (rule at Velocity); HOLD: keep position; SAFE_STOP: zero force, zero velocity, brake. On HAND_ESTOP STOP the controller brakes and retires its epoch: RELEASE does not resume anything, the finger moves again only after a SAFE_STOP of a new epoch (rule at Epoch)." },
            SignalInfo { name: "Force", start_bit: 16, size: 16, signed: true, factor: 0.01, offset: 0.0, min: -50.0, max: 50.0, raw_min: -5000, raw_max: 5000, unit: "N", values: &[], comment: "The most force the finger may push with at the fingertip, flexion positive; its sign must agree with Velocity's for the finger to move (rule at Velocity). handd sends 0 in SAFE_STOP." },
            SignalInfo { name: "Velocity", start_bit: 32, size: 16, signed: true, factor: 0.001, offset: 0.0, min: -20.0, max: 20.0, raw_min: -20000, raw_max: 20000, unit: "rad/s", values: &[], comment: "Commanded joint velocity, flexion positive. In ACTIVE the controller drives the joint at Velocity, pushing with at most |Force|, when Force and Velocity are both non-zero and of the same sign; when they differ in sign, or either is zero, it holds the finger still (as HOLD). A finger blocked by an object or by its joint stop pushes with at most |Force|. A controller that cannot reach Velocity or |Force| within its own limits saturates and reports it (it never exceeds them)." },
            SignalInfo { name: "Epoch", start_bit: 48, size: 16, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 65535.0, raw_min: 0, raw_max: 65535, unit: "epoch", values: &[], comment: "Setpoint epoch, one per finger. handd draws a fresh, unpredictable epoch for each finger at every start and moves every finger to its next one (+1 modulo 65536) on every bus recovery (reopen after bus-off or link down), every change of state into SAFE and in its last round of safe stops before it exits (so the controller retires the epoch it ran in at once), but only finger f on a report of finger f's controller that it braked by itself (the others keep their epoch and their force); in each of its epochs a finger gets SAFE_STOP before anything else. The controller is bound to at most one epoch and remembers the last one it left (retired). A valid SAFE_STOP of an epoch that is not retired binds the controller to it (retiring the previous one); every other setpoint (ACTIVE, HOLD, DISABLED) is followed only if its epoch is the bound one, and a setpoint of the retired epoch, or of any epoch but the bound one, is ignored and counted. At power-up the controller is bound to none; when it brakes by itself (no valid setpoint for 150 ms) or on HAND_ESTOP STOP it retires its epoch and is bound to none, so it moves again only after a SAFE_STOP of a new epoch. Epochs are compared for equality only, so the counter wraps freely; within one run of handd an epoch repeats only after 65536 changes." },
        ],
    },
    MessageInfo {
        name: "FINGER_SETPOINT_1",
        id: 0x201,
        dlc: 8,
        cycle_time_ms: 50,
        senders: &["HAND"],
        receivers: &["MC_1"],
        e2e: Some(E2eProfile::from_dbc(0x2201, 4, 8)),
        comment: "Setpoint for finger 1 (index), see FINGER_SETPOINT_0.",
        signals: &[
            SignalInfo { name: "Crc", start_bit: 0, size: 8, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 255.0, raw_min: 0, raw_max: 255, unit: "crc", values: &[], comment: "" },
            SignalInfo { name: "Counter", start_bit: 8, size: 4, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 15.0, raw_min: 0, raw_max: 15, unit: "count", values: &[], comment: "" },
            SignalInfo { name: "Mode", start_bit: 12, size: 4, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 3.0, raw_min: 0, raw_max: 3, unit: "enum", values: &[(0, "DISABLED"), (1, "ACTIVE"), (2, "HOLD"), (3, "SAFE_STOP")], comment: "" },
            SignalInfo { name: "Force", start_bit: 16, size: 16, signed: true, factor: 0.01, offset: 0.0, min: -50.0, max: 50.0, raw_min: -5000, raw_max: 5000, unit: "N", values: &[], comment: "" },
            SignalInfo { name: "Velocity", start_bit: 32, size: 16, signed: true, factor: 0.001, offset: 0.0, min: -20.0, max: 20.0, raw_min: -20000, raw_max: 20000, unit: "rad/s", values: &[], comment: "" },
            SignalInfo { name: "Epoch", start_bit: 48, size: 16, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 65535.0, raw_min: 0, raw_max: 65535, unit: "epoch", values: &[], comment: "" },
        ],
    },
    MessageInfo {
        name: "FINGER_SETPOINT_2",
        id: 0x202,
        dlc: 8,
        cycle_time_ms: 50,
        senders: &["HAND"],
        receivers: &["MC_2"],
        e2e: Some(E2eProfile::from_dbc(0x2202, 4, 8)),
        comment: "Setpoint for finger 2 (middle), see FINGER_SETPOINT_0.",
        signals: &[
            SignalInfo { name: "Crc", start_bit: 0, size: 8, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 255.0, raw_min: 0, raw_max: 255, unit: "crc", values: &[], comment: "" },
            SignalInfo { name: "Counter", start_bit: 8, size: 4, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 15.0, raw_min: 0, raw_max: 15, unit: "count", values: &[], comment: "" },
            SignalInfo { name: "Mode", start_bit: 12, size: 4, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 3.0, raw_min: 0, raw_max: 3, unit: "enum", values: &[(0, "DISABLED"), (1, "ACTIVE"), (2, "HOLD"), (3, "SAFE_STOP")], comment: "" },
            SignalInfo { name: "Force", start_bit: 16, size: 16, signed: true, factor: 0.01, offset: 0.0, min: -50.0, max: 50.0, raw_min: -5000, raw_max: 5000, unit: "N", values: &[], comment: "" },
            SignalInfo { name: "Velocity", start_bit: 32, size: 16, signed: true, factor: 0.001, offset: 0.0, min: -20.0, max: 20.0, raw_min: -20000, raw_max: 20000, unit: "rad/s", values: &[], comment: "" },
            SignalInfo { name: "Epoch", start_bit: 48, size: 16, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 65535.0, raw_min: 0, raw_max: 65535, unit: "epoch", values: &[], comment: "" },
        ],
    },
    MessageInfo {
        name: "FINGER_SETPOINT_3",
        id: 0x203,
        dlc: 8,
        cycle_time_ms: 50,
        senders: &["HAND"],
        receivers: &["MC_3"],
        e2e: Some(E2eProfile::from_dbc(0x2203, 4, 8)),
        comment: "Setpoint for finger 3 (ring), see FINGER_SETPOINT_0.",
        signals: &[
            SignalInfo { name: "Crc", start_bit: 0, size: 8, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 255.0, raw_min: 0, raw_max: 255, unit: "crc", values: &[], comment: "" },
            SignalInfo { name: "Counter", start_bit: 8, size: 4, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 15.0, raw_min: 0, raw_max: 15, unit: "count", values: &[], comment: "" },
            SignalInfo { name: "Mode", start_bit: 12, size: 4, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 3.0, raw_min: 0, raw_max: 3, unit: "enum", values: &[(0, "DISABLED"), (1, "ACTIVE"), (2, "HOLD"), (3, "SAFE_STOP")], comment: "" },
            SignalInfo { name: "Force", start_bit: 16, size: 16, signed: true, factor: 0.01, offset: 0.0, min: -50.0, max: 50.0, raw_min: -5000, raw_max: 5000, unit: "N", values: &[], comment: "" },
            SignalInfo { name: "Velocity", start_bit: 32, size: 16, signed: true, factor: 0.001, offset: 0.0, min: -20.0, max: 20.0, raw_min: -20000, raw_max: 20000, unit: "rad/s", values: &[], comment: "" },
            SignalInfo { name: "Epoch", start_bit: 48, size: 16, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 65535.0, raw_min: 0, raw_max: 65535, unit: "epoch", values: &[], comment: "" },
        ],
    },
    MessageInfo {
        name: "FINGER_SETPOINT_4",
        id: 0x204,
        dlc: 8,
        cycle_time_ms: 50,
        senders: &["HAND"],
        receivers: &["MC_4"],
        e2e: Some(E2eProfile::from_dbc(0x2204, 4, 8)),
        comment: "Setpoint for finger 4 (pinky), see FINGER_SETPOINT_0.",
        signals: &[
            SignalInfo { name: "Crc", start_bit: 0, size: 8, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 255.0, raw_min: 0, raw_max: 255, unit: "crc", values: &[], comment: "" },
            SignalInfo { name: "Counter", start_bit: 8, size: 4, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 15.0, raw_min: 0, raw_max: 15, unit: "count", values: &[], comment: "" },
            SignalInfo { name: "Mode", start_bit: 12, size: 4, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 3.0, raw_min: 0, raw_max: 3, unit: "enum", values: &[(0, "DISABLED"), (1, "ACTIVE"), (2, "HOLD"), (3, "SAFE_STOP")], comment: "" },
            SignalInfo { name: "Force", start_bit: 16, size: 16, signed: true, factor: 0.01, offset: 0.0, min: -50.0, max: 50.0, raw_min: -5000, raw_max: 5000, unit: "N", values: &[], comment: "" },
            SignalInfo { name: "Velocity", start_bit: 32, size: 16, signed: true, factor: 0.001, offset: 0.0, min: -20.0, max: 20.0, raw_min: -20000, raw_max: 20000, unit: "rad/s", values: &[], comment: "" },
            SignalInfo { name: "Epoch", start_bit: 48, size: 16, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 65535.0, raw_min: 0, raw_max: 65535, unit: "epoch", values: &[], comment: "" },
        ],
    },
    MessageInfo {
        name: "FINGER_STATUS_0",
        id: 0x280,
        dlc: 8,
        cycle_time_ms: 20,
        senders: &["MC_0"],
        receivers: &["HAND"],
        e2e: Some(E2eProfile::from_dbc(0x1280, 4, 8)),
        comment: "Status of finger 0 (thumb), 50 Hz.",
        signals: &[
            SignalInfo { name: "Crc", start_bit: 0, size: 8, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 255.0, raw_min: 0, raw_max: 255, unit: "crc", values: &[], comment: "" },
            SignalInfo { name: "Counter", start_bit: 8, size: 4, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 15.0, raw_min: 0, raw_max: 15, unit: "count", values: &[], comment: "" },
            SignalInfo { name: "State", start_bit: 12, size: 4, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 5.0, raw_min: 0, raw_max: 5, unit: "enum", values: &[(0, "DISABLED"), (1, "ACTIVE"), (2, "HOLD"), (3, "SAFE_STOP"), (4, "BRAKED"), (5, "FAULT")], comment: "" },
            SignalInfo { name: "Position", start_bit: 16, size: 12, signed: false, factor: 0.001, offset: -0.5, min: -0.5, max: 2.0, raw_min: 0, raw_max: 2500, unit: "rad", values: &[], comment: "Joint angle, 0 = fully extended, flexion positive." },
            SignalInfo { name: "Velocity", start_bit: 28, size: 12, signed: true, factor: 0.01, offset: 0.0, min: -20.0, max: 20.0, raw_min: -2000, raw_max: 2000, unit: "rad/s", values: &[], comment: "" },
            SignalInfo { name: "Force", start_bit: 40, size: 12, signed: true, factor: 0.025, offset: 0.0, min: -50.0, max: 50.0, raw_min: -2000, raw_max: 2000, unit: "N", values: &[], comment: "" },
            SignalInfo { name: "Faults", start_bit: 52, size: 8, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 255.0, raw_min: 0, raw_max: 255, unit: "bitmask", values: &[], comment: "bit 0 over-current, bit 1 over-temperature, bit 2 encoder, bit 3 setpoint timeout (braked), bit 4 E2E error on setpoints, bit 5 joint limit (at a joint stop with the command pushing into it: handd stops integrating velocity toward that stop), bit 6 setpoint ignored by the epoch rule (a valid setpoint of a stale or not yet opened epoch, see FINGER_SETPOINT Epoch) since the previous status." },
        ],
    },
    MessageInfo {
        name: "FINGER_STATUS_1",
        id: 0x281,
        dlc: 8,
        cycle_time_ms: 20,
        senders: &["MC_1"],
        receivers: &["HAND"],
        e2e: Some(E2eProfile::from_dbc(0x1281, 4, 8)),
        comment: "Status of finger 1 (index), 50 Hz.",
        signals: &[
            SignalInfo { name: "Crc", start_bit: 0, size: 8, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 255.0, raw_min: 0, raw_max: 255, unit: "crc", values: &[], comment: "" },
            SignalInfo { name: "Counter", start_bit: 8, size: 4, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 15.0, raw_min: 0, raw_max: 15, unit: "count", values: &[], comment: "" },
            SignalInfo { name: "State", start_bit: 12, size: 4, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 5.0, raw_min: 0, raw_max: 5, unit: "enum", values: &[(0, "DISABLED"), (1, "ACTIVE"), (2, "HOLD"), (3, "SAFE_STOP"), (4, "BRAKED"), (5, "FAULT")], comment: "" },
            SignalInfo { name: "Position", start_bit: 16, size: 12, signed: false, factor: 0.001, offset: -0.5, min: -0.5, max: 2.0, raw_min: 0, raw_max: 2500, unit: "rad", values: &[], comment: "" },
            SignalInfo { name: "Velocity", start_bit: 28, size: 12, signed: true, factor: 0.01, offset: 0.0, min: -20.0, max: 20.0, raw_min: -2000, raw_max: 2000, unit: "rad/s", values: &[], comment: "" },
            SignalInfo { name: "Force", start_bit: 40, size: 12, signed: true, factor: 0.025, offset: 0.0, min: -50.0, max: 50.0, raw_min: -2000, raw_max: 2000, unit: "N", values: &[], comment: "" },
            SignalInfo { name: "Faults", start_bit: 52, size: 8, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 255.0, raw_min: 0, raw_max: 255, unit: "bitmask", values: &[], comment: "" },
        ],
    },
    MessageInfo {
        name: "FINGER_STATUS_2",
        id: 0x282,
        dlc: 8,
        cycle_time_ms: 20,
        senders: &["MC_2"],
        receivers: &["HAND"],
        e2e: Some(E2eProfile::from_dbc(0x1282, 4, 8)),
        comment: "Status of finger 2 (middle), 50 Hz.",
        signals: &[
            SignalInfo { name: "Crc", start_bit: 0, size: 8, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 255.0, raw_min: 0, raw_max: 255, unit: "crc", values: &[], comment: "" },
            SignalInfo { name: "Counter", start_bit: 8, size: 4, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 15.0, raw_min: 0, raw_max: 15, unit: "count", values: &[], comment: "" },
            SignalInfo { name: "State", start_bit: 12, size: 4, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 5.0, raw_min: 0, raw_max: 5, unit: "enum", values: &[(0, "DISABLED"), (1, "ACTIVE"), (2, "HOLD"), (3, "SAFE_STOP"), (4, "BRAKED"), (5, "FAULT")], comment: "" },
            SignalInfo { name: "Position", start_bit: 16, size: 12, signed: false, factor: 0.001, offset: -0.5, min: -0.5, max: 2.0, raw_min: 0, raw_max: 2500, unit: "rad", values: &[], comment: "" },
            SignalInfo { name: "Velocity", start_bit: 28, size: 12, signed: true, factor: 0.01, offset: 0.0, min: -20.0, max: 20.0, raw_min: -2000, raw_max: 2000, unit: "rad/s", values: &[], comment: "" },
            SignalInfo { name: "Force", start_bit: 40, size: 12, signed: true, factor: 0.025, offset: 0.0, min: -50.0, max: 50.0, raw_min: -2000, raw_max: 2000, unit: "N", values: &[], comment: "" },
            SignalInfo { name: "Faults", start_bit: 52, size: 8, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 255.0, raw_min: 0, raw_max: 255, unit: "bitmask", values: &[], comment: "" },
        ],
    },
    MessageInfo {
        name: "FINGER_STATUS_3",
        id: 0x283,
        dlc: 8,
        cycle_time_ms: 20,
        senders: &["MC_3"],
        receivers: &["HAND"],
        e2e: Some(E2eProfile::from_dbc(0x1283, 4, 8)),
        comment: "Status of finger 3 (ring), 50 Hz.",
        signals: &[
            SignalInfo { name: "Crc", start_bit: 0, size: 8, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 255.0, raw_min: 0, raw_max: 255, unit: "crc", values: &[], comment: "" },
            SignalInfo { name: "Counter", start_bit: 8, size: 4, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 15.0, raw_min: 0, raw_max: 15, unit: "count", values: &[], comment: "" },
            SignalInfo { name: "State", start_bit: 12, size: 4, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 5.0, raw_min: 0, raw_max: 5, unit: "enum", values: &[(0, "DISABLED"), (1, "ACTIVE"), (2, "HOLD"), (3, "SAFE_STOP"), (4, "BRAKED"), (5, "FAULT")], comment: "" },
            SignalInfo { name: "Position", start_bit: 16, size: 12, signed: false, factor: 0.001, offset: -0.5, min: -0.5, max: 2.0, raw_min: 0, raw_max: 2500, unit: "rad", values: &[], comment: "" },
            SignalInfo { name: "Velocity", start_bit: 28, size: 12, signed: true, factor: 0.01, offset: 0.0, min: -20.0, max: 20.0, raw_min: -2000, raw_max: 2000, unit: "rad/s", values: &[], comment: "" },
            SignalInfo { name: "Force", start_bit: 40, size: 12, signed: true, factor: 0.025, offset: 0.0, min: -50.0, max: 50.0, raw_min: -2000, raw_max: 2000, unit: "N", values: &[], comment: "" },
            SignalInfo { name: "Faults", start_bit: 52, size: 8, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 255.0, raw_min: 0, raw_max: 255, unit: "bitmask", values: &[], comment: "" },
        ],
    },
    MessageInfo {
        name: "FINGER_STATUS_4",
        id: 0x284,
        dlc: 8,
        cycle_time_ms: 20,
        senders: &["MC_4"],
        receivers: &["HAND"],
        e2e: Some(E2eProfile::from_dbc(0x1284, 4, 8)),
        comment: "Status of finger 4 (pinky), 50 Hz.",
        signals: &[
            SignalInfo { name: "Crc", start_bit: 0, size: 8, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 255.0, raw_min: 0, raw_max: 255, unit: "crc", values: &[], comment: "" },
            SignalInfo { name: "Counter", start_bit: 8, size: 4, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 15.0, raw_min: 0, raw_max: 15, unit: "count", values: &[], comment: "" },
            SignalInfo { name: "State", start_bit: 12, size: 4, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 5.0, raw_min: 0, raw_max: 5, unit: "enum", values: &[(0, "DISABLED"), (1, "ACTIVE"), (2, "HOLD"), (3, "SAFE_STOP"), (4, "BRAKED"), (5, "FAULT")], comment: "" },
            SignalInfo { name: "Position", start_bit: 16, size: 12, signed: false, factor: 0.001, offset: -0.5, min: -0.5, max: 2.0, raw_min: 0, raw_max: 2500, unit: "rad", values: &[], comment: "" },
            SignalInfo { name: "Velocity", start_bit: 28, size: 12, signed: true, factor: 0.01, offset: 0.0, min: -20.0, max: 20.0, raw_min: -2000, raw_max: 2000, unit: "rad/s", values: &[], comment: "" },
            SignalInfo { name: "Force", start_bit: 40, size: 12, signed: true, factor: 0.025, offset: 0.0, min: -50.0, max: 50.0, raw_min: -2000, raw_max: 2000, unit: "N", values: &[], comment: "" },
            SignalInfo { name: "Faults", start_bit: 52, size: 8, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 255.0, raw_min: 0, raw_max: 255, unit: "bitmask", values: &[], comment: "" },
        ],
    },
    MessageInfo {
        name: "HAND_HEARTBEAT",
        id: 0x300,
        dlc: 8,
        cycle_time_ms: 100,
        senders: &["HAND"],
        receivers: &["AMP", "MC_0", "MC_1", "MC_2", "MC_3", "MC_4", "TOOL"],
        e2e: Some(E2eProfile::from_dbc(0x2300, 4, 8)),
        comment: "handd heartbeat, 10 Hz.",
        signals: &[
            SignalInfo { name: "Crc", start_bit: 0, size: 8, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 255.0, raw_min: 0, raw_max: 255, unit: "crc", values: &[], comment: "" },
            SignalInfo { name: "Counter", start_bit: 8, size: 4, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 15.0, raw_min: 0, raw_max: 15, unit: "count", values: &[], comment: "" },
            SignalInfo { name: "State", start_bit: 12, size: 4, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 3.0, raw_min: 0, raw_max: 3, unit: "enum", values: &[(0, "BOOT"), (1, "READY"), (2, "RUNNING"), (3, "SAFE")], comment: "" },
            SignalInfo { name: "FaultMask", start_bit: 16, size: 16, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 65535.0, raw_min: 0, raw_max: 65535, unit: "bitmask", values: &[], comment: "handd's active faults, one bit each, as handctl status names them: bit 0 emg_silence, bit 1 e2e_error, bit 2 invalid_window, bit 3 non_finite, bit 4 signal_quality, bit 5 estop, bit 6 bus_off, bit 7 interface_down, bit 8 repeated_e2e, bit 9 model_error, bit 10 stop_requested, bit 11 calibrating, bit 12 no_model, bit 13 model_swapped, bit 14 second_master, bit 15 bus_degraded; all 16 bits in use. A finger whose controller fell silent is not a daemon fault: FINGER_STATUS and handctl status show it." },
            SignalInfo { name: "ModelId", start_bit: 32, size: 32, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 4294967295.0, raw_min: 0, raw_max: 4294967295, unit: "id", values: &[], comment: "Fingerprint of the loaded model file: the 32-bit FNV-1a hash (offset basis 0x811C9DC5, prime 0x01000193) of the whole file's bytes, as handctl status shows it in hex; 0 when no model is loaded." },
        ],
    },
    MessageInfo {
        name: "HAND_DIAG",
        id: 0x301,
        dlc: 8,
        cycle_time_ms: 50,
        senders: &["HAND"],
        receivers: &["TOOL"],
        e2e: None,
        comment: "handd diagnostics for the technician tool, 20 Hz, one per tick. Not safety relevant, so no E2E.",
        signals: &[
            SignalInfo { name: "TickLatency", start_bit: 0, size: 16, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 65535.0, raw_min: 0, raw_max: 65535, unit: "us", values: &[], comment: "Previous tick (this frame is built before its own tick's setpoints are written): receive time of the newest complete EMG sample it had to its setpoints written, us (sender caps at 65535). A replay finds the samples each tick had from it." },
            SignalInfo { name: "DeadlineMisses", start_bit: 16, size: 8, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 255.0, raw_min: 0, raw_max: 255, unit: "count", values: &[], comment: "Deadline misses since handd started, modulo 256 (a wrapping total: 255 is followed by 0). A tool takes the difference of two frames modulo 256, which stays right across lost HAND_DIAG frames as long as fewer than 256 misses fall between them; the full count is in handctl status." },
            SignalInfo { name: "EmgSamplesLost", start_bit: 24, size: 8, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 255.0, raw_min: 0, raw_max: 255, unit: "count", values: &[], comment: "EMG samples lost (and bridged) since handd started, modulo 256 (a wrapping total, as DeadlineMisses); the full count is in handctl status." },
            SignalInfo { name: "Label0", start_bit: 32, size: 6, signed: true, factor: 0.05, offset: 0.0, min: -1.0, max: 1.0, raw_min: -20, raw_max: 20, unit: "1", values: &[], comment: "Decoded label of finger 0 (thumb), flexion +1, extension -1, for display (0.05 steps)." },
            SignalInfo { name: "Label1", start_bit: 38, size: 6, signed: true, factor: 0.05, offset: 0.0, min: -1.0, max: 1.0, raw_min: -20, raw_max: 20, unit: "1", values: &[], comment: "Decoded label of finger 1 (index)." },
            SignalInfo { name: "Label2", start_bit: 44, size: 6, signed: true, factor: 0.05, offset: 0.0, min: -1.0, max: 1.0, raw_min: -20, raw_max: 20, unit: "1", values: &[], comment: "Decoded label of finger 2 (middle)." },
            SignalInfo { name: "Label3", start_bit: 50, size: 6, signed: true, factor: 0.05, offset: 0.0, min: -1.0, max: 1.0, raw_min: -20, raw_max: 20, unit: "1", values: &[], comment: "Decoded label of finger 3 (ring)." },
            SignalInfo { name: "Label4", start_bit: 56, size: 6, signed: true, factor: 0.05, offset: 0.0, min: -1.0, max: 1.0, raw_min: -20, raw_max: 20, unit: "1", values: &[], comment: "Decoded label of finger 4 (pinky)." },
            SignalInfo { name: "NewestSample", start_bit: 62, size: 2, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 3.0, raw_min: 0, raw_max: 3, unit: "count", values: &[], comment: "Previous tick: the EMG sample counter of the newest complete sample it had, modulo 4. With TickLatency it names that sample exactly, so a replay of a bus log knows which samples each tick had." },
        ],
    },
    MessageInfo {
        name: "CALIBRATION_CUE",
        id: 0x380,
        dlc: 8,
        cycle_time_ms: 100,
        senders: &["TOOL"],
        receivers: &["HAND", "AMP"],
        e2e: Some(E2eProfile::from_dbc(0x1380, 4, 8)),
        comment: "Calibration cue from the technician tool (handctl calibrate) to the patient: what to do now. Sent at 10 Hz and at once on every change of phase, only while a calibration runs. A patient-facing display (AMP side) or the simulated patient follows it; handd ignores it. A receiver that sees no valid cue for 1 s takes the calibration as gone and rests.",
        signals: &[
            SignalInfo { name: "Crc", start_bit: 0, size: 8, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 255.0, raw_min: 0, raw_max: 255, unit: "crc", values: &[], comment: "CRC-8 SAE J1850 over data id 0x1380 and bytes 1..7." },
            SignalInfo { name: "Counter", start_bit: 8, size: 4, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 15.0, raw_min: 0, raw_max: 15, unit: "count", values: &[], comment: "4-bit alive counter." },
            SignalInfo { name: "Phase", start_bit: 12, size: 4, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 5.0, raw_min: 0, raw_max: 5, unit: "enum", values: &[(0, "IDLE"), (1, "PREPARE"), (2, "HOLD"), (3, "RELAX"), (4, "DONE"), (5, "ABORTED")], comment: "IDLE: no trial yet (or between trials); PREPARE: get ready for the trial named, stay at rest; HOLD: contract now as cued and hold; RELAX: let go, back to rest; DONE: the protocol is finished; ABORTED: the calibration was stopped. Every phase but HOLD means rest." },
            SignalInfo { name: "Trial", start_bit: 16, size: 8, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 255.0, raw_min: 0, raw_max: 255, unit: "index", values: &[], comment: "Index of the trial in the protocol (0..254); 255 = none (IDLE, DONE, ABORTED)." },
            SignalInfo { name: "Finger", start_bit: 24, size: 4, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 15.0, raw_min: 0, raw_max: 15, unit: "finger", values: &[], comment: "Cued finger: 0 thumb, 1 index, 2 middle, 3 ring, 4 pinky, 5 the whole hand (all five), 15 none (rest). 6..14 are not used; a receiver takes them as none." },
            SignalInfo { name: "Kind", start_bit: 28, size: 4, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 2.0, raw_min: 0, raw_max: 2, unit: "enum", values: &[(0, "REST"), (1, "FLEXION"), (2, "EXTENSION")], comment: "REST: stay relaxed; FLEXION: maximal flexion of the cued finger(s) (label +1); EXTENSION: maximal extension (label -1)." },
            SignalInfo { name: "Repetition", start_bit: 32, size: 4, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 15.0, raw_min: 0, raw_max: 15, unit: "count", values: &[], comment: "Repetition of this trial's movement in the protocol, 0-based." },
            SignalInfo { name: "Attempt", start_bit: 36, size: 4, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 15.0, raw_min: 0, raw_max: 15, unit: "count", values: &[], comment: "Attempt at this trial, 0 = first; a trial repeated after a failed quality check counts up (modulo 16)." },
            SignalInfo { name: "TimeLeft", start_bit: 40, size: 16, signed: false, factor: 0.01, offset: 0.0, min: 0.0, max: 655.35, raw_min: 0, raw_max: 65535, unit: "s", values: &[], comment: "Time left in the current phase, 0.01 s per LSB (0..655.35 s)." },
            SignalInfo { name: "Effort", start_bit: 56, size: 8, signed: false, factor: 1.0, offset: 0.0, min: 0.0, max: 100.0, raw_min: 0, raw_max: 100, unit: "%", values: &[], comment: "Requested effort in percent of maximal voluntary contraction; 100 for a normal cue." },
        ],
    },
];
