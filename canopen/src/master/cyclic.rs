//! The cyclic PDOs of a finger drive as fixed layouts (the mapping [`crate::pdo::finger_pdos`]
//! writes at start-up): RPDO1 = controlword + target, TPDO1 = statusword + torque actual +
//! velocity actual, TPDO2 = position actual. Encoded and decoded without allocation.

use crate::cia402::{Controlword, Mode, Statusword};
use crate::frame::CanFrame;
use crate::ids::{CobId, Function, NodeId};

/// What a tick commands one drive, in the drive's units (per mille of rated torque in CST,
/// rpm in CSV and PV).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Target {
    /// Follow this target (Operation enabled; the bank walks the drive there first).
    Run(i32),
    /// Quick stop with the target zeroed: handd's SAFE_STOP for a CiA 402 finger.
    Stop,
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

/// RPDO1 (0x200 + node) carrying `cw` and `target`: 16-bit target torque in CST, 32-bit target
/// velocity otherwise. A CST target outside i16 saturates.
pub fn rpdo1(node: NodeId, mode: Mode, cw: Controlword, target: i32) -> CanFrame {
    let id = CobId::of(Function::Rpdo(1), node).map_or(0x200, CobId::raw);
    let mut d = [0u8; 8];
    d[..2].copy_from_slice(&cw.0.to_le_bytes());
    let len = match mode {
        Mode::CyclicSyncTorque => {
            let t = target.clamp(i32::from(i16::MIN), i32::from(i16::MAX)) as i16;
            d[2..4].copy_from_slice(&t.to_le_bytes());
            4
        }
        Mode::CyclicSyncVelocity | Mode::ProfileVelocity => {
            d[2..6].copy_from_slice(&target.to_le_bytes());
            6
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
            for (cw, target) in [(0x000F_u16, -300_i32), (0x0002, 0), (0x0080, 1234)] {
                let ours = rpdo1(node(), mode, Controlword(cw), target);
                let general = rx
                    .encode(&[u32::from(cw), target as u32])
                    .expect("two entries");
                assert_eq!(ours, general, "{mode:?} cw {cw:#06x} target {target}");
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

    #[test]
    fn a_cst_target_beyond_i16_saturates_rather_than_wrapping() {
        let f = rpdo1(node(), Mode::CyclicSyncTorque, Controlword(0x0F), 40_000);
        assert_eq!(&f.payload()[2..4], &i16::MAX.to_le_bytes());
        let f = rpdo1(node(), Mode::CyclicSyncTorque, Controlword(0x0F), -40_000);
        assert_eq!(&f.payload()[2..4], &i16::MIN.to_le_bytes());
    }

    #[test]
    fn a_short_tpdo1_is_not_feedback() {
        let f = CanFrame::new(0x189, &[0x27, 0x06, 0, 0]).expect("valid");
        assert!(decode_tpdo1(&f, 0).is_none());
    }
}
