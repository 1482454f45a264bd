//! E2E protection: CRC-8 SAE J1850 and every receiver status, counter wrap included.

use hand_dbc::e2e::{crc8_j1850, E2eChecker, E2eError, E2eProfile, E2eProtector, E2eStatus};
use hand_dbc::messages::{EmgSamplesG0, HandEstop, HandHeartbeat};

#[test]
fn crc8_j1850_check_value() {
    assert_eq!(crc8_j1850(b"123456789"), 0x4B);
    // Published SAE J1850 / AUTOSAR CRC-8 examples.
    assert_eq!(crc8_j1850(&[0x00, 0x00, 0x00, 0x00]), 0x59);
    assert_eq!(crc8_j1850(&[0xF2, 0x01, 0x83]), 0x37);
    assert_eq!(crc8_j1850(&[0xFF, 0xFF, 0xFF, 0xFF]), 0x74);
}

#[test]
fn profile_crc_covers_data_id_then_payload_after_byte_0() {
    let p = E2eProfile::try_new(0x1234, 4, 4).expect("valid");
    let data = [0xAA, 0x05, 0x10, 0x20];
    assert_eq!(p.crc(&data), crc8_j1850(&[0x34, 0x12, 0x05, 0x10, 0x20]));
}

/// `n` consecutive protected payloads of the profile's length, each with different content.
fn stream(profile: E2eProfile, n: usize) -> Vec<Vec<u8>> {
    let mut tx = E2eProtector::new(profile);
    (0..n)
        .map(|i| {
            let mut data = vec![0u8; profile.dlc()];
            let last = data.len() - 1;
            if last >= 2 {
                data[last] = i as u8;
            }
            tx.protect_bytes(&mut data).expect("right length");
            data
        })
        .collect()
}

fn check_all_classes(counter_bits: u8) {
    let profile = E2eProfile::try_new(0x1100, counter_bits, 8).expect("valid");
    let modulus = usize::from(profile.counter_modulus());
    let frames = stream(profile, 2 * modulus + 5);
    let mut rx = E2eChecker::try_new(profile, 2).expect("valid");
    // First frame: OK. Then consecutive frames through two wraps: all OK.
    for f in &frames {
        assert_eq!(rx.check(Some(f)), E2eStatus::Ok);
    }
    assert_eq!(rx.lost_frames(), 0);
    let last = frames.len() - 1;
    // Repeated: the same frame again.
    assert_eq!(rx.check(Some(&frames[last])), E2eStatus::Repeated);
    // NoNewData.
    assert_eq!(rx.check(None), E2eStatus::NoNewData);
    // Error: a flipped bit in the payload, or a wrong length.
    let more = stream(profile, frames.len() + 10);
    let mut bad = more[last + 1].clone();
    bad[5] ^= 0x01;
    assert_eq!(rx.check(Some(&bad)), E2eStatus::Error);
    assert_eq!(rx.check(Some(&more[last + 1][..7])), E2eStatus::Error);
    // OK with one frame lost (delta 2 <= max delta 2) across the wrap boundary.
    assert_eq!(rx.check(Some(&more[last + 2])), E2eStatus::Ok);
    assert_eq!(rx.lost_frames(), 1);
    // WrongSequence: delta 3 > 2.
    assert_eq!(rx.check(Some(&more[last + 5])), E2eStatus::WrongSequence);
    // ... and the stream resynchronises on the next consecutive frame.
    assert_eq!(rx.check(Some(&more[last + 6])), E2eStatus::Ok);
}

#[test]
fn every_status_with_a_4_bit_counter() {
    check_all_classes(4);
}

#[test]
fn every_status_with_an_8_bit_counter() {
    check_all_classes(8);
}

#[test]
fn counter_wraps_at_16_and_256() {
    for (bits, modulus) in [(4u8, 16usize), (8, 256)] {
        let profile = E2eProfile::try_new(7, bits, 2).expect("valid");
        let frames = stream(profile, modulus + 2);
        assert_eq!(profile.counter(&frames[modulus - 1]) as usize, modulus - 1);
        assert_eq!(profile.counter(&frames[modulus]), 0);
        assert_eq!(profile.counter(&frames[modulus + 1]), 1);
        // Delta across the wrap (modulus-1 -> 0) is 1, not -(modulus-1).
        let mut rx = E2eChecker::try_new(profile, 1).expect("valid");
        assert_eq!(rx.check(Some(&frames[modulus - 1])), E2eStatus::Ok);
        assert_eq!(rx.check(Some(&frames[modulus])), E2eStatus::Ok);
        // A step backwards is a large forward delta: wrong sequence, not repeated.
        assert_eq!(
            rx.check(Some(&frames[modulus - 1])),
            E2eStatus::WrongSequence
        );
    }
}

#[test]
fn no_new_data_widens_the_allowed_step() {
    let profile = E2eProfile::try_new(9, 4, 3).expect("valid");
    let frames = stream(profile, 10);
    let mut rx = E2eChecker::try_new(profile, 1).expect("valid");
    assert_eq!(rx.check(Some(&frames[0])), E2eStatus::Ok);
    // Two cycles without reception: the sender kept counting, so a step of 3 is fine.
    assert_eq!(rx.check(None), E2eStatus::NoNewData);
    assert_eq!(rx.check(None), E2eStatus::NoNewData);
    assert_eq!(rx.check(Some(&frames[3])), E2eStatus::Ok);
    // Without the empty cycles the same step is a wrong sequence.
    assert_eq!(rx.check(Some(&frames[6])), E2eStatus::WrongSequence);
}

#[test]
fn right_crc_under_the_wrong_id_is_rejected() {
    let estop = HandEstop::decode(&[0, 0, 0]).expect("valid");
    let mut tx = E2eProtector::new(HandEstop::E2E);
    let frame = tx.protect_message(&estop).expect("own profile");
    let mut own = E2eChecker::try_new(HandEstop::E2E, 1).expect("valid");
    assert_eq!(own.check_frame(Some(&frame)), E2eStatus::Ok);
    // Same bytes checked as another 3-byte-compatible stream with another data id.
    let other_profile = E2eProfile::try_new(HandHeartbeat::E2E.data_id(), 4, 3).expect("valid");
    let mut other = E2eChecker::try_new(other_profile, 1).expect("valid");
    assert_eq!(other.check_frame(Some(&frame)), E2eStatus::Error);
    // A protector refuses a message of another profile.
    let mut emg_tx = E2eProtector::new(EmgSamplesG0::E2E);
    assert!(matches!(
        emg_tx.protect_message(&estop),
        Err(E2eError::WrongMessage { .. })
    ));
}

#[test]
fn protector_keeps_the_other_bits_of_the_counter_byte() {
    // HAND_ESTOP's Request signal shares byte 1 with the 4-bit counter.
    let mut estop = HandEstop::decode(&[0, 0x10, 0]).expect("valid: Request = STOP");
    estop.set_reason(hand_dbc::messages::EstopReason::Watchdog);
    let mut tx = E2eProtector::new(HandEstop::E2E);
    for expected in 0..20u8 {
        let frame = tx.protect_message(&estop).expect("own profile");
        let back = HandEstop::try_from_frame(&frame).expect("decodes");
        assert_eq!(back.request(), hand_dbc::messages::EstopRequest::Stop);
        assert_eq!(back.counter(), expected % 16);
        assert_eq!(back.crc(), HandEstop::E2E.crc(frame.data()));
    }
}

#[test]
fn configuration_is_validated() {
    assert_eq!(
        E2eProfile::try_new(1, 5, 8),
        Err(E2eError::CounterBits { bits: 5 })
    );
    assert_eq!(E2eProfile::try_new(1, 4, 1), Err(E2eError::Dlc { dlc: 1 }));
    assert_eq!(E2eProfile::try_new(1, 4, 9), Err(E2eError::Dlc { dlc: 9 }));
    let p4 = E2eProfile::try_new(1, 4, 2).expect("valid");
    assert!(E2eChecker::try_new(p4, 0).is_err());
    assert!(E2eChecker::try_new(p4, 15).is_ok());
    assert!(E2eChecker::try_new(p4, 16).is_err());
    let mut tx = E2eProtector::new(p4);
    assert!(matches!(
        tx.protect_bytes(&mut [0; 3]),
        Err(E2eError::Length { .. })
    ));
}
