//! The control protocol's request line: any bytes give a request or a refusal naming the
//! column, or the length limit; never a panic.

use driver::protocol::{parse_request, Request, MAX_REQUEST_BYTES};
use proptest::prelude::*;

use crate::mutate::{arbitrary_bytes, mutated, seeded};

const VALID: &[&str] = &[
    r#"{"cmd":"tune","finger":"index","kf":0.8,"kalpha":3.0}"#,
    r#"{"cmd":"status"}"#,
    r#"{"cmd": "tune", "finger": "4", "kalpha": 12.5}"#,
];

fn check(bytes: &[u8]) -> Result<(), TestCaseError> {
    let line = String::from_utf8_lossy(bytes);
    match parse_request(&line) {
        Ok(req) => {
            let again = serde_json::to_string(&req).expect("a request serialises");
            prop_assert_eq!(parse_request(&again), Ok(req));
        }
        Err(reason) if line.len() > MAX_REQUEST_BYTES => {
            prop_assert!(reason.contains("longer than 4096 bytes"), "{reason}");
        }
        Err(reason) => {
            prop_assert!(reason.starts_with("malformed request: "), "{reason}");
            let named = reason.contains(" column ") || reason.contains("field `");
            prop_assert!(named, "no place: {reason}");
        }
    }
    Ok(())
}

#[test]
fn the_valid_lines_parse_and_deep_nesting_is_refused() {
    for line in VALID {
        assert!(matches!(
            parse_request(line),
            Ok(Request::Tune { .. } | Request::Status)
        ));
    }
    let deep = format!(
        r#"{{"cmd":"status","x":{}{}}}"#,
        "[".repeat(2000),
        "]".repeat(2000)
    );
    let reason = parse_request(&deep).expect_err("too deep");
    assert!(
        reason.contains("recursion limit") && reason.contains("column"),
        "{reason}"
    );
}

proptest! {
    #![proptest_config(seeded(3000, 0xC7_0001))]

    #[test]
    fn arbitrary_bytes_never_panic(bytes in arbitrary_bytes(300)) {
        check(&bytes)?;
    }

    #[test]
    fn mutated_requests_never_panic(
        which in 0..VALID.len(),
        bytes in mutated(VALID[0].as_bytes().to_vec()),
        other in mutated(VALID[2].as_bytes().to_vec()),
    ) {
        check(if which == 2 { &other } else { &bytes })?;
    }

    #[test]
    fn overlong_lines_are_refused_whatever_they_hold(pad in MAX_REQUEST_BYTES - 40..MAX_REQUEST_BYTES + 40) {
        let line = format!(r#"{{"cmd":"status","x":"{}"}}"#, "a".repeat(pad));
        check(line.as_bytes())?;
    }
}
