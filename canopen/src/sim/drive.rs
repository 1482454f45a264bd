//! The simulated CiA 402 drive node: NMT and boot-up, an SDO server over its object
//! dictionary, heartbeat producer and 0x1016 consumer with the 0x6007 reaction, RPDOs
//! applied and TPDOs sent on SYNC, EMCY, and the power state machine.

use super::od::{ObjectDictionary, FINGER_DRIVE_OBJECTS};
use crate::cia402::{objects, transition_for, Controlword, PowerState, Statusword};
use crate::emcy::Emcy;
use crate::frame::CanFrame;
use crate::ids::{CobId, NodeId, ObjectAddr};
use crate::nmt::{ErrorControl, NmtCommand, NmtMessage, NmtState};
use crate::pdo::{Mapped, PDO_INVALID};
use crate::sdo::{AbortCode, SdoReply, SdoRequest};
use crate::sync::is_sync_on;

/// EMCY code for a lost heartbeat (CiA 301).
pub const EMCY_HEARTBEAT: u16 = 0x8130;
/// EMCY code for an RPDO of the wrong length (CiA 301).
pub const EMCY_PDO_LENGTH: u16 = 0x8210;

/// Counters of what the simulated drive did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SimStats {
    /// Quick stops executed (commanded or by the watchdog).
    pub quick_stops: u32,
    /// Times the 0x1016 watchdog fired.
    pub watchdog_trips: u32,
    /// EMCY messages sent.
    pub emcys: u32,
    /// RPDOs refused for their length.
    pub rpdo_length_errors: u32,
    /// RPDOs applied.
    pub rpdos_applied: u32,
    /// TPDOs sent.
    pub tpdos_sent: u32,
}

/// One simulated drive.
#[derive(Clone, Debug)]
pub struct SimDrive {
    node: NodeId,
    od: ObjectDictionary,
    nmt: Option<NmtState>,
    power: PowerState,
    last_cw: Controlword,
    pending_rpdo: Vec<(u8, Vec<u32>)>,
    next_heartbeat_us: u64,
    master_seen_us: Option<u64>,
    tpdo_sync_count: [u8; 4],
    silent: bool,
    stats: SimStats,
}

/// The SYNC COB-ID in 0x1005 (bits 0..10; CiA 301's bit 30 "generates SYNC" is not this
/// node's business).
fn sync_cob_of(raw: u32) -> CobId {
    CobId::try_new((raw & 0x7FF) as u16).unwrap_or(CobId::SYNC)
}

fn addr(index: u16, sub: u8) -> ObjectAddr {
    ObjectAddr::new(index, sub)
}

impl SimDrive {
    /// The COB-ID it takes SYNC on (its 0x1005).
    pub fn sync_cob_id(&self) -> CobId {
        sync_cob_of(self.od.get(addr(0x1005, 0)))
    }

    /// A powered-off drive with the finger drive's dictionary.
    pub fn new(node: NodeId) -> Self {
        Self {
            node,
            od: ObjectDictionary::new(node, FINGER_DRIVE_OBJECTS),
            nmt: None,
            power: PowerState::NotReadyToSwitchOn,
            last_cw: Controlword(0),
            pending_rpdo: Vec::new(),
            next_heartbeat_us: 0,
            master_seen_us: None,
            tpdo_sync_count: [0; 4],
            silent: false,
            stats: SimStats::default(),
        }
    }

    /// A drive that never sends anything (dead, or unpowered).
    pub fn set_silent(&mut self, silent: bool) {
        self.silent = silent;
    }

    /// The NMT state (`None`: powered off).
    pub fn nmt_state(&self) -> Option<NmtState> {
        self.nmt
    }

    /// The power state.
    pub fn power_state(&self) -> PowerState {
        self.power
    }

    /// The object dictionary.
    pub fn od(&self) -> &ObjectDictionary {
        &self.od
    }

    /// The counters.
    pub fn stats(&self) -> SimStats {
        self.stats
    }

    /// Changes 0x6502 (a drive that lists other modes).
    pub fn set_supported_modes(&mut self, modes: u32) {
        self.od.set(addr(objects::SUPPORTED_MODES, 0), modes);
    }

    /// Sets the position actual value (increments), e.g. from a finger model.
    pub fn set_position(&mut self, increments: i32) {
        self.od
            .set(addr(objects::POSITION_ACTUAL, 0), increments as u32);
    }

    /// Powers on: initialisation, boot-up, pre-operational.
    pub fn power_on(&mut self, now_us: u64, out: &mut Vec<CanFrame>) {
        self.od.reset(|_| true);
        self.set_power(PowerState::SwitchOnDisabled);
        self.last_cw = Controlword(0);
        self.boot(now_us, out);
    }

    fn boot(&mut self, now_us: u64, out: &mut Vec<CanFrame>) {
        self.nmt = Some(NmtState::PreOperational);
        self.master_seen_us = None;
        self.pending_rpdo.clear();
        self.tpdo_sync_count = [0; 4];
        self.next_heartbeat_us = now_us;
        self.send(
            out,
            ErrorControl {
                node: self.node,
                state: NmtState::BootUp,
            }
            .frame(),
        );
    }

    fn send(&mut self, out: &mut Vec<CanFrame>, f: CanFrame) {
        if !self.silent {
            out.push(f);
        }
    }

    fn set_power(&mut self, s: PowerState) {
        if s == PowerState::QuickStopActive && self.power != s {
            self.stats.quick_stops += 1;
        }
        self.power = s;
        let sw = Statusword::of(s).0 | Statusword::REMOTE;
        self.od.set(addr(objects::STATUSWORD, 0), u32::from(sw));
        if s != PowerState::OperationEnabled {
            self.od.set(addr(objects::TORQUE_ACTUAL, 0), 0);
            self.od.set(addr(objects::VELOCITY_ACTUAL, 0), 0);
        }
    }

    /// A drive fault: EMCY with `code`, then Fault.
    pub fn inject_fault(&mut self, code: u16, out: &mut Vec<CanFrame>) {
        self.set_power(PowerState::FaultReactionActive);
        self.set_power(PowerState::Fault);
        self.od.set(addr(0x603F, 0), u32::from(code));
        self.emcy(code, 0x01, out);
    }

    fn emcy(&mut self, code: u16, register: u8, out: &mut Vec<CanFrame>) {
        self.od.set(addr(0x1001, 0), u32::from(register));
        self.stats.emcys += 1;
        let f = Emcy {
            node: self.node,
            code,
            register,
            vendor: [0; 5],
        }
        .frame();
        self.send(out, f);
    }

    fn apply_controlword(&mut self, cw: Controlword) {
        if let Some(t) = transition_for(self.power, self.last_cw, cw) {
            self.set_power(t.to);
        }
        self.last_cw = cw;
    }

    /// Offers a frame from the bus.
    pub fn on_frame(&mut self, f: &CanFrame, now_us: u64, out: &mut Vec<CanFrame>) {
        let Some(nmt) = self.nmt else { return };
        let id = f.cob_id();
        if id == 0 {
            if let Ok(m) = NmtMessage::decode(f) {
                if m.addresses(self.node) {
                    self.on_nmt(m.command, now_us, out);
                }
            }
        } else if is_sync_on(f, self.sync_cob_id()) {
            if nmt == NmtState::Operational {
                self.on_sync(out);
            }
        } else if id == 0x600 + u16::from(self.node.get()) {
            if nmt != NmtState::Stopped {
                self.on_sdo(f, out);
            }
        } else if let Ok(ec) = ErrorControl::decode(f) {
            let watch = self.od.get(addr(0x1016, 1));
            if watch != 0 && u32::from(ec.node.get()) == (watch >> 16) & 0x7F {
                self.master_seen_us = Some(now_us);
            }
        } else if nmt == NmtState::Operational {
            self.on_rpdo(f, out);
        }
    }

    fn on_nmt(&mut self, c: NmtCommand, now_us: u64, out: &mut Vec<CanFrame>) {
        match c {
            NmtCommand::Start => self.nmt = Some(NmtState::Operational),
            NmtCommand::Stop => self.nmt = Some(NmtState::Stopped),
            NmtCommand::PreOperational => self.nmt = Some(NmtState::PreOperational),
            NmtCommand::ResetNode => self.power_on(now_us, out),
            NmtCommand::ResetCommunication => {
                self.od.reset(|d| (0x1000..0x2000).contains(&d.addr.index));
                self.boot(now_us, out);
            }
        }
    }

    fn on_sdo(&mut self, f: &CanFrame, out: &mut Vec<CanFrame>) {
        let reply = match SdoRequest::decode(f, self.node) {
            Ok(SdoRequest::Upload(a)) => match self.od.read(a) {
                Ok(d) => SdoReply::Uploaded(a, d),
                Err(code) => SdoReply::Abort(a, code),
            },
            Ok(SdoRequest::Download(a, data)) => match self.write(a, data) {
                Ok(()) => SdoReply::Downloaded(a),
                Err(code) => SdoReply::Abort(a, code),
            },
            Ok(SdoRequest::Abort(..)) => return,
            Err(_) => {
                let p = f.payload();
                let a = match p {
                    [_, i0, i1, s, ..] => ObjectAddr::new(u16::from_le_bytes([*i0, *i1]), *s),
                    _ => ObjectAddr::new(0, 0),
                };
                SdoReply::Abort(a, AbortCode::InvalidCommand)
            }
        };
        let f = reply.frame(self.node);
        self.send(out, f);
    }

    /// An SDO download with the drive's own rules on top of access and length.
    fn write(&mut self, a: ObjectAddr, data: crate::sdo::SdoData) -> Result<(), AbortCode> {
        let raw = self.od.check_write(a, data)?;
        match a.index {
            0x1400..=0x1403 | 0x1800..=0x1803 if a.sub == 1 => {
                let old = self.od.get(a);
                if old & PDO_INVALID == 0 && raw & PDO_INVALID == 0 && old != raw {
                    return Err(AbortCode::InvalidValue);
                }
            }
            0x1600..=0x1603 | 0x1A00..=0x1A03 => self.check_mapping(a, raw)?,
            objects::MODES_OF_OPERATION => {
                let mode = data.as_i32();
                let supported = self.od.get(addr(objects::SUPPORTED_MODES, 0));
                if !(1..=32).contains(&mode) || supported & (1 << (mode - 1)) == 0 {
                    return Err(AbortCode::InvalidValue);
                }
                self.od.set(addr(objects::MODES_DISPLAY, 0), raw);
            }
            _ => {}
        }
        self.od.set(a, raw);
        if a == addr(objects::CONTROLWORD, 0) {
            self.apply_controlword(Controlword(raw as u16));
        }
        Ok(())
    }

    fn check_mapping(&self, a: ObjectAddr, raw: u32) -> Result<(), AbortCode> {
        let comm = addr(a.index - 0x200, 1);
        if self.od.get(comm) & PDO_INVALID == 0 {
            return Err(AbortCode::CannotStoreState);
        }
        if a.sub == 0 {
            if raw > 4 {
                return Err(AbortCode::ValueHigh);
            }
            let mut bits = 0;
            for k in 1..=raw as u8 {
                let m = Mapped::from_raw(self.od.get(addr(a.index, k)));
                let def = self.od.def(m.addr).map_err(|_| AbortCode::NotMappable)?;
                if !def.mappable || u32::from(m.bits) != 8 * u32::from(def.bytes) {
                    return Err(AbortCode::NotMappable);
                }
                bits += u32::from(m.bits);
            }
            if bits > 64 {
                return Err(AbortCode::PdoLength);
            }
        } else if self.od.get(addr(a.index, 0)) != 0 {
            return Err(AbortCode::CannotStoreState);
        }
        Ok(())
    }

    fn mapping(&self, map_index: u16) -> Vec<Mapped> {
        let count = self.od.get(addr(map_index, 0)) as u8;
        (1..=count)
            .map(|k| Mapped::from_raw(self.od.get(addr(map_index, k))))
            .collect()
    }

    fn on_rpdo(&mut self, f: &CanFrame, out: &mut Vec<CanFrame>) {
        for k in 0..4u8 {
            let cob = self.od.get(addr(0x1400 + u16::from(k), 1));
            if cob & PDO_INVALID != 0 || cob & 0x7FF != u32::from(f.cob_id()) {
                continue;
            }
            let entries = self.mapping(0x1600 + u16::from(k));
            let len: usize = entries.iter().map(|e| usize::from(e.bits / 8)).sum();
            let p = f.payload();
            if p.len() != len {
                self.stats.rpdo_length_errors += 1;
                self.emcy(EMCY_PDO_LENGTH, 0x10, out);
                return;
            }
            let mut at = 0;
            let mut values = Vec::with_capacity(entries.len());
            for e in &entries {
                let n = usize::from(e.bits / 8);
                let mut b = [0u8; 4];
                b[..n].copy_from_slice(&p[at..at + n]);
                values.push(u32::from_le_bytes(b));
                at += n;
            }
            let ttype = self.od.get(addr(0x1400 + u16::from(k), 2));
            self.pending_rpdo.retain(|(n, _)| *n != k);
            self.pending_rpdo.push((k, values));
            if ttype > 240 {
                self.apply_rpdos();
            }
            return;
        }
    }

    fn apply_rpdos(&mut self) {
        for (k, values) in core::mem::take(&mut self.pending_rpdo) {
            let entries = self.mapping(0x1600 + u16::from(k));
            for (e, v) in entries.iter().zip(values) {
                if e.addr == addr(objects::CONTROLWORD, 0) {
                    self.od.set(e.addr, v);
                    self.apply_controlword(Controlword(v as u16));
                } else {
                    self.od.set(e.addr, v);
                }
            }
            self.stats.rpdos_applied += 1;
        }
    }

    /// The drive's plant, trivially: in Operation enabled the actual torque or velocity
    /// follows its target (a finger model can set the position).
    fn follow_targets(&mut self) {
        if self.power != PowerState::OperationEnabled {
            return;
        }
        match self.od.get_i32(addr(objects::MODES_DISPLAY, 0)) {
            10 => {
                let t = self.od.get(addr(objects::TARGET_TORQUE, 0));
                self.od.set(addr(objects::TORQUE_ACTUAL, 0), t);
            }
            3 | 9 => {
                let v = self.od.get(addr(objects::TARGET_VELOCITY, 0));
                self.od.set(addr(objects::VELOCITY_ACTUAL, 0), v);
            }
            _ => {}
        }
    }

    fn on_sync(&mut self, out: &mut Vec<CanFrame>) {
        self.apply_rpdos();
        self.follow_targets();
        for k in 0..4u8 {
            let cob = self.od.get(addr(0x1800 + u16::from(k), 1));
            let ttype = self.od.get(addr(0x1800 + u16::from(k), 2)) as u8;
            if cob & PDO_INVALID != 0 || ttype > 240 {
                continue;
            }
            let c = &mut self.tpdo_sync_count[usize::from(k)];
            *c += 1;
            if *c < ttype.max(1) {
                continue;
            }
            *c = 0;
            let mut d = [0u8; 8];
            let mut at = 0;
            for e in self.mapping(0x1A00 + u16::from(k)) {
                let n = usize::from(e.bits / 8);
                if at + n > 8 {
                    break;
                }
                d[at..at + n].copy_from_slice(&self.od.get(e.addr).to_le_bytes()[..n]);
                at += n;
            }
            let f = CanFrame::from_parts((cob & 0x7FF) as u16, at, d);
            self.stats.tpdos_sent += 1;
            self.send(out, f);
        }
    }

    /// Advances time: heartbeat production, the 0x1016 watchdog, the quick stop ramp.
    pub fn poll(&mut self, now_us: u64, out: &mut Vec<CanFrame>) {
        let Some(nmt) = self.nmt else { return };
        let period_ms = self.od.get(addr(0x1017, 0));
        if period_ms > 0 && now_us >= self.next_heartbeat_us {
            self.next_heartbeat_us = now_us + u64::from(period_ms) * 1000;
            let f = ErrorControl {
                node: self.node,
                state: nmt,
            }
            .frame();
            self.send(out, f);
        }
        let watch = self.od.get(addr(0x1016, 1));
        let timeout_us = u64::from(watch & 0xFFFF) * 1000;
        if let Some(seen) = self.master_seen_us {
            if timeout_us > 0 && now_us.saturating_sub(seen) > timeout_us {
                self.master_seen_us = None;
                self.on_master_lost(out);
            }
        }
        // The quick stop ramp takes no time here; options 0..=4 then disable the drive.
        if self.power == PowerState::QuickStopActive
            && (0..=4).contains(&self.od.get_i32(addr(objects::QUICK_STOP_OPTION, 0)))
        {
            self.set_power(PowerState::SwitchOnDisabled);
        }
    }

    fn on_master_lost(&mut self, out: &mut Vec<CanFrame>) {
        self.stats.watchdog_trips += 1;
        self.emcy(EMCY_HEARTBEAT, 0x11, out);
        match self.od.get_i32(addr(objects::ABORT_CONNECTION, 0)) {
            1 => {
                self.set_power(PowerState::FaultReactionActive);
                self.set_power(PowerState::Fault);
            }
            2 => self.set_power(PowerState::SwitchOnDisabled),
            3 if self.power == PowerState::OperationEnabled => {
                self.set_power(PowerState::QuickStopActive)
            }
            _ => {}
        }
    }
}
