//! What one drive's start-up needs, validated once into the plan of steps.

use super::step::Step;
use crate::cia402::{objects, Mode};
use crate::ids::{CobId, NodeId, ObjectAddr};
use crate::pdo::finger_pdos;
use crate::sdo::{SdoData, SdoWrite};
use thiserror::Error;

/// 0x6007 abort connection option: 3 = quick stop when the master's heartbeat is lost.
pub const ABORT_CONNECTION_QUICK_STOP: i16 = 3;
/// 0x605A quick stop option: 2 = slow down on the quick stop ramp, then Switch on disabled.
pub const QUICK_STOP_RAMP_THEN_DISABLE: i16 = 2;

/// The start-up settings of one CiA 402 drive.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StartupSettings {
    /// The drive.
    pub node: NodeId,
    /// handd's own node id (its heartbeat is what the drive watches through 0x1016).
    pub master: NodeId,
    /// The operating mode (0x6060); refused unless 0x6502 lists it.
    pub mode: Mode,
    /// The SYNC period, written to 0x60C2.
    pub sync_period_us: u32,
    /// The SYNC COB-ID, written to 0x1005 (CiA 301's default is [`CobId::SYNC`], 0x080).
    pub sync_cob_id: CobId,
    /// How long the drive tolerates silence from handd's heartbeat (0x1016:01), ms.
    pub master_heartbeat_timeout_ms: u16,
    /// The drive's own heartbeat period (0x1017), ms.
    pub drive_heartbeat_ms: u16,
    /// 0x6007.
    pub abort_connection: i16,
    /// 0x605A.
    pub quick_stop_option: i16,
    /// Timeout of each SDO transfer.
    pub sdo_timeout_us: u64,
    /// Timeout of the boot-up wait and of each power state machine step.
    pub step_timeout_us: u64,
}

/// A start-up setting that cannot work.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Error)]
pub enum SettingsError {
    /// The drive and handd share a node id.
    #[error("drive node id {0} is handd's own node id")]
    SameNode(u8),
    /// The SYNC COB-ID is NMT's or one of the drive's own COB-IDs.
    #[error("SYNC COB-ID {0:#05x} is NMT's or one of the drive's own COB-IDs")]
    SyncCobId(u16),
    /// 0x60C2 cannot express the SYNC period (value 1..=255 times 10^-3..10^-6 s).
    #[error("SYNC period of {0} us cannot be written to 0x60C2")]
    SyncPeriod(u32),
    /// A zero timeout or period.
    #[error("`{0}` must be > 0")]
    Zero(&'static str),
    /// The drive's watchdog on handd's heartbeat must outlast a SYNC period (handd sends
    /// both from the same loop).
    #[error(
        "master heartbeat timeout {timeout_ms} ms is not longer than the SYNC period {sync_us} us"
    )]
    WatchdogTooShort {
        /// 0x1016 time.
        timeout_ms: u16,
        /// The SYNC period.
        sync_us: u32,
    },
}

/// 0x60C2 value and index (exponent of ten, seconds) for a period.
pub fn interpolation_period(period_us: u32) -> Option<(u8, i8)> {
    [(-3i8, 1000u32), (-4, 100), (-5, 10), (-6, 1)]
        .into_iter()
        .find(|(_, div)| period_us.is_multiple_of(*div) && (1..=255).contains(&(period_us / div)))
        .map(|(idx, div)| ((period_us / div) as u8, idx))
}

impl StartupSettings {
    /// Checks the settings and lays out the steps.
    pub fn plan(&self) -> Result<Vec<Step>, SettingsError> {
        let (ip_value, ip_index) = self.validate()?;
        let mut config = self.objects(ip_value, ip_index);
        let mut read_back: Vec<SdoWrite> = config.clone();
        let pdos = finger_pdos(self.node, self.mode);
        config.extend(pdos.iter().flat_map(|p| p.plan()));
        read_back.extend(pdos.iter().flat_map(|p| p.expected()));
        let zero = self.zeroed();
        read_back.extend(zero.iter().copied());

        let mut steps = vec![Step::ResetCommunication, Step::AwaitBootUp];
        steps.extend((1..=4).map(Step::ReadIdentity));
        steps.push(Step::CheckMode(self.mode));
        steps.extend(config.into_iter().map(Step::Write));
        steps.extend(zero.into_iter().map(Step::ZeroTarget));
        steps.extend(read_back.into_iter().map(Step::ReadBack));
        steps.push(Step::StartNode);
        steps.push(Step::Enable);
        Ok(steps)
    }

    /// Refuses settings that cannot work; the 0x60C2 value and index of the SYNC period.
    fn validate(&self) -> Result<(u8, i8), SettingsError> {
        if self.node == self.master {
            return Err(SettingsError::SameNode(self.node.get()));
        }
        for (name, v) in [
            ("sdo_timeout_us", self.sdo_timeout_us),
            ("step_timeout_us", self.step_timeout_us),
            (
                "master_heartbeat_timeout_ms",
                u64::from(self.master_heartbeat_timeout_ms),
            ),
            ("drive_heartbeat_ms", u64::from(self.drive_heartbeat_ms)),
        ] {
            if v == 0 {
                return Err(SettingsError::Zero(name));
            }
        }
        if self.sync_cob_id == CobId::NMT || CobId::all_of(self.node).contains(&self.sync_cob_id) {
            return Err(SettingsError::SyncCobId(self.sync_cob_id.raw()));
        }
        let period = interpolation_period(self.sync_period_us)
            .ok_or(SettingsError::SyncPeriod(self.sync_period_us))?;
        if u64::from(self.master_heartbeat_timeout_ms) * 1000 <= u64::from(self.sync_period_us) {
            return Err(SettingsError::WatchdogTooShort {
                timeout_ms: self.master_heartbeat_timeout_ms,
                sync_us: self.sync_period_us,
            });
        }
        Ok(period)
    }

    /// The communication and drive objects written (and read back), PDOs aside.
    fn objects(&self, ip_value: u8, ip_index: i8) -> Vec<SdoWrite> {
        let consumer =
            (u32::from(self.master.get()) << 16) | u32::from(self.master_heartbeat_timeout_ms);
        vec![
            write(0x1005, 0, SdoData::u32(u32::from(self.sync_cob_id.raw()))),
            write(0x1017, 0, SdoData::u16(self.drive_heartbeat_ms)),
            write(0x1016, 1, SdoData::u32(consumer)),
            write(
                objects::ABORT_CONNECTION,
                0,
                SdoData::i16(self.abort_connection),
            ),
            write(
                objects::QUICK_STOP_OPTION,
                0,
                SdoData::i16(self.quick_stop_option),
            ),
            write(objects::INTERPOLATION_PERIOD, 1, SdoData::u8(ip_value)),
            write(objects::INTERPOLATION_PERIOD, 2, SdoData::i8(ip_index)),
            write(
                objects::MODES_OF_OPERATION,
                0,
                SdoData::i8(self.mode.value()),
            ),
        ]
    }

    /// What is written 0 before the drive is enabled: nothing left in the drive may move the
    /// motor on enable. The target, and in the velocity modes the torque limit too (until the
    /// first RPDO1 brings handd's, the drive would otherwise push with whatever limit its own
    /// memory holds).
    fn zeroed(&self) -> Vec<SdoWrite> {
        match self.mode {
            Mode::CyclicSyncTorque => vec![write(objects::TARGET_TORQUE, 0, SdoData::i16(0))],
            Mode::CyclicSyncVelocity | Mode::ProfileVelocity => vec![
                write(objects::TARGET_VELOCITY, 0, SdoData::i32(0)),
                write(objects::MAX_TORQUE, 0, SdoData::u16(0)),
            ],
        }
    }
}

/// One expedited write of `data` to `index`:`sub`.
fn write(index: u16, sub: u8, data: SdoData) -> SdoWrite {
    SdoWrite::new(ObjectAddr::new(index, sub), data)
}
