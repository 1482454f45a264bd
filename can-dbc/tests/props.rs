//! Property tests: hostile input never panics, and what is valid round-trips exactly.

use hand_dbc::candump::{format_line, parse_line, parse_log, LogEntry, LogWriter};
use hand_dbc::messages::{decode, MESSAGES};
use hand_dbc::CanFrame;
use proptest::prelude::*;
use rand::{Rng, SeedableRng};

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    #[test]
    fn decoding_any_payload_under_any_id_never_panics(
        id in 0u32..=0x7FF,
        data in proptest::collection::vec(any::<u8>(), 0..=8),
    ) {
        if let Ok(msg) = decode(id, &data) {
            // Whatever decodes re-encodes to a frame that decodes to the same message.
            let frame = msg.to_frame();
            prop_assert_eq!(frame.raw_id(), id);
            prop_assert_eq!(decode(id, frame.data()).ok(), Some(msg));
        }
    }

    #[test]
    fn candump_parser_never_panics_on_random_text(line in ".{0,80}") {
        let _ = parse_line(&line);
        let _ = parse_log(&line);
    }

    #[test]
    fn candump_parser_never_panics_on_near_miss_lines(
        line in r"\([0-9]{0,12}\.[0-9]{0,8}\) [a-z0-9]{0,6} [0-9A-Fa-fRr#_.]{0,24}",
    ) {
        let _ = parse_line(&line);
    }

    #[test]
    fn candump_lines_round_trip(
        time_us in 0u64..=u64::MAX / 2,
        extended in any::<bool>(),
        remote in any::<bool>(),
        id in any::<u32>(),
        data in proptest::collection::vec(any::<u8>(), 0..=8),
    ) {
        let frame = match (extended, remote) {
            (false, false) => CanFrame::new_standard((id & 0x7FF) as u16, &data),
            (true, false) => CanFrame::new_extended(id & 0x1FFF_FFFF, &data),
            (false, true) => CanFrame::new_remote(
                embedded_can::StandardId::new((id & 0x7FF) as u16).expect("masked"), data.len()),
            (true, true) => CanFrame::new_remote(
                embedded_can::ExtendedId::new(id & 0x1FFF_FFFF).expect("masked"), data.len()),
        }.expect("valid frame");
        let entry = LogEntry { time_us, iface: "vcan0".into(), frame };
        let line = format_line(&entry);
        prop_assert_eq!(parse_line(&line), Ok(entry));
    }
}

/// Every id of the 11-bit space, every length 0..=8, random bytes: no panic, and decoding
/// succeeds only for ids hand.dbc defines.
#[test]
fn every_id_and_length_is_handled() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    for id in 0u32..=0x7FF {
        for len in 0..=8usize {
            for _ in 0..4 {
                let data: Vec<u8> = (0..len).map(|_| rng.gen()).collect();
                let result = decode(id, &data);
                let known = MESSAGES.iter().find(|m| m.id == id);
                match known {
                    None => assert!(result.is_err(), "id {id:#x} is not in hand.dbc"),
                    Some(m) if m.dlc != len => assert!(result.is_err(), "{} len {len}", m.name),
                    Some(_) => {}
                }
            }
        }
    }
}

#[test]
fn writer_output_reads_back() {
    let entries: Vec<LogEntry> = MESSAGES
        .iter()
        .enumerate()
        .map(|(i, m)| LogEntry {
            time_us: 1_700_000_000_000_000 + i as u64 * 1234,
            iface: "vcan0".into(),
            frame: CanFrame::new_standard(m.id as u16, &vec![0xA5; m.dlc]).expect("valid"),
        })
        .collect();
    let mut w = LogWriter::new(Vec::new());
    for e in &entries {
        w.write(e).expect("in-memory write");
    }
    let text = String::from_utf8(w.into_inner()).expect("ASCII");
    assert_eq!(text.lines().count(), entries.len());
    assert_eq!(parse_log(&text).expect("own output parses"), entries);
    let path = std::env::temp_dir().join(format!("hand-dbc-{}.log", std::process::id()));
    std::fs::write(&path, &text).expect("temp file");
    let back = hand_dbc::candump::read_log(&path).expect("reads");
    let _ = std::fs::remove_file(&path);
    assert_eq!(back, entries);
}
