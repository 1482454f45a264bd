//! The CiA 402 drives as the bus shows them, for the bus and log sources (the daemon source
//! has handd's own view of them in its subscription).
//!
//! Which node drives which finger is handd's config (`[fingers.NAME.drive]`): the monitor
//! reads it (`--config`, or the default file when it exists) and follows each drive's own
//! frames, as far as they carry it:
//! - its heartbeat (0x700 + node): the NMT state; none for [`HEARTBEAT_STALE_US`]: silent;
//! - its TPDO1 (0x180 + node, statusword first): the CiA 402 power state and the feedback's age;
//! - its EMCY (0x080 + node): the newest error, until the drive sends an error reset (code 0)
//!   or boots again.
//!
//! A drive faulted on the bus (silent, an EMCY in force, the power state Fault) is marked
//! faulted; what handd decided about it (latched until `arm`) only the daemon source shows.

use driver::drive_config::{Drive, Drives};
use driver::protocol::DriveLine;
use hand_canopen::nmt::ErrorControl;
use hand_canopen::{CanFrame, Emcy, NmtState, NodeId, PowerState, Statusword};
use hand_dbc::hand::{FINGER_NAMES, N_FINGERS};

/// A drive whose heartbeat is older than this is shown silent, µs (handd's drives beat every
/// 50 ms by default; a few periods missed is a drive gone, or a bus that does not reach it).
pub const HEARTBEAT_STALE_US: u64 = 500_000;

/// What the bus said of one drive.
#[derive(Debug, Clone, Copy)]
struct Seen {
    finger: usize,
    node: NodeId,
    nmt: Option<(NmtState, u64)>,
    statusword: Option<(Statusword, u64)>,
    emcy: Option<Emcy>,
}

/// Every CiA 402 finger's drive, from its frames (see the module docs).
#[derive(Debug, Clone, Default)]
pub struct BusDrives {
    drives: Vec<Seen>,
}

impl BusDrives {
    /// The drives of handd's config (none when every finger is native).
    pub fn of(config: &Drives) -> Self {
        let drives = (0..N_FINGERS)
            .filter_map(|finger| match config.fingers[finger] {
                Drive::Cia402 { node, .. } => Some(Seen {
                    finger,
                    node,
                    nmt: None,
                    statusword: None,
                    emcy: None,
                }),
                Drive::Native => None,
            })
            .collect();
        Self { drives }
    }

    /// Whether no finger has a drive.
    pub fn is_empty(&self) -> bool {
        self.drives.is_empty()
    }

    /// Takes a standard frame received at `t_us`; true if it was one of a drive's.
    pub fn on_frame(&mut self, id: u32, data: &[u8], t_us: u64) -> bool {
        let Some(f) = u16::try_from(id)
            .ok()
            .and_then(|id| CanFrame::new(id, data))
        else {
            return false;
        };
        let (base, node) = (f.cob_id() & 0x780, (f.cob_id() & 0x7F) as u8);
        let Some(d) = self.drives.iter_mut().find(|d| d.node.get() == node) else {
            return false;
        };
        match base {
            0x700 => {
                if let Ok(ec) = ErrorControl::decode(&f) {
                    if ec.is_boot_up() {
                        d.emcy = None;
                        d.statusword = None;
                    }
                    d.nmt = Some((ec.state, t_us));
                }
            }
            0x180 => {
                if let [lo, hi, ..] = f.payload() {
                    d.statusword = Some((Statusword(u16::from_le_bytes([*lo, *hi])), t_us));
                }
            }
            0x080 => {
                if let Ok(e) = Emcy::decode(&f) {
                    d.emcy = (!e.is_reset()).then_some(e);
                }
            }
            _ => return false,
        }
        true
    }

    /// Every drive's line at `t_us`.
    pub fn lines(&self, t_us: u64) -> Vec<DriveLine> {
        self.drives.iter().map(|d| d.line(t_us)).collect()
    }
}

impl Seen {
    fn line(&self, t_us: u64) -> DriveLine {
        let silent_for = match self.nmt {
            Some((_, at)) => t_us.saturating_sub(at),
            None => u64::MAX,
        };
        let silent = silent_for > HEARTBEAT_STALE_US;
        let power = self.statusword.map(|(sw, _)| sw.state());
        let faulted_power = matches!(
            power,
            Some(Some(PowerState::Fault | PowerState::FaultReactionActive))
        );
        let nmt = match self.nmt {
            _ if silent => "silent",
            Some((NmtState::BootUp, _)) => "boot-up",
            Some((NmtState::PreOperational, _)) => "pre-operational",
            Some((NmtState::Operational, _)) => "operational",
            Some((NmtState::Stopped, _)) => "stopped",
            None => "silent",
        };
        let state = if let Some(e) = &self.emcy {
            format!("EMCY 0x{:04X} ({}) in force", e.code, e.meaning())
        } else if silent && self.nmt.is_none() {
            "no heartbeat seen".to_owned()
        } else if silent {
            format!("no heartbeat for {} ms", silent_for / 1000)
        } else {
            match power {
                Some(Some(p)) => format!("{p}, NMT {nmt}"),
                Some(None) => format!("statusword outside the CiA 402 table, NMT {nmt}"),
                None => format!("NMT {nmt}, no TPDO1 yet"),
            }
        };
        DriveLine {
            finger: FINGER_NAMES[self.finger].into(),
            node: self.node.get(),
            state,
            faulted: silent || faulted_power || self.emcy.is_some(),
            nmt: nmt.into(),
            power_state: power.map(|p| p.map_or("unknown".into(), |p| p.to_string())),
            feedback_age_ms: self
                .statusword
                .map(|(_, at)| t_us.saturating_sub(at) / 1000),
            emcy: self
                .emcy
                .map(|e| format!("0x{:04X} {}", e.code, e.meaning())),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use driver::config::Config;

    /// handd's config with the index on node 6 and the ring on node 9, both cia402.
    fn drives() -> BusDrives {
        use driver::drive_config::{DriveConfig, DriveMode, Profile};
        let mut c = Config::default();
        for (finger, node) in [(1, 6), (3, 9)] {
            c.fingers.get_mut(finger).drive = DriveConfig {
                profile: Profile::Cia402,
                node_id: Some(node),
                mode: Some(DriveMode::Cst),
                rated_torque_mnm: Some(25.0),
                gear_ratio: Some(64.0),
                moment_arm_m: Some(0.04),
                max_torque_permille: Some(1000),
                max_speed_rpm: Some(8000),
            };
        }
        BusDrives::of(&c.drives().expect("valid drives"))
    }

    #[test]
    fn each_drive_is_followed_from_its_own_frames() {
        let mut d = drives();
        let lines = d.lines(0);
        assert_eq!(
            lines
                .iter()
                .map(|l| (l.finger.as_str(), l.node))
                .collect::<Vec<_>>(),
            vec![("index", 6), ("ring", 9)]
        );
        assert!(
            lines.iter().all(|l| l.faulted && l.nmt == "silent"),
            "{lines:?}"
        );
        // Heartbeats, then the index's TPDO1 (statusword 0x0637: Operation enabled).
        assert!(d.on_frame(0x706, &[0x05], 1_000));
        assert!(d.on_frame(0x709, &[0x7F], 1_000));
        assert!(d.on_frame(0x186, &[0x37, 0x06, 0, 0, 0, 0, 0, 0], 2_000));
        let l = d.lines(14_000);
        assert!(!l[0].faulted, "{l:?}");
        assert_eq!(l[0].power_state.as_deref(), Some("Operation enabled"));
        assert_eq!(l[0].feedback_age_ms, Some(12));
        assert_eq!(l[0].nmt, "operational");
        assert_eq!(l[1].nmt, "pre-operational");
        assert!(l[1].state.contains("no TPDO1 yet"), "{}", l[1].state);
        // Another node's frames, and hand.dbc's, are not a drive's.
        assert!(!d.on_frame(0x707, &[0x05], 3_000));
        assert!(!d.on_frame(0x100, &[0; 8], 3_000));
        // An EMCY: in force until the drive's error reset.
        assert!(d.on_frame(0x086, &[0x10, 0x23, 0x01, 0, 0, 0, 0, 0], 20_000));
        let l = d.lines(21_000);
        assert!(l[0].faulted, "{l:?}");
        assert_eq!(l[0].emcy.as_deref().map(|e| &e[..6]), Some("0x2310"));
        assert!(d.on_frame(0x086, &[0; 8], 22_000));
        assert!(d.lines(23_000)[0].emcy.is_none());
        // Silent: no heartbeat for longer than the stale time.
        let late = 1_000 + HEARTBEAT_STALE_US + 1;
        let l = d.lines(late);
        assert!(l[0].faulted && l[0].nmt == "silent", "{l:?}");
        assert!(
            l[0].state.starts_with("no heartbeat for "),
            "{}",
            l[0].state
        );
        // A statusword in Fault is a fault.
        assert!(d.on_frame(0x709, &[0x05], late));
        assert!(d.on_frame(0x189, &[0x08, 0x00], late));
        let l = d.lines(late);
        assert_eq!(l[1].power_state.as_deref(), Some("Fault"));
        assert!(l[1].faulted);
        // Every finger native: nothing to show.
        assert!(BusDrives::of(&Drives::default()).is_empty());
    }
}
