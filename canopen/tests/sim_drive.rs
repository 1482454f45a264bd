//! The master core against the simulated CiA 402 drive over an in-memory bus.

mod common;

use common::{node, settings, sync_cob, Bench, DRIVE, MASTER, SYNC_COB};
use hand_canopen::emcy::{Emcy, ErrorClass};
use hand_canopen::pdo::{finger_pdos, Direction};
use hand_canopen::sdo::{SdoClient, SdoError};
use hand_canopen::sim::{EMCY_HEARTBEAT, EMCY_PDO_LENGTH, SIM_SUPPORTED_MODES};
use hand_canopen::startup::{Step, StepFailure, MAX_BOOT_UPS_DURING_STARTUP};
use hand_canopen::{
    AbortCode, Mode, NmtState, ObjectAddr, PowerState, StartupStatus, Statusword, SyncProducer,
};

fn started(mode: Mode) -> Bench {
    let mut b = Bench::new(settings(mode));
    let mut out = Vec::new();
    b.drive.power_on(0, &mut out);
    b.run_startup(2_000_000);
    let status = b.startup.status();
    assert!(
        matches!(status, StartupStatus::Done { .. }),
        "start-up did not finish: {status:?}"
    );
    b
}

#[test]
fn startup_reaches_operation_enabled_with_the_configuration_written() {
    for mode in [Mode::CyclicSyncTorque, Mode::CyclicSyncVelocity] {
        let b = started(mode);
        let StartupStatus::Done {
            identity,
            supported_modes,
        } = b.startup.status()
        else {
            unreachable!("checked by started()")
        };
        assert_eq!(identity.vendor, hand_canopen::sim::od::SIM_VENDOR_ID);
        assert_eq!(supported_modes, SIM_SUPPORTED_MODES);
        assert_eq!(b.drive.power_state(), PowerState::OperationEnabled);
        assert_eq!(b.drive.nmt_state(), Some(NmtState::Operational));
        let od = b.drive.od();
        let s = settings(mode);
        assert_eq!(
            od.get(ObjectAddr::new(0x1016, 1)),
            (u32::from(MASTER) << 16) | u32::from(s.master_heartbeat_timeout_ms)
        );
        assert_eq!(
            od.get_i32(ObjectAddr::new(0x6060, 0)),
            i32::from(mode.value())
        );
        // Every PDO as planned: mapping, COB-ID and validity.
        for p in finger_pdos(node(DRIVE), mode) {
            for w in p.expected() {
                assert_eq!(od.get(w.addr), w.data.as_u32(), "{} of {:?}", w.addr, p);
            }
        }
        // Targets were zeroed and the drive was enabled only after configuration.
        let enable = b
            .to_drive
            .iter()
            .position(|f| f.payload().starts_with(&[0x2B, 0x40, 0x60, 0x00]))
            .expect("controlword written");
        let zero = b
            .to_drive
            .iter()
            .position(|f| {
                let p = f.payload();
                f.cob_id() == 0x600 + u16::from(DRIVE)
                    && p[0] & 0xE0 == 0x20
                    && p[1..3] == mode.target().to_le_bytes()
            })
            .expect("target zeroed");
        assert!(zero < enable);
    }
}

#[test]
fn setpoint_rpdo_and_sync_give_the_tpdo() {
    let mut b = started(Mode::CyclicSyncTorque);
    let pdos = finger_pdos(node(DRIVE), Mode::CyclicSyncTorque);
    let rpdo = pdos
        .iter()
        .find(|p| p.direction == Direction::Rx && p.number == 1)
        .expect("RPDO1");
    let tpdo1 = pdos
        .iter()
        .find(|p| p.direction == Direction::Tx && p.number == 1)
        .expect("TPDO1");
    let target: i16 = -321;
    // A SYNC on CiA 301's default id is not this drive's any more (the start-up wrote 0x1005):
    // no TPDO answers it; a HAND_ESTOP-shaped frame there neither.
    let first = b.from_drive.len();
    b.send(hand_canopen::sync::sync_frame());
    b.send(hand_canopen::CanFrame::new(0x080, &[0x12, 0x31, 0x00]).expect("frame"));
    assert!(
        b.from_drive[first..]
            .iter()
            .all(|(_, f)| f.cob_id() != tpdo1.cob_id.raw()),
        "a TPDO answered a SYNC on 0x080 after 0x1005 = {SYNC_COB:#05x}"
    );
    assert_eq!(b.drive.sync_cob_id().raw(), SYNC_COB);
    b.sync = Some(
        SyncProducer::try_new(10_000)
            .expect("period > 0")
            .on_cob_id(sync_cob()),
    );
    let first = b.from_drive.len();
    b.send(
        rpdo.encode(&[0x000F, target as u16 as u32])
            .expect("RPDO1 encodes"),
    );
    b.step(1_000);
    let tpdo = b.from_drive[first..]
        .iter()
        .find(|(_, f)| f.cob_id() == tpdo1.cob_id.raw())
        .map(|(_, f)| *f)
        .expect("TPDO1 after SYNC");
    let v = tpdo1.decode(&tpdo).expect("TPDO1 decodes");
    assert_eq!(
        Statusword(v[0] as u16).state(),
        Some(PowerState::OperationEnabled)
    );
    assert_eq!(v[1] as u16 as i16, target);

    // A wrong-length RPDO: refused with EMCY 0x8210, which the master decodes.
    let first = b.from_drive.len();
    let short = hand_canopen::CanFrame::new(rpdo.cob_id.raw(), &[0x0F, 0x00]).expect("frame");
    b.send(short);
    let emcy = b.from_drive[first..]
        .iter()
        .find_map(|(_, f)| Emcy::decode(f).ok())
        .expect("EMCY for the short RPDO");
    assert_eq!(emcy.code, EMCY_PDO_LENGTH);
    assert_eq!(emcy.class(), ErrorClass::Monitoring);
    assert!(emcy.meaning().contains("length"));
    assert_eq!(b.drive.stats().rpdo_length_errors, 1);
}

#[test]
fn drive_quick_stops_when_the_master_heartbeat_stops() {
    let mut b = started(Mode::CyclicSyncTorque);
    for _ in 0..300 {
        b.step(1_000);
    }
    assert_eq!(b.drive.power_state(), PowerState::OperationEnabled);
    assert_eq!(b.drive.stats().quick_stops, 0);
    b.heartbeat = None;
    let stopped_at = b.now;
    let first = b.from_drive.len();
    let timeout_us = u64::from(settings(Mode::CyclicSyncTorque).master_heartbeat_timeout_ms) * 1000;
    while b.drive.stats().quick_stops == 0 && b.now < stopped_at + 2 * timeout_us {
        b.step(1_000);
    }
    assert_eq!(b.drive.stats().quick_stops, 1);
    assert!(b.now - stopped_at <= timeout_us + 10_000 + 1_000);
    b.step(1_000);
    assert_eq!(b.drive.power_state(), PowerState::SwitchOnDisabled);
    let emcy = b.from_drive[first..]
        .iter()
        .find_map(|(_, f)| Emcy::decode(f).ok())
        .expect("heartbeat EMCY");
    assert_eq!(emcy.code, EMCY_HEARTBEAT);
    assert!(emcy.meaning().contains("heartbeat"));
}

#[test]
fn sdo_to_a_missing_object_is_aborted_and_named() {
    let mut b = started(Mode::CyclicSyncTorque);
    let mut sdo = SdoClient::new(node(DRIVE), 10_000);
    for (addr, code) in [
        (ObjectAddr::new(0x2000, 0), AbortCode::NoObject),
        (ObjectAddr::new(0x6041, 7), AbortCode::NoSubIndex),
    ] {
        let first = b.from_drive.len();
        b.send(sdo.upload(addr, b.now).expect("client idle"));
        let result = b.from_drive[first..]
            .iter()
            .find_map(|(_, f)| sdo.on_frame(f))
            .expect("a reply");
        assert_eq!(
            result,
            Err(SdoError::Aborted {
                node: node(DRIVE),
                addr,
                code
            })
        );
        let text = result.expect_err("aborted").to_string();
        assert!(text.contains(code.meaning()), "{text}");
    }
    // Writing a read-only object.
    let first = b.from_drive.len();
    let addr = ObjectAddr::new(0x6041, 0);
    b.send(
        sdo.download(addr, hand_canopen::SdoData::u16(0), b.now)
            .expect("idle"),
    );
    let result = b.from_drive[first..]
        .iter()
        .find_map(|(_, f)| sdo.on_frame(f));
    assert!(matches!(
        result,
        Some(Err(SdoError::Aborted {
            code: AbortCode::ReadOnly,
            ..
        }))
    ));
}

#[test]
fn a_silent_drive_times_out_with_the_step_named() {
    // Never powered: no boot-up.
    let mut b = Bench::new(settings(Mode::CyclicSyncTorque));
    b.run_startup(1_000_000);
    let StartupStatus::Failed(e) = b.startup.status() else {
        panic!("a silent drive must fail, got {:?}", b.startup.status())
    };
    assert_eq!(e.step, Step::AwaitBootUp);
    assert!(matches!(e.cause, StepFailure::NoBootUp(_)));
    assert!(e.to_string().contains("boot-up"), "{e}");

    // Boots, then never answers an SDO.
    let mut b = Bench::new(settings(Mode::CyclicSyncTorque));
    let mut out = Vec::new();
    b.drive.power_on(0, &mut out);
    b.drive.set_silent(true);
    // The drive's boot-up after reset communication is what it cannot send now; let it
    // through once by hand so the first SDO step is the one that times out.
    b.step(1_000);
    let boot = hand_canopen::nmt::ErrorControl {
        node: node(DRIVE),
        state: NmtState::BootUp,
    }
    .frame();
    assert!(b.startup.on_frame(&boot, b.now).is_none());
    b.run_startup(1_000_000);
    let StartupStatus::Failed(e) = b.startup.status() else {
        panic!("a silent drive must fail, got {:?}", b.startup.status())
    };
    assert_eq!(e.step, Step::ReadIdentity(1));
    assert!(matches!(
        e.cause,
        StepFailure::Sdo(SdoError::Timeout { .. })
    ));
    assert!(e.to_string().contains("0x1018:01"), "{e}");
}

#[test]
fn an_unsupported_mode_is_refused_at_its_step() {
    let mut b = Bench::new(settings(Mode::ProfileVelocity));
    let mut out = Vec::new();
    b.drive.power_on(0, &mut out);
    // The simulated drive lists mode 3; clear it so the check must refuse.
    let modes = ObjectAddr::new(0x6502, 0);
    let listed = b.drive.od().get(modes);
    assert_ne!(listed & Mode::ProfileVelocity.supported_bit(), 0);
    b.drive
        .set_supported_modes(listed & !Mode::ProfileVelocity.supported_bit());
    b.run_startup(1_000_000);
    let StartupStatus::Failed(e) = b.startup.status() else {
        panic!("must fail, got {:?}", b.startup.status())
    };
    assert_eq!(e.step, Step::CheckMode(Mode::ProfileVelocity));
    assert!(matches!(
        e.cause,
        StepFailure::ModeUnsupported { mode: 3, .. }
    ));
}

#[test]
fn a_boot_up_from_before_the_reset_is_not_taken_as_its_answer() {
    let mut b = Bench::new(settings(Mode::CyclicSyncTorque));
    let mut queued = Vec::new();
    b.drive.power_on(0, &mut queued);
    let old_boot_up = queued[0];
    // The reset goes out at 1 ms; the power-on boot-up, still queued, is read at the same time.
    let reset = b.startup.poll(1_000).expect("the reset communication");
    assert_eq!(reset.cob_id(), 0x000);
    assert!(b.startup.poll(1_000).is_none(), "waiting for the boot-up");
    assert!(b.startup.on_frame(&old_boot_up, 1_000).is_none());
    assert_eq!(
        b.startup.status(),
        StartupStatus::Running(Step::AwaitBootUp)
    );
    // The answer to the reset, read after it was sent, is.
    assert!(b.startup.on_frame(&old_boot_up, 1_200).is_none());
    assert_eq!(
        b.startup.status(),
        StartupStatus::Running(Step::ReadIdentity(1))
    );
}

/// The start-up up to its first SDO request (the identity's vendor), which is left in flight;
/// the drive then boots again: its boot-up message.
fn booted_during_the_identity_read() -> (Bench, hand_canopen::CanFrame) {
    let mut b = Bench::new(settings(Mode::CyclicSyncTorque));
    let mut out = Vec::new();
    b.drive.power_on(0, &mut out);
    let reset = b.startup.poll(1_000).expect("the reset communication");
    b.now = 1_000;
    b.send(reset);
    // The drive's answer, at its next poll.
    while b.startup.status() == StartupStatus::Running(Step::AwaitBootUp) {
        b.now += 1_000;
        assert!(b.now < 100_000, "no boot-up answered the reset");
        assert!(b.startup.poll(b.now).is_none());
        let mut out = Vec::new();
        b.drive.poll(b.now, &mut out);
        for f in out {
            assert!(b.startup.on_frame(&f, b.now).is_none());
        }
    }
    assert_eq!(
        b.startup.status(),
        StartupStatus::Running(Step::ReadIdentity(1))
    );
    let request = b.startup.poll(b.now).expect("the identity's SDO upload");
    assert_eq!(request.cob_id(), 0x600 + u16::from(DRIVE));
    let mut out = Vec::new();
    b.now += 500;
    b.drive.power_on(b.now, &mut out);
    (b, out[0])
}

/// A drive powered on while handd starts answers the reset with a second boot-up, which can
/// come while handd already reads its identity (seen on vcan with five drives): the start-up
/// begins again after that boot-up and ends with the configuration written.
#[test]
fn a_boot_up_during_the_start_up_starts_it_again_after_the_boot_up() {
    let (mut b, boot_up) = booted_during_the_identity_read();
    assert!(b.startup.on_frame(&boot_up, b.now).is_none());
    assert_eq!(
        b.startup.status(),
        StartupStatus::Running(Step::ReadIdentity(1))
    );
    b.run_startup(2_000_000);
    let status = b.startup.status();
    assert!(
        matches!(status, StartupStatus::Done { .. }),
        "start-up did not finish after the second boot-up: {status:?}"
    );
    assert_eq!(b.drive.power_state(), PowerState::OperationEnabled);
    let s = settings(Mode::CyclicSyncTorque);
    assert_eq!(
        b.drive.od().get(ObjectAddr::new(0x1016, 1)),
        (u32::from(MASTER) << 16) | u32::from(s.master_heartbeat_timeout_ms)
    );
}

/// A drive that keeps rebooting during its start-up fails it, the step named.
#[test]
fn a_drive_that_keeps_booting_during_its_start_up_fails_it() {
    let (mut b, boot_up) = booted_during_the_identity_read();
    for n in 1..=MAX_BOOT_UPS_DURING_STARTUP {
        b.now += 1_000;
        b.startup.on_frame(&boot_up, b.now);
        assert_eq!(
            b.startup.status(),
            StartupStatus::Running(Step::ReadIdentity(1)),
            "after boot-up {n}"
        );
    }
    b.now += 1_000;
    b.startup.on_frame(&boot_up, b.now);
    let StartupStatus::Failed(e) = b.startup.status() else {
        panic!(
            "still running after {} boot-ups",
            MAX_BOOT_UPS_DURING_STARTUP + 1
        );
    };
    assert_eq!(e.step, Step::ReadIdentity(1));
    assert_eq!(e.cause, StepFailure::UnexpectedBootUp);
    assert!(e.to_string().contains("kept booting"), "{e}");
}

/// CSV: the 8-byte RPDO1 (controlword, target velocity, max torque) is applied on SYNC with
/// 0x6072 set; one in the old 6-byte layout, without the limit, is refused and counted
/// (EMCY 0x8210) and leaves the limit as it was.
#[test]
fn csv_rpdo1_carries_the_torque_limit_and_the_old_layout_is_a_length_error() {
    let mut b = started(Mode::CyclicSyncVelocity);
    b.sync = Some(
        SyncProducer::try_new(10_000)
            .expect("period > 0")
            .on_cob_id(sync_cob()),
    );
    let f = hand_canopen::master::cyclic::rpdo1(
        node(DRIVE),
        Mode::CyclicSyncVelocity,
        hand_canopen::cia402::Controlword(0x000F),
        hand_canopen::master::Setpoint {
            value: 1_500,
            max_torque: hand_canopen::master::TorqueLimit(320),
        },
    );
    b.send(f);
    b.step(10_000);
    let od = b.drive.od();
    assert_eq!(od.get_i32(ObjectAddr::new(0x60FF, 0)), 1_500);
    assert_eq!(od.get(ObjectAddr::new(0x6072, 0)), 320);
    assert_eq!(b.drive.stats().rpdo_length_errors, 0);
    let first = b.from_drive.len();
    let v = (-900_i32).to_le_bytes();
    let old = hand_canopen::CanFrame::new(f.cob_id(), &[0x0F, 0x00, v[0], v[1], v[2], v[3]])
        .expect("frame");
    b.send(old);
    b.step(10_000);
    let emcy = b.from_drive[first..]
        .iter()
        .find_map(|(_, f)| Emcy::decode(f).ok())
        .expect("EMCY for the 6-byte RPDO1");
    assert_eq!(emcy.code, EMCY_PDO_LENGTH);
    assert_eq!(b.drive.stats().rpdo_length_errors, 1);
    let od = b.drive.od();
    assert_eq!(od.get_i32(ObjectAddr::new(0x60FF, 0)), 1_500);
    assert_eq!(od.get(ObjectAddr::new(0x6072, 0)), 320);
}
