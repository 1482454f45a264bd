//! Codec behaviour against hand.dbc: round trips, range refusal, frame conversion, dispatch.

use hand_dbc::e2e::{E2eChecker, E2eProtector, E2eStatus};
use hand_dbc::messages::{
    self, decode, CalibrationCue, CodecError, CueKind, CuePhase, EmgSamplesG1, FingerMode,
    FingerSetpoint, FingerStatus, HandDiag, HandEstop, Message, MESSAGES,
};
use hand_dbc::CanFrame;

#[test]
fn setpoint_round_trips_through_bytes_and_frames() {
    let sp = FingerSetpoint::new(2, FingerMode::Active, 12.34, -1.5, 0xBEEF).expect("in range");
    assert_eq!(sp.id(), 0x202);
    assert_eq!(sp.epoch(), 0xBEEF);
    // The epoch is the last two bytes, little-endian (hand.dbc: Epoch 48|16@1+).
    assert_eq!(&sp.encode()[6..], &[0xEF, 0xBE]);
    assert_eq!(sp.name(), "FINGER_SETPOINT_2");
    assert!((sp.force() - 12.34).abs() < 1e-9);
    assert_eq!(sp.force_raw(), 1234);
    assert_eq!(sp.velocity_raw(), -1500);
    let frame = sp.to_frame();
    assert_eq!(frame.raw_id(), 0x202);
    assert_eq!(frame.dlc(), FingerSetpoint::DLC);
    let back = FingerSetpoint::try_from_frame(&frame).expect("decodes");
    assert_eq!(back, sp);
    match decode(0x202, frame.data()).expect("dispatches") {
        Message::FingerSetpoint(m) => assert_eq!(m, sp),
        other => panic!("wrong message {other:?}"),
    }
}

#[test]
fn out_of_range_values_are_refused_not_wrapped() {
    let err = FingerSetpoint::new(0, FingerMode::Active, 50.01, 0.0, 0).expect_err("force too big");
    assert!(
        matches!(
            err,
            CodecError::OutOfRange {
                signal: "Force",
                ..
            }
        ),
        "{err}"
    );
    assert!(FingerSetpoint::new(0, FingerMode::Active, f64::NAN, 0.0, 0).is_err());
    assert!(FingerSetpoint::new(0, FingerMode::Active, 0.0, -20.001, 0).is_err());
    assert!(FingerSetpoint::new(5, FingerMode::Active, 0.0, 0.0, 0).is_err());
    let mut sp = FingerSetpoint::new(0, FingerMode::Hold, 50.0, 20.0, 0).expect("limits inclusive");
    assert!(sp.set_counter(16).is_err());
    assert!(sp.set_force_raw(5001).is_err());
    assert_eq!(
        sp.force_raw(),
        5000,
        "a refused set leaves the value unchanged"
    );
    let mut g1 = EmgSamplesG1::decode(&[0; 8]).expect("zeros are valid");
    assert!(
        g1.set_emg4_raw(2048).is_err(),
        "12-bit signed tops out at 2047"
    );
    assert!(g1.set_emg4(5117.5).is_ok());
    assert!(g1.set_emg4(5120.0).is_err());
}

#[test]
fn decode_refuses_bad_frames() {
    assert!(matches!(
        decode(0x7FF, &[]),
        Err(CodecError::UnknownId { id: 0x7FF })
    ));
    assert!(matches!(
        decode(0x100, &[0; 7]),
        Err(CodecError::WrongLength {
            expected: 8,
            got: 7,
            ..
        })
    ));
    // A setpoint of the 6-byte layout before the epoch is refused, not misread.
    assert!(matches!(
        decode(0x200, &[0; 6]),
        Err(CodecError::WrongLength {
            expected: 8,
            got: 6,
            ..
        })
    ));
    // Mode 4 is not in the FingerMode value table.
    assert!(matches!(
        decode(0x200, &[0, 0x40, 0, 0, 0, 0, 0, 0]),
        Err(CodecError::UnknownValue { signal: "Mode", .. })
    ));
    // Force raw 0x7FFF exceeds the DBC max of 50 N.
    assert!(matches!(
        decode(0x200, &[0, 0, 0xFF, 0x7F, 0, 0, 0, 0]),
        Err(CodecError::RawOutOfRange {
            signal: "Force",
            ..
        })
    ));
    let ext = CanFrame::new_extended(0x200, &[0; 6]).expect("frame");
    assert!(matches!(
        messages::decode_frame(&ext),
        Err(CodecError::ExtendedId { .. })
    ));
    let rtr =
        CanFrame::new_remote(embedded_can::StandardId::new(0x200).expect("id"), 6).expect("frame");
    assert!(matches!(
        messages::decode_frame(&rtr),
        Err(CodecError::RemoteFrame { .. })
    ));
    let other = HandEstop::decode(&[0; 3]).expect("valid").to_frame();
    assert!(matches!(
        FingerStatus::try_from_frame(&other),
        Err(CodecError::WrongId { .. })
    ));
}

#[test]
fn every_message_round_trips_its_zero_and_by_name_form() {
    for info in MESSAGES {
        let msg = messages::from_signals(info.id, &mut |name| {
            let s = info.signals.iter().find(|s| s.name == name)?;
            // The smallest raw value that the value table (if any) names.
            let raw = s.values.first().map_or(s.raw_min, |v| v.0);
            Some(s.physical(raw))
        })
        .unwrap_or_else(|e| panic!("{}: {e}", info.name));
        assert_eq!(msg.id(), info.id);
        assert_eq!(msg.name(), info.name);
        let frame = msg.to_frame();
        assert_eq!(frame.dlc(), info.dlc);
        assert_eq!(decode(info.id, frame.data()).expect("decodes"), msg);
        let mut n = 0;
        msg.for_each_signal(&mut |_, _| n += 1);
        assert_eq!(n, info.signals.len());
    }
}

#[test]
fn diag_labels_are_checked_and_protected_messages_carry_valid_crc() {
    let diag = HandDiag::new(250, 0, 3, 1.0, -1.0, 0.05, 0.0, -0.55, 2).expect("in range");
    assert!((diag.label4() + 0.55).abs() < 1e-12);
    assert!(HandDiag::new(250, 0, 3, 1.05, 0.0, 0.0, 0.0, 0.0, 0).is_err());

    let sp = FingerSetpoint::new(4, FingerMode::SafeStop, 0.0, 0.0, 0).expect("valid");
    let mut tx = E2eProtector::new(sp.e2e());
    let mut rx = E2eChecker::try_new(FingerSetpoint::E2E[4], 1).expect("valid config");
    for _ in 0..20 {
        let frame = tx.protect_message(&sp).expect("right profile");
        assert_eq!(rx.check_frame(Some(&frame)), E2eStatus::Ok);
        let decoded = FingerSetpoint::try_from_frame(&frame).expect("decodes");
        assert_eq!(decoded.mode(), FingerMode::SafeStop);
    }
    // The right CRC under another finger's data id is an error.
    let frame = tx.protect_message(&sp).expect("right profile");
    let mut other = E2eChecker::try_new(FingerSetpoint::E2E[3], 1).expect("valid config");
    assert_eq!(other.check_frame(Some(&frame)), E2eStatus::Error);
}

#[test]
fn physical_values_round_to_the_nearest_step_within_the_range() {
    let mut sp = FingerSetpoint::new(0, FingerMode::Active, 0.0, 0.0, 0).expect("valid");
    sp.set_force(12.344).expect("in range");
    assert_eq!(sp.force_raw(), 1234);
    sp.set_force(-12.346).expect("in range");
    assert_eq!(sp.force_raw(), -1235);
    let mut st = FingerStatus::new(3, hand_dbc::messages::FingerState::Hold, -0.5, 0.0, 0.0, 0)
        .expect("valid");
    assert_eq!(st.position_raw(), 0, "offset -0.5 rad maps to raw 0");
    st.set_position(2.0).expect("upper limit");
    assert_eq!(st.position_raw(), 2500);
    assert!(st.set_position(2.01).is_err());
    assert!(st.set_position(-0.51).is_err());
    assert_eq!(st.id(), 0x283);
}

#[test]
fn calibration_cue_lays_out_as_the_dbc_says_and_refuses_what_it_cannot_mean() {
    // HOLD of trial 7: index flexion, repetition 2, second attempt, 4.25 s left, 100 %.
    let cue = CalibrationCue::new(CuePhase::Hold, 7, 1, CueKind::Flexion, 2, 1, 4.25, 100)
        .expect("in range");
    assert_eq!(
        (CalibrationCue::ID, CalibrationCue::CYCLE_TIME_MS),
        (0x380, 100)
    );
    assert_eq!(CalibrationCue::E2E.data_id(), 0x1380);
    // Phase 12|4, Trial 16|8, Finger 24|4, Kind 28|4, Repetition 32|4, Attempt 36|4,
    // TimeLeft 40|16 (425 = 0x01A9), Effort 56|8, all little-endian; CRC and counter still 0.
    assert_eq!(
        cue.encode(),
        [0x00, 0x20, 0x07, 0x11, 0x12, 0xA9, 0x01, 0x64]
    );
    let mut tx = E2eProtector::new(CalibrationCue::E2E);
    let mut rx = E2eChecker::try_new(CalibrationCue::E2E, 1).expect("valid config");
    let frame = tx.protect_message(&cue).expect("right profile");
    assert_eq!(rx.check_frame(Some(&frame)), E2eStatus::Ok);
    match messages::decode_frame(&frame).expect("decodes") {
        Message::CalibrationCue(m) => {
            assert_eq!(
                (m.phase(), m.kind(), m.finger()),
                (CuePhase::Hold, CueKind::Flexion, 1)
            );
            assert!((m.time_left() - 4.25).abs() < 1e-9);
        }
        other => panic!("unexpected {other:?}"),
    }
    assert!(CalibrationCue::new(CuePhase::Hold, 7, 1, CueKind::Flexion, 2, 1, 4.25, 101).is_err());
    assert!(CalibrationCue::new(CuePhase::Hold, 7, 16, CueKind::Flexion, 2, 1, 4.25, 100).is_err());
    assert!(CalibrationCue::new(CuePhase::Hold, 7, 1, CueKind::Rest, 16, 0, 0.0, 100).is_err());
    assert!(CalibrationCue::new(CuePhase::Relax, 7, 1, CueKind::Rest, 0, 0, 655.36, 100).is_err());
    // Phase 6 and Kind 3 are in no value table; Effort 101 is over the DBC max.
    let bytes = cue.encode();
    let mut bad_phase = bytes;
    bad_phase[1] = 0x60;
    assert!(matches!(
        decode(0x380, &bad_phase),
        Err(CodecError::UnknownValue {
            signal: "Phase",
            ..
        })
    ));
    let mut bad_kind = bytes;
    bad_kind[3] = 0x31;
    assert!(matches!(
        decode(0x380, &bad_kind),
        Err(CodecError::UnknownValue { signal: "Kind", .. })
    ));
    let mut bad_effort = bytes;
    bad_effort[7] = 101;
    assert!(matches!(
        decode(0x380, &bad_effort),
        Err(CodecError::RawOutOfRange {
            signal: "Effort",
            ..
        })
    ));
}
