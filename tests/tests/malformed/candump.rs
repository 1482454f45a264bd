//! candump logs: any bytes give entries or the number of the first bad line, never a panic.

use hand_dbc::candump::{format_line, parse_line, CandumpError, LogReader, MAX_LINE_BYTES};
use proptest::prelude::*;

use crate::mutate::{arbitrary_bytes, line_count, mutated, seeded};

const VALID: &str = "(1700000000.000000) can0 180#0102030405060708\n\
(1700000000.001000) can0 181#00FF\n\
(1700000000.002000) can0 1ABCDEF0#DEADBEEF\n\
\n\
(1700000000.003000) vcan0 7FF#R4\n\
(1700000000.004000) can0 100#\n";

/// Reads `bytes` as a log: every entry re-formats to a line that parses back to it, and an
/// error names a line of the input.
fn check(bytes: &[u8]) -> Result<(), TestCaseError> {
    let lines = line_count(bytes);
    for item in LogReader::new(bytes) {
        match item {
            Ok(entry) => prop_assert_eq!(parse_line(&format_line(&entry)), Ok(entry)),
            Err(CandumpError::Line { line, error }) => {
                prop_assert!(
                    (1..=lines).contains(&line),
                    "line {line} of {lines}: {error}"
                );
                let msg = CandumpError::Line { line, error }.to_string();
                prop_assert!(msg.starts_with(&format!("line {line}: ")), "{msg}");
            }
            Err(e) => prop_assert!(false, "an in-memory log gave an I/O error: {e}"),
        }
    }
    Ok(())
}

#[test]
fn the_valid_log_reads_whole() {
    let entries: Vec<_> = LogReader::new(VALID.as_bytes())
        .collect::<Result<_, _>>()
        .expect("valid log");
    assert_eq!(entries.len(), 5);
}

#[test]
fn a_log_without_newlines_is_refused_at_line_1_without_buffering_it() {
    let endless = vec![b'1'; 50 * MAX_LINE_BYTES];
    let err = LogReader::new(&endless[..])
        .next()
        .expect("one item")
        .expect_err("not a line");
    assert_eq!(
        err.to_string(),
        "line 1: line longer than 256 bytes: not a candump line"
    );
}

proptest! {
    #![proptest_config(seeded(3000, 0xCA4D_0001))]

    #[test]
    fn arbitrary_bytes_never_panic(bytes in arbitrary_bytes(600)) {
        check(&bytes)?;
    }

    #[test]
    fn mutated_logs_never_panic(bytes in mutated(VALID.as_bytes().to_vec())) {
        check(&bytes)?;
    }
}
