//! The cyclic PDOs of a finger drive as fixed layouts (the mapping [`crate::pdo::finger_pdos`]
//! writes at start-up): RPDO1 = controlword + target (+ max torque in the velocity modes),
//! TPDO1 = statusword + torque actual + velocity actual, TPDO2 = position actual. Encoded and
//! decoded without allocation.

use crate::cia402::{Controlword, Mode, Statusword};
use crate::frame::CanFrame;
use crate::ids::{CobId, Function, NodeId};

/// Max torque (0x6072, UNSIGNED16), per mille of rated torque: in CSV and PV the torque the
/// drive's velocity loop may use, sent with the target each tick (the force-limited velocity
/// of the native controller). Not sent in CST, whose target is the torque itself.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct TorqueLimit(pub u16);

impl TorqueLimit {
    /// No torque: what a stopped or not yet enabled drive gets.
    pub const ZERO: Self = Self(0);
}

/// What a tick commands one drive, in the drive's units (per mille of rated torque in CST,
/// rpm in CSV and PV).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Target {
    /// Follow this target (Operation enabled; the bank walks the drive there first).
    Run {
        /// 0x6071 in CST, 0x60FF in CSV and PV.
        value: i32,
        /// 0x6072 in CSV and PV (ignored in CST).
        max_torque: TorqueLimit,
    },
    /// Quick stop with the target and the torque limit zeroed: handd's SAFE_STOP for a CiA 402
    /// finger.
    Stop,
}

impl Target {
    /// `Run` with no torque limit to speak of ([`TorqueLimit::ZERO`]): a CST target.
    pub const fn torque(permille: i32) -> Self {
        Self::Run {
            value: permille,
            max_torque: TorqueLimit::ZERO,
        }
    }

    /// `Run` with a velocity target (rpm) and its torque limit: a CSV or PV target.
    pub const fn velocity(rpm: i32, max_torque: TorqueLimit) -> Self {
        Self::Run {
            value: rpm,
            max_torque,
        }
    }
}

/// What one RPDO1 carries besides its controlword.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Setpoint {
    /// 0x6071 in CST (saturated to i16), 0x60FF in CSV and PV.
    pub value: i32,
    /// 0x6072 in CSV and PV.
    pub max_torque: TorqueLimit,
}

impl Setpoint {
    /// Target and torque limit zeroed: the quick stop's, and a drive's being walked back to
    /// Operation enabled.
    pub const ZERO: Self = Self {
        value: 0,
        max_torque: TorqueLimit::ZERO,
    };
}

/// The newest TPDO1 of a drive and when it arrived.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Feedback {
    /// 0x6041.
    pub statusword: Statusword,
    /// 0x6077, per mille of rated torque.
    pub torque_permille: i16,
    /// 0x606C, rpm at the motor.
    pub velocity_rpm: i32,
    /// The caller's clock when it arrived, us.
    pub at_us: u64,
}

/// RPDO1 (0x200 + node) carrying `cw` and `sp`: in CST the 16-bit target torque (4 bytes), in
/// CSV and PV the 32-bit target velocity and the 16-bit max torque (8 bytes). A CST target
/// outside i16 saturates.
pub fn rpdo1(node: NodeId, mode: Mode, cw: Controlword, sp: Setpoint) -> CanFrame {
    let id = CobId::of(Function::Rpdo(1), node).map_or(0x200, CobId::raw);
    let mut d = [0u8; 8];
    d[..2].copy_from_slice(&cw.0.to_le_bytes());
    let len = match mode {
        Mode::CyclicSyncTorque => {
            let t = sp.value.clamp(i32::from(i16::MIN), i32::from(i16::MAX)) as i16;
            d[2..4].copy_from_slice(&t.to_le_bytes());
            4
        }
        Mode::CyclicSyncVelocity | Mode::ProfileVelocity => {
            d[2..6].copy_from_slice(&sp.value.to_le_bytes());
            d[6..8].copy_from_slice(&sp.max_torque.0.to_le_bytes());
            8
        }
    };
    CanFrame::from_parts(id, len, d)
}

/// Whether `f` is `node`'s TPDO1.
pub fn is_tpdo1_of(f: &CanFrame, node: NodeId) -> bool {
    CobId::of(Function::Tpdo(1), node).is_some_and(|c| c.raw() == f.cob_id())
}

/// TPDO1's values, if `f` has its 8 bytes.
pub fn decode_tpdo1(f: &CanFrame, now_us: u64) -> Option<Feedback> {
    let p = f.payload();
    if p.len() != 8 {
        return None;
    }
    Some(Feedback {
        statusword: Statusword(u16::from_le_bytes([p[0], p[1]])),
        torque_permille: i16::from_le_bytes([p[2], p[3]]),
        velocity_rpm: i32::from_le_bytes([p[4], p[5], p[6], p[7]]),
        at_us: now_us,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pdo::{finger_pdos, Direction};

    fn node() -> NodeId {
        NodeId::try_new(9).expect("in range")
    }

    /// The fixed layouts agree with the mapping start-up writes (the general PDO codec).
    #[test]
    fn fixed_layouts_agree_with_the_mapping_written_at_start_up() {
        for mode in [
            Mode::CyclicSyncTorque,
            Mode::CyclicSyncVelocity,
            Mode::ProfileVelocity,
        ] {
            let pdos = finger_pdos(node(), mode);
            let rx = pdos
                .iter()
                .find(|p| p.direction == Direction::Rx && p.number == 1)
                .expect("RPDO1");
            for (cw, value, limit) in [
                (0x000F_u16, -300_i32, 450_u16),
                (0x0002, 0, 0),
                (0x0080, 1234, u16::MAX),
            ] {
                let sp = Setpoint {
                    value,
                    max_torque: TorqueLimit(limit),
                };
                let ours = rpdo1(node(), mode, Controlword(cw), sp);
                let values: &[u32] = match mode {
                    Mode::CyclicSyncTorque => &[u32::from(cw), value as u32],
                    _ => &[u32::from(cw), value as u32, u32::from(limit)],
                };
                let general = rx.encode(values).expect("one value per entry");
                assert_eq!(ours, general, "{mode:?} cw {cw:#06x} {sp:?}");
                let masked: Vec<u32> = rx
                    .entries
                    .iter()
                    .zip(values)
                    .map(|(e, v)| v & (u32::MAX >> (32 - u32::from(e.bits))))
                    .collect();
                assert_eq!(rx.decode(&ours).expect("its own length"), masked);
            }
            let tx = pdos
                .iter()
                .find(|p| p.direction == Direction::Tx && p.number == 1)
                .expect("TPDO1");
            let f = tx
                .encode(&[0x0627, (-512_i16) as u16 as u32, (-70_000_i32) as u32])
                .expect("three entries");
            assert!(is_tpdo1_of(&f, node()));
            let fb = decode_tpdo1(&f, 77).expect("8 bytes");
            assert_eq!(fb.statusword, Statusword(0x0627));
            assert_eq!(fb.torque_permille, -512);
            assert_eq!(fb.velocity_rpm, -70_000);
            assert_eq!(fb.at_us, 77);
        }
    }

    fn sp(value: i32, limit: u16) -> Setpoint {
        Setpoint {
            value,
            max_torque: TorqueLimit(limit),
        }
    }

    #[test]
    fn a_cst_target_beyond_i16_saturates_rather_than_wrapping() {
        let f = rpdo1(
            node(),
            Mode::CyclicSyncTorque,
            Controlword(0x0F),
            sp(40_000, 0),
        );
        assert_eq!(&f.payload()[2..4], &i16::MAX.to_le_bytes());
        let f = rpdo1(
            node(),
            Mode::CyclicSyncTorque,
            Controlword(0x0F),
            sp(-40_000, 0),
        );
        assert_eq!(&f.payload()[2..4], &i16::MIN.to_le_bytes());
    }

    /// CSV and PV: controlword, target velocity, max torque, little-endian, 8 bytes on 0x200 +
    /// node; CST: controlword and target torque, 4 bytes, the limit not sent.
    #[test]
    fn the_velocity_modes_carry_the_torque_limit_after_the_target() {
        for mode in [Mode::CyclicSyncVelocity, Mode::ProfileVelocity] {
            let f = rpdo1(node(), mode, Controlword(0x000F), sp(-70_000, 0x01F4));
            assert_eq!(f.cob_id(), 0x209, "{mode:?}");
            let v = (-70_000_i32).to_le_bytes();
            assert_eq!(
                f.payload(),
                &[0x0F, 0x00, v[0], v[1], v[2], v[3], 0xF4, 0x01],
                "{mode:?}"
            );
        }
        let f = rpdo1(
            node(),
            Mode::CyclicSyncTorque,
            Controlword(0x000F),
            sp(-300, 0x01F4),
        );
        assert_eq!(f.payload(), &[0x0F, 0x00, 0xD4, 0xFE]);
    }

    #[test]
    fn the_target_constructors_put_the_limit_where_the_mode_reads_it() {
        assert_eq!(
            Target::torque(250),
            Target::Run {
                value: 250,
                max_torque: TorqueLimit::ZERO
            }
        );
        assert_eq!(
            Target::velocity(-1200, TorqueLimit(300)),
            Target::Run {
                value: -1200,
                max_torque: TorqueLimit(300)
            }
        );
        assert_eq!(Setpoint::ZERO, sp(0, 0));
    }

    #[test]
    fn a_short_tpdo1_is_not_feedback() {
        let f = CanFrame::new(0x189, &[0x27, 0x06, 0, 0]).expect("valid");
        assert!(decode_tpdo1(&f, 0).is_none());
    }
}
