//! `session.toml`: any text gives the metadata or an error naming the line, the field, the
//! trial or the segment; never a panic.

use std::path::Path;

use decoder::session::{SessionError, SessionMeta};
use proptest::prelude::*;

use crate::mutate::{arbitrary_bytes, mentioned_lines, mutated, names_lines_of, seeded};

const VALID: &str = r#"format_version = 1
onset_skip_ms = 150.0

[chain]
channels = 12
sample_rate_hz = 1000.0
band_low_hz = 20.0
band_high_hz = 450.0
bandpass_order = 4
mains_hz = 50
notch_q = 30.0
mains_harmonics = 1
window_ms = 200.0
step_ms = 50.0

[recording]
format = "candump"
file = "frames.log"
full_scale = 2047.0

[[segment]]
start_us = 0
end_us = 5000000

[[trial]]
id = 1
finger = 1
kind = "flexion"
repetition = 1
start_us = 1000000
end_us = 4000000

[[trial]]
id = 2
finger = "all"
kind = "rest"
repetition = 1
start_sample = 4000
end_sample = 4900
"#;

/// `VALID` without its `[[segment]]` (the whole recording is one).
fn without_segments() -> Vec<u8> {
    edited("[[segment]]\nstart_us = 0\nend_us = 5000000\n\n", "").into_bytes()
}

/// The chain configuration's fields, which its errors start with.
const CHAIN_FIELDS: &[&str] = &[
    "channels",
    "sample_rate_hz",
    "band_low_hz",
    "band_high_hz",
    "bandpass_order",
    "mains_hz",
    "notch_q",
    "mains_harmonics",
    "dc_cutoff_hz",
    "window_ms",
    "step_ms",
];

/// What a refusal of a well-formed file may name: a top-level field, a trial or a segment.
const PLACES: &[&str] = &[
    "format_version",
    "onset_skip_ms",
    "recording.full_scale",
    "trial",
    "segment",
];

/// Parses `bytes` (as a reader of the file would see them): a value, or an error naming where.
fn check(bytes: &[u8]) -> Result<(), TestCaseError> {
    let text = String::from_utf8_lossy(bytes);
    match SessionMeta::parse(&text, Path::new("s/session.toml")) {
        Ok(meta) => {
            let again = SessionMeta::parse(&meta.to_toml(), Path::new("again.toml"));
            prop_assert_eq!(again.ok(), Some(meta));
        }
        Err(SessionError::Toml { message, .. }) => {
            prop_assert!(
                names_lines_of(&message, bytes),
                "no line of the file: {message}"
            );
        }
        Err(SessionError::Invalid { message, .. }) => {
            prop_assert!(PLACES.iter().any(|p| message.contains(p)), "{message}");
        }
        Err(SessionError::Chain(e)) => {
            let msg = e.to_string();
            let field = msg.split(" = ").next().unwrap_or_default();
            prop_assert!(
                CHAIN_FIELDS.contains(&field),
                "chain error names no field: {msg}"
            );
        }
        Err(other) => prop_assert!(false, "unexpected kind of error: {other}"),
    }
    Ok(())
}

#[test]
fn the_valid_file_parses() {
    let meta = SessionMeta::parse(VALID, Path::new("session.toml")).expect("valid");
    assert_eq!(meta.trials.len(), 2);
    assert_eq!(
        (meta.trials[1].start_us, meta.trials[1].end_us),
        (4_000_000, 4_900_000)
    );
}

#[test]
fn deep_nesting_is_refused_with_its_line_not_a_stack_overflow() {
    let text = format!("x = {}1{}\n", "[".repeat(100_000), "]".repeat(100_000));
    let err = SessionMeta::parse(&text, Path::new("session.toml")).expect_err("nested");
    assert!(mentioned_lines(&err.to_string()) == [1], "{err}");
}

proptest! {
    #![proptest_config(seeded(2000, 0x5E55_0001))]

    #[test]
    fn arbitrary_bytes_never_panic(bytes in arbitrary_bytes(400)) {
        check(&bytes)?;
    }

    #[test]
    fn mutated_files_never_panic(
        bytes in prop_oneof![mutated(VALID.as_bytes().to_vec()), mutated(without_segments())],
    ) {
        check(&bytes)?;
    }
}

/// `VALID` with `from` replaced by `to` (which must occur).
fn edited(from: &str, to: &str) -> String {
    assert!(VALID.contains(from), "{from}");
    VALID.replacen(from, to, 1)
}

// Regression: a NaN or negative full scale was accepted and made the saturation gate moot.
#[test]
fn a_full_scale_that_is_not_a_positive_number_is_refused() {
    for bad in ["nan", "-2047.0", "0.0", "inf"] {
        let text = edited("full_scale = 2047.0", &format!("full_scale = {bad}"));
        let err = SessionMeta::parse(&text, Path::new("session.toml")).expect_err(bad);
        assert!(err.to_string().contains("recording.full_scale"), "{err}");
    }
}

// Regression: a huge end_sample gave a time TOML cannot hold, and writing the metadata back
// (`to_toml`) panicked.
#[test]
fn a_time_beyond_tomls_integers_is_refused() {
    let text = edited("end_sample = 4900", "end_sample = 9223372036854775807");
    let err = SessionMeta::parse(&text, Path::new("session.toml")).expect_err("too late");
    let msg = err.to_string();
    assert!(
        msg.contains("trial 2") && msg.contains("is beyond 9223372036854775807"),
        "{msg}"
    );
    // The largest time accepted is written back and read again unchanged.
    let text = edited("end_us = 4000000", "end_us = 9223372036854775807")
        .replace("end_us = 5000000", "end_us = 9223372036854775807");
    let meta = SessionMeta::parse(&text, Path::new("session.toml")).expect("at the limit");
    assert_eq!(meta.trials[0].end_us, decoder::session::MAX_TIME_US);
    let again = SessionMeta::parse(&meta.to_toml(), Path::new("again.toml")).expect("again");
    assert_eq!(again, meta);
}

// Regression: bytes that are not UTF-8 were refused without saying where.
#[test]
fn a_file_that_is_not_text_is_refused_with_line_and_column() {
    let dir = std::env::temp_dir().join(format!("handstack-malformed-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let mut bytes = VALID.as_bytes().to_vec();
    bytes.splice(2..2, [0xff]);
    std::fs::write(dir.join("session.toml"), &bytes).expect("write");
    let err = SessionMeta::read(&dir).expect_err("not text");
    std::fs::remove_dir_all(&dir).expect("clean up");
    let msg = err.to_string();
    assert!(
        msg.contains("session.toml: not UTF-8 text at line 1, column 3"),
        "{msg}"
    );
}
