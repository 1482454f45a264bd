//! E2E protection: CRC-8 SAE J1850 and every receiver status, counter wrap included.

use hand_dbc::e2e::{
    crc8_j1850, E2eCheckConfig, E2eChecker, E2eError, E2eProfile, E2eProtector, E2eStatus,
};
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

/// Every protected message of hand.dbc, its valid frames sent under every other protected
/// message's id, is rejected by that message's receiver: no two share a CRC for any payload.
/// (Before HAND_HEARTBEAT moved to data id 0x2300 it shared FINGER_STATUS_3's register and
/// every FINGER_STATUS_3 frame passed as a heartbeat.)
#[test]
fn no_protected_frame_passes_under_another_protected_id() {
    use hand_dbc::messages::MESSAGES;
    let protected: Vec<_> = MESSAGES
        .iter()
        .filter_map(|m| m.e2e.map(|p| (m.name, p)))
        .collect();
    assert_eq!(protected.len(), 17);
    let mut x: u32 = 0x9E37_79B9;
    for &(name, profile) in &protected {
        // Frames with every counter value and varied content: a CRC collision for one payload
        // but not another is not possible (the register difference survives every byte), but
        // the test does not rely on that argument.
        let mut tx = E2eProtector::new(profile);
        for _ in 0..2 * usize::from(profile.counter_modulus()) {
            let mut data = vec![0u8; profile.dlc()];
            for b in data.iter_mut().skip(1) {
                x ^= x << 13;
                x ^= x >> 17;
                x ^= x << 5;
                *b = x as u8;
            }
            tx.protect_bytes(&mut data).expect("own length");
            let mut own = E2eChecker::try_new(profile, 1).expect("valid");
            assert_eq!(own.check(Some(&data)), E2eStatus::Ok, "{name}");
            for &(other_name, other) in &protected {
                if other == profile {
                    continue;
                }
                let mut rx = E2eChecker::try_new(other, 1).expect("valid");
                assert_eq!(
                    rx.check(Some(&data)),
                    E2eStatus::Error,
                    "a {name} frame passed as {other_name}"
                );
            }
        }
    }
}

/// One step of a Profile 1 scenario: the frame with sequence number `n` (counter `n % 16`),
/// nothing (`None`), or a corrupted copy of frame `n`, and the status the check must give.
#[derive(Clone, Copy)]
enum Rx {
    Frame(usize),
    Nothing,
    Corrupt(usize),
}
use E2eStatus::{Error, NoNewData, Repeated, Sync, WrongSequence};
use Rx::{Corrupt, Frame, Nothing};

/// Runs `steps` through a checker with `config` on a 4-bit, 8-byte profile and asserts every
/// status.
fn scenario(config: E2eCheckConfig, steps: &[(Rx, E2eStatus)]) {
    let profile = E2eProfile::try_new(0x1100, 4, 8).expect("valid");
    let frames = stream(profile, 64);
    let mut rx = E2eChecker::with_config(profile, config).expect("valid");
    for (i, &(step, want)) in steps.iter().enumerate() {
        let got = match step {
            Frame(n) => rx.check(Some(&frames[n])),
            Nothing => rx.check(None),
            Corrupt(n) => {
                let mut bad = frames[n].clone();
                bad[4] ^= 0x10;
                rx.check(Some(&bad))
            }
        };
        assert_eq!(got, want, "step {i}");
    }
}

const OK: E2eStatus = E2eStatus::Ok;

#[test]
fn profile1_after_a_jump_the_sync_counter_holds_the_data_back() {
    let p1 = E2eCheckConfig::profile1(1);
    assert_eq!(p1.sync_counter, E2eCheckConfig::DEFAULT_SYNC_COUNTER);
    assert_eq!(p1.sync_counter, 2);
    scenario(
        p1,
        &[
            (Frame(0), OK),
            (Frame(1), OK),
            (Frame(5), WrongSequence),
            (Frame(6), Sync),
            (Frame(7), Sync),
            (Frame(8), OK),
        ],
    );
    // Without the sync phase the frame right after the jump is used: the old behaviour.
    scenario(
        E2eCheckConfig::resync_at_once(1),
        &[(Frame(0), OK), (Frame(5), WrongSequence), (Frame(6), OK)],
    );
}

#[test]
fn profile1_a_stray_frame_does_not_let_the_next_one_through() {
    // A stray frame (right CRC, counter 9) lands in the real stream 0, 1, 2, 3, ...
    scenario(
        E2eCheckConfig::profile1(1),
        &[
            (Frame(0), OK),
            (Frame(1), OK),
            (Frame(9), WrongSequence),
            (Frame(2), WrongSequence),
            (Frame(3), Sync),
            (Frame(4), Sync),
            (Frame(5), OK),
        ],
    );
}

#[test]
fn profile1_a_second_sender_interleaving_one_ahead_never_gets_data_used() {
    // The real sender's frame n, then a second sender's guess of n + 1 before the real n + 1
    // arrives (which then repeats it), and so on.
    let mut steps = vec![(Frame(3), OK), (Frame(4), OK)];
    for n in 5..12 {
        // n is the intruder's, the real sender's n follows as a repeat.
        steps.push((Frame(n), if n == 5 { OK } else { Sync }));
        steps.push((Frame(n), Repeated));
    }
    scenario(E2eCheckConfig::profile1(1), &steps);
    // Resynchronising at once, every intruder frame after the first repeat is used.
    let mut steps = vec![(Frame(3), OK), (Frame(4), OK)];
    for n in 5..12 {
        steps.push((Frame(n), OK));
        steps.push((Frame(n), Repeated));
    }
    scenario(E2eCheckConfig::resync_at_once(1), &steps);
}

#[test]
fn profile1_a_repeat_needs_the_same_resynchronisation() {
    scenario(
        E2eCheckConfig::profile1(1),
        &[
            (Frame(0), OK),
            (Frame(1), OK),
            (Frame(1), Repeated),
            (Frame(2), Sync),
            (Frame(3), Sync),
            (Frame(4), OK),
        ],
    );
    // A repeat limit of 1 tolerates one repeat (or one empty cycle), not two.
    let one = E2eCheckConfig {
        max_no_new_or_repeated: 1,
        ..E2eCheckConfig::profile1(1)
    };
    scenario(
        one,
        &[
            (Frame(0), OK),
            (Frame(0), Repeated),
            (Frame(1), OK),
            (Nothing, NoNewData),
            (Frame(3), OK),
            (Frame(3), Repeated),
            (Nothing, NoNewData),
            (Frame(5), Sync),
            (Frame(6), Sync),
            (Frame(7), OK),
        ],
    );
}

#[test]
fn profile1_errors_widen_the_step_and_a_new_jump_restarts_the_sync() {
    scenario(
        E2eCheckConfig::profile1(1),
        &[
            (Frame(0), OK),
            (Frame(5), WrongSequence),
            // A corrupted frame neither ends nor restarts the sync; the sender counted it, so
            // a step of 2 is in sequence after it.
            (Corrupt(6), Error),
            (Frame(7), Sync),
            // Another jump during the sync starts it again.
            (Frame(12), WrongSequence),
            (Frame(13), Sync),
            (Frame(14), Sync),
            // Across the counter wrap (15 -> 0).
            (Frame(15), OK),
            (Frame(16), OK),
        ],
    );
}

#[test]
fn profile1_the_sync_counter_is_a_setting() {
    let n = |sync_counter| E2eCheckConfig {
        sync_counter,
        ..E2eCheckConfig::profile1(1)
    };
    scenario(
        n(0),
        &[(Frame(0), OK), (Frame(4), WrongSequence), (Frame(5), OK)],
    );
    let mut steps = vec![(Frame(0), OK), (Frame(4), WrongSequence)];
    steps.extend((5..10).map(|k| (Frame(k), Sync)));
    steps.push((Frame(10), OK));
    scenario(n(5), &steps);
    // The max delta is validated with the config.
    let p = E2eProfile::try_new(1, 4, 8).expect("valid");
    assert!(matches!(
        E2eChecker::with_config(p, E2eCheckConfig::profile1(16)),
        Err(E2eError::MaxDelta { value: 16, max: 15 })
    ));
    assert!(matches!(
        E2eChecker::with_config(p, E2eCheckConfig::profile1(0)),
        Err(E2eError::MaxDelta { value: 0, .. })
    ));
}
