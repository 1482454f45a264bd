//! The CiA 402 fingers: `hand_canopen::DriveBank` inside the engine. Frames of the drives'
//! COB-IDs go to the bank instead of hand.dbc's decoder; a CiA 402 finger's setpoint leaves as
//! its RPDO1 (torque per mille in CST, rpm and the force as max torque in CSV and PV, through
//! the finger's scaling), then one SYNC and handd's CANopen heartbeat end the tick. Start-up
//! SDO replies are answered at once ([`Engine::take_immediate`]), so a drive starts at bus
//! speed, not one step per tick.

use hand_canopen::master::{BankSettings, DriveBank, DriveStatus, Target, TorqueLimit};
use hand_canopen::{CobId, NodeId};
use hand_dbc::CanFrame;

use crate::conditioner::Setpoint;
use crate::drive_config::{Drive, Drives as DriveTable};
use crate::units::N_FINGERS;

/// Most frames [`Engine::take_immediate`] holds between two reads of the bus; more are
/// dropped and counted (a start-up step then times out and names itself).
pub const MAX_IMMEDIATE: usize = 16;

/// How long a drive may take to answer one SDO request during start-up, µs: python
/// `canopen`'s `SdoClient.RESPONSE_TIMEOUT` (0.3 s). The request goes out when handd has read
/// the previous answer (it reads the bus every 10 ms between ticks), and a drive may be busy
/// (saving, resetting); 50 ms timed out in the vcan suite, whose guest CPUs stop for up to 32 ms
/// under emulation. Start-up holds the finger disabled, so a longer wait costs only time.
pub const SDO_TIMEOUT_US: u64 = 300_000;

/// handd's side of the CANopen timing, from the tick: the drives watch handd's heartbeat for
/// three ticks, send their own every tick, and handd gives them three ticks too. An SDO reply
/// may take [`SDO_TIMEOUT_US`].
pub fn bank_settings(master: NodeId, sync: CobId, tick_us: u64) -> BankSettings {
    let tick_ms = (tick_us / 1000).clamp(1, u64::from(u16::MAX) / 3) as u16;
    BankSettings {
        master,
        tick_us: tick_us as u32,
        sync_cob_id: sync,
        master_heartbeat_timeout_ms: 3 * tick_ms,
        drive_heartbeat_ms: tick_ms,
        drive_heartbeat_timeout_us: 3 * u64::from(tick_ms) * 1000,
        sdo_timeout_us: SDO_TIMEOUT_US,
        step_timeout_us: 1_000_000,
    }
}

/// The bank and which finger is which of its drives.
#[derive(Clone)]
pub(super) struct Drives {
    bank: DriveBank,
    /// Per finger: its slot in the bank and its scaling.
    slot: [Option<(usize, hand_canopen::scaling::Scaling)>; N_FINGERS],
    /// Every drive's COB-IDs (for routing), one bit per 11-bit id: every received frame is
    /// looked up, so a bit test rather than a scan of the 60 ids of five drives.
    cob_ids: CobIdSet,
    targets: [Target; N_FINGERS],
    immediate: [CanFrame; MAX_IMMEDIATE],
    immediate_len: usize,
    /// Immediate frames dropped for want of room.
    pub(super) immediate_dropped: u64,
}

/// A set of 11-bit CAN ids.
#[derive(Clone, Default)]
struct CobIdSet([u64; 2048 / 64]);

impl CobIdSet {
    fn insert(&mut self, id: u16) {
        let id = usize::from(id & 0x7FF);
        self.0[id / 64] |= 1 << (id % 64);
    }

    fn contains(&self, id: u32) -> bool {
        let id = id as usize;
        id < 2048 && self.0[id / 64] & (1 << (id % 64)) != 0
    }
}

fn to_dbc(f: hand_canopen::CanFrame) -> CanFrame {
    CanFrame::new_standard(f.cob_id(), f.payload()).expect("an 11-bit CANopen frame")
}

impl Drives {
    /// The bank for `table`, or `None` when every finger is native. The table was validated
    /// with the config, so the bank's own checks hold; `Err` names one that does not.
    pub(super) fn try_new(table: &DriveTable, tick_us: u64) -> Result<Option<Self>, String> {
        let Some((master, sync)) = table.master else {
            return Ok(None);
        };
        let mut list = Vec::new();
        let mut slot = [None; N_FINGERS];
        let mut cob_ids = CobIdSet::default();
        for (f, d) in table.fingers.iter().enumerate() {
            if let Drive::Cia402 {
                node,
                mode,
                scaling,
            } = *d
            {
                slot[f] = Some((list.len(), scaling));
                list.push((node, mode));
                for c in CobId::all_of(node) {
                    cob_ids.insert(c.raw());
                }
            }
        }
        let bank = DriveBank::try_new(bank_settings(master, sync, tick_us), &list)
            .map_err(|e| e.to_string())?;
        Ok(Some(Self {
            bank,
            slot,
            cob_ids,
            targets: [Target::Stop; N_FINGERS],
            immediate: [CanFrame::new_standard(0, &[]).expect("an empty frame is valid");
                MAX_IMMEDIATE],
            immediate_len: 0,
            immediate_dropped: 0,
        }))
    }

    /// Whether finger `f` has a CiA 402 drive.
    pub(super) fn has(&self, f: usize) -> bool {
        self.slot[f].is_some()
    }

    /// Whether `frame` is one of the drives' (handd routes it here, not to hand.dbc's decoder).
    pub(super) fn claims(&self, frame: &CanFrame) -> bool {
        !frame.is_extended() && self.cob_ids.contains(frame.raw_id())
    }

    /// A drive's frame at `rx_us`; start-up replies wait in the immediate queue.
    pub(super) fn on_frame(&mut self, frame: &CanFrame, rx_us: u64) {
        let Some(f) = hand_canopen::CanFrame::new(frame.raw_id() as u16, frame.data()) else {
            return;
        };
        let (immediate, len, dropped) = (
            &mut self.immediate,
            &mut self.immediate_len,
            &mut self.immediate_dropped,
        );
        self.bank.on_frame(&f, rx_us, &mut |out| {
            if *len < MAX_IMMEDIATE {
                immediate[*len] = to_dbc(out);
                *len += 1;
            } else {
                *dropped += 1;
            }
        });
    }

    /// The frames to send at once, and empties the queue.
    pub(super) fn take_immediate(&mut self) -> &[CanFrame] {
        let n = self.immediate_len;
        self.immediate_len = 0;
        &self.immediate[..n]
    }

    /// Finger `f` may be driven: its drive runs with no latched fault.
    pub(super) fn ready(&self, f: usize) -> bool {
        self.slot[f]
            .is_some_and(|(k, _)| matches!(self.bank.status(k), DriveStatus::Running { .. }))
    }

    /// Finger `f`'s drive follows its target now.
    pub(super) fn enabled(&self, f: usize) -> bool {
        self.slot[f].is_some_and(|(k, _)| self.bank.is_enabled(k))
    }

    /// Finger `f`'s drive's node id, if it has one.
    pub(super) fn node(&self, f: usize) -> Option<u8> {
        self.slot[f].map(|(k, _)| self.bank.node(k).get())
    }

    /// Finger `f`'s drive status, if it has one.
    pub(super) fn status(&self, f: usize) -> Option<DriveStatus> {
        self.slot[f].map(|(k, _)| self.bank.status(k))
    }

    /// Finger `f`'s setpoint as its drive's target: `None` stops it. In CST the force is the
    /// target torque; in CSV and PV the velocity is the target and the force's magnitude its
    /// torque limit (0x6072), the native controller's force-limited velocity.
    pub(super) fn set_target(&mut self, f: usize, setpoint: Option<&Setpoint>) {
        let Some((k, scaling)) = self.slot[f] else {
            return;
        };
        let target = match setpoint {
            None => Target::Stop,
            Some(sp) => match self.bank.mode(k) {
                hand_canopen::Mode::CyclicSyncTorque => {
                    Target::torque(i32::from(scaling.torque_permille(sp.force.0)))
                }
                hand_canopen::Mode::CyclicSyncVelocity | hand_canopen::Mode::ProfileVelocity => {
                    Target::velocity(
                        scaling.velocity_rpm(sp.velocity.0),
                        TorqueLimit(scaling.max_torque_permille(sp.force.0)),
                    )
                }
            },
        };
        self.targets[k] = target;
    }

    /// The tick's drive frames: RPDO1 per drive, SYNC, heartbeat.
    pub(super) fn tick(&mut self, now_us: u64, mut push: impl FnMut(CanFrame)) {
        let n = self.bank.len();
        self.bank
            .tick(now_us, &self.targets[..n], &mut |f| push(to_dbc(f)));
    }

    /// Quick stop with zeroed targets for every drive and the SYNC that applies it, at once.
    pub(super) fn stop_frames(&mut self, mut push: impl FnMut(CanFrame)) {
        self.targets = [Target::Stop; N_FINGERS];
        self.bank.stop_frames(&mut |f| push(to_dbc(f)));
    }

    /// `arm`: every faulted drive starts from scratch.
    pub(super) fn arm(&mut self) -> usize {
        self.bank.arm()
    }

    /// The bus came back: every drive is read and configured again on `arm`.
    pub(super) fn bus_recovered(&mut self) {
        self.bank.bus_recovered();
    }

    /// Finger `f`'s fed-back fingertip force (N) from its drive's torque actual.
    pub(super) fn force_n(&self, f: usize) -> Option<f64> {
        let (_, scaling) = self.slot[f]?;
        match self.status(f)? {
            DriveStatus::Running {
                feedback: Some(fb), ..
            } => Some(scaling.force_n(fb.torque_permille)),
            _ => None,
        }
    }

    /// Finger `f`'s drive reports an internal limit (statusword bit 11): the joint pushes into
    /// a stop, as FINGER_STATUS bit 5 says for a native finger.
    pub(super) fn at_limit(&self, f: usize) -> bool {
        matches!(
            self.status(f),
            Some(DriveStatus::Running { feedback: Some(fb), .. })
                if fb.statusword.0 & hand_canopen::Statusword::INTERNAL_LIMIT != 0
        )
    }
}

/// Whether `table` makes a bank at this tick (the config's checks plus the bank's own: the
/// SYNC period must fit 0x60C2). handd and `--check` call it before building the engine.
pub fn check_drives(table: &DriveTable, tick_us: u64) -> Result<(), String> {
    Drives::try_new(table, tick_us).map(|_| ())
}

#[cfg(test)]
mod cob_id_set_tests {
    use super::CobIdSet;

    #[test]
    fn holds_exactly_the_ids_put_in() {
        let ids = [0x000, 0x07F, 0x085, 0x185, 0x705, 0x7FF];
        let mut set = CobIdSet::default();
        for id in ids {
            set.insert(id);
        }
        for id in 0..4096u32 {
            assert_eq!(set.contains(id), ids.contains(&(id as u16)), "id 0x{id:X}");
        }
        assert!(!set.contains(u32::MAX));
    }
}
