//! The worst-case bus load a configuration plans, before anything runs (`handd --check` prints
//! it): hand.dbc's messages at their DBC rates ([`hand_dbc::busload`]), each finger's
//! FINGER_SETPOINT once per tick, and for a finger on a CiA 402 drive its drive's traffic in place
//! of its FINGER_SETPOINT and FINGER_STATUS:
//! - per tick, its RPDO1 (controlword and target: 4 bytes in torque mode; controlword, target
//!   and max torque: 8 bytes in velocity modes);
//! - on each SYNC (one per tick), its TPDO1 (statusword, torque, velocity: 8 bytes) and TPDO2
//!   (position: 4 bytes), as [`hand_canopen::pdo::finger_pdos`] maps them;
//! - its heartbeat, once per tick (0x1017 is the tick: [`crate::engine::bank_settings`]);
//! - and once per tick for all drives, handd's SYNC (no data) and its CANopen heartbeat.
//!
//! Every frame counts hand.dbc's worst-case bits (bit stuffing included), so the figure is an
//! upper bound, comparable with the design's 50 % limit. The start-up's SDO traffic is left out:
//! it ends before any drive is enabled.

use std::fmt;

use hand_canopen::pdo::{finger_pdos, Direction};
use hand_dbc::busload::{bus_load, frame_bits_worst_case, BITRATE_BPS, MAX_LOAD};
use hand_dbc::messages::{FingerSetpoint, FingerStatus};

use crate::drive_config::{Drive, Drives};
use crate::units::N_FINGERS;

/// One kind of frame on the planned bus.
#[derive(Debug, Clone, PartialEq)]
pub struct PlannedRow {
    /// What it is (a hand.dbc message's name, or the CANopen frame and its node).
    pub what: String,
    /// Frames per second.
    pub frames_per_s: f64,
    /// Worst-case bits per frame.
    pub bits_per_frame: u64,
    /// True for the CiA 402 drives' traffic (handd's SYNC and heartbeat included).
    pub canopen: bool,
}

impl PlannedRow {
    /// Worst-case bits per second.
    pub fn bits_per_s(&self) -> f64 {
        self.frames_per_s * self.bits_per_frame as f64
    }
}

/// The planned bus: every kind of frame.
#[derive(Debug, Clone, PartialEq)]
pub struct PlannedLoad {
    /// The rows, hand.dbc's first.
    pub rows: Vec<PlannedRow>,
    /// The tick, µs.
    pub tick_us: u64,
}

impl PlannedLoad {
    /// Worst-case bits per second in all.
    pub fn bits_per_s(&self) -> f64 {
        self.rows.iter().map(PlannedRow::bits_per_s).sum()
    }

    /// The load as a fraction of the bus's 1 Mbit/s.
    pub fn load(&self) -> f64 {
        self.bits_per_s() / BITRATE_BPS
    }

    /// The CiA 402 drives' share as a fraction of the bus.
    pub fn canopen_load(&self) -> f64 {
        self.rows
            .iter()
            .filter(|r| r.canopen)
            .map(PlannedRow::bits_per_s)
            .sum::<f64>()
            / BITRATE_BPS
    }

    /// Whether it stays within the design's limit (half the bus).
    pub fn within_limit(&self) -> bool {
        self.load() <= MAX_LOAD
    }
}

impl fmt::Display for PlannedLoad {
    /// One line: the total, the drives' share, the limit.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "worst-case bus load {:.1}% of {:.0} Mbit/s ({:.0} bit/s) at a {} ms tick",
            self.load() * 100.0,
            BITRATE_BPS / 1e6,
            self.bits_per_s(),
            self.tick_us / 1000
        )?;
        if self.rows.iter().any(|r| r.canopen) {
            write!(
                f,
                ", of which the CiA 402 drives {:.1}%",
                self.canopen_load() * 100.0
            )?;
        }
        if self.within_limit() {
            write!(f, " (limit {:.0}%)", MAX_LOAD * 100.0)
        } else {
            write!(
                f,
                " !! OVER the design's {:.0}% limit: a longer tick{}",
                MAX_LOAD * 100.0,
                if self.canopen_load() > 0.0 {
                    " or fewer drives"
                } else {
                    ""
                }
            )
        }
    }
}

/// The load `drives` plans at a tick of `tick_us`.
pub fn planned_load(drives: &Drives, tick_us: u64) -> PlannedLoad {
    let per_tick = 1e6 / tick_us.max(1) as f64;
    let is_drive = |f: usize| matches!(drives.fingers[f], Drive::Cia402 { .. });
    let mut rows = Vec::new();
    for r in bus_load().0 {
        let setpoint = FingerSetpoint::instance_of(r.id);
        let status = FingerStatus::instance_of(r.id);
        if setpoint.or(status).is_some_and(is_drive) {
            continue;
        }
        rows.push(PlannedRow {
            what: r.name.to_string(),
            // handd sends each setpoint once per tick, whatever hand.dbc's cycle time says.
            frames_per_s: if setpoint.is_some() {
                per_tick
            } else {
                r.frames_per_s
            },
            bits_per_frame: r.bits_per_frame,
            canopen: false,
        });
    }
    for f in 0..N_FINGERS {
        let Drive::Cia402 { node, mode, .. } = drives.fingers[f] else {
            continue;
        };
        for pdo in finger_pdos(node, mode).iter().filter(|p| p.enabled()) {
            let kind = match pdo.direction {
                Direction::Rx => "RPDO",
                Direction::Tx => "TPDO",
            };
            rows.push(PlannedRow {
                what: format!("{kind}{} {node}", pdo.number),
                frames_per_s: per_tick,
                // finger_pdos maps at most 64 bits of 16- and 32-bit objects.
                bits_per_frame: frame_bits_worst_case(pdo.byte_len().unwrap_or(8)),
                canopen: true,
            });
        }
        rows.push(PlannedRow {
            what: format!("heartbeat {node}"),
            frames_per_s: per_tick,
            bits_per_frame: frame_bits_worst_case(1),
            canopen: true,
        });
    }
    if let Some((master, _)) = drives.master {
        rows.push(PlannedRow {
            what: "SYNC".into(),
            frames_per_s: per_tick,
            bits_per_frame: frame_bits_worst_case(0),
            canopen: true,
        });
        rows.push(PlannedRow {
            what: format!("heartbeat {master} (handd)"),
            frames_per_s: per_tick,
            bits_per_frame: frame_bits_worst_case(1),
            canopen: true,
        });
    }
    PlannedLoad { rows, tick_us }
}

#[cfg(test)]
mod tests {
    use hand_canopen::cia402::Mode;
    use hand_canopen::scaling::ScalingSettings;
    use hand_canopen::{CobId, NodeId};

    use super::*;

    /// Every finger on a drive in `mode`, nodes 5 to 9, handd node 127, SYNC 0x07F.
    fn five_drives(mode: Mode) -> Drives {
        let scaling = ScalingSettings {
            rated_torque_mnm: 25.0,
            gear_ratio: 64.0,
            moment_arm_m: 0.04,
            max_torque_permille: 1000,
            max_speed_rpm: 8000,
        }
        .validate()
        .expect("scaling");
        Drives {
            fingers: std::array::from_fn(|f| Drive::Cia402 {
                node: NodeId::try_new(5 + f as u8).expect("node"),
                mode,
                scaling,
            }),
            master: Some((
                NodeId::try_new(127).expect("node"),
                CobId::try_new(0x07F).expect("cob-id"),
            )),
        }
    }

    #[test]
    fn native_fingers_at_the_50_ms_tick_plan_hand_dbcs_own_load() {
        let plan = planned_load(&Drives::default(), 50_000);
        let (rows, total) = bus_load();
        assert_eq!(plan.rows.len(), rows.len());
        assert!((plan.load() - total).abs() < 1e-12, "{plan} vs {total}");
        assert_eq!(plan.canopen_load(), 0.0);
        assert!(plan.within_limit(), "{plan}");
        assert!(!plan.to_string().contains("CiA 402"), "{plan}");
    }

    #[test]
    fn five_torque_drives_replace_the_native_setpoints_and_statuses() {
        let plan = planned_load(&five_drives(Mode::CyclicSyncTorque), 50_000);
        for r in &plan.rows {
            assert!(
                !r.what.starts_with("FINGER_SETPOINT") && !r.what.starts_with("FINGER_STATUS"),
                "a drive's finger keeps its native {}",
                r.what
            );
        }
        // By hand, 20 ticks/s: per drive RPDO1 4 bytes (95 bits), TPDO1 8 (135), TPDO2 4 (95),
        // heartbeat 1 (65) = 390 bits per tick, 39,000 bit/s for five; SYNC 55 bits and
        // handd's heartbeat 65 bits per tick, 2,400 bit/s.
        let canopen = plan.canopen_load() * BITRATE_BPS;
        assert!((canopen - 41_400.0).abs() < 1e-6, "{canopen} bit/s");
        let native = planned_load(&Drives::default(), 50_000);
        let replaced: f64 = native
            .rows
            .iter()
            .filter(|r| {
                r.what.starts_with("FINGER_SETPOINT") || r.what.starts_with("FINGER_STATUS")
            })
            .map(PlannedRow::bits_per_s)
            .sum();
        assert!(
            (plan.bits_per_s() - (native.bits_per_s() - replaced + 41_400.0)).abs() < 1e-6,
            "{plan}"
        );
        assert!(plan.within_limit(), "{plan}");
        assert!(
            plan.to_string().contains("of which the CiA 402 drives"),
            "{plan}"
        );
    }

    #[test]
    fn velocity_drives_send_a_longer_rpdo_and_a_10_ms_tick_goes_over_the_limit() {
        let torque = planned_load(&five_drives(Mode::CyclicSyncTorque), 50_000);
        for mode in [Mode::CyclicSyncVelocity, Mode::ProfileVelocity] {
            let velocity = planned_load(&five_drives(mode), 50_000);
            // RPDO1 of 8 bytes (the torque limit too): 47 + 64 + floor(97 / 4) = 135 bits, 40
            // more than the torque mode's 95 per drive and tick.
            let more = velocity.bits_per_s() - torque.bits_per_s();
            assert!((more - 5.0 * 40.0 * 20.0).abs() < 1e-6, "{mode:?}: {more}");
            assert!(velocity.within_limit(), "{velocity}");
        }
        // The README's table: five csv drives at a 50 ms and a 10 ms tick (= SYNC).
        let csv = planned_load(&five_drives(Mode::CyclicSyncVelocity), 50_000);
        assert!((csv.bits_per_s() - 465_550.0).abs() < 1e-6, "{csv}");
        let csv_fast = planned_load(&five_drives(Mode::CyclicSyncVelocity), 10_000);
        assert!(!csv_fast.within_limit(), "{csv_fast}");
        let fast = planned_load(&five_drives(Mode::CyclicSyncTorque), 10_000);
        assert!(!fast.within_limit(), "{fast}");
        assert!(fast.to_string().contains("OVER"), "{fast}");
        assert!(
            (csv_fast.bits_per_s() - fast.bits_per_s() - 5.0 * 40.0 * 100.0).abs() < 1e-6,
            "{csv_fast}"
        );
    }
}
