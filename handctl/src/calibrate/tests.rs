//! The calibration's tests: protocol validation (fast), and the whole workflow in memory.

use super::protocol::{Protocol, ProtocolError};

fn invalid(text: &str) -> String {
    match Protocol::parse(text, "p.toml") {
        Err(e @ (ProtocolError::Invalid { .. } | ProtocolError::Toml { .. })) => e.to_string(),
        other => panic!("{text:?} should be refused, got {other:?}"),
    }
}

#[test]
fn bad_protocols_are_refused_naming_the_key_and_line() {
    let unknown = invalid("repetitions = 2\nhold_seconds = 4\n");
    assert!(
        unknown.contains("hold_seconds") && unknown.contains("line 2"),
        "{unknown}"
    );
    let finger = invalid("fingers = [\"index\", \"toe\"]");
    assert!(
        finger.contains("fingers") && finger.contains("toe"),
        "{finger}"
    );
    let zero = invalid("repetitions = 0");
    assert!(
        zero.contains("repetitions") && zero.contains("0 is not 1..=15"),
        "{zero}"
    );
    let negative = invalid("relax_s = -1.5");
    assert!(
        negative.contains("relax_s") && negative.contains("-1.5"),
        "{negative}"
    );
    let short = invalid("hold_s = 0.2");
    assert!(short.contains("hold_s"), "{short}");
    let kind = invalid("kinds = [\"rest\"]");
    assert!(kind.contains("kinds"), "{kind}");
    // One direction alone: every finger would have one anchor (issue 32 item 3).
    let one = invalid("kinds = [\"flexion\"]");
    assert!(
        one.contains("kinds") && one.contains("one anchor") && one.contains("extension"),
        "{one}"
    );
    let one = invalid("kinds = [\"Extension\"]");
    assert!(one.contains("extension alone"), "{one}");
    let twice = invalid("fingers = [\"all\", \"ALL\"]");
    assert!(twice.contains("twice"), "{twice}");
    let typed = invalid("hold_s = \"5\"");
    assert!(
        typed.contains("hold_s") && typed.contains("line 1"),
        "{typed}"
    );
}

#[test]
fn the_default_protocol_is_the_papers_and_a_file_round_trips() {
    let d = Protocol::default();
    // Rest, then flexion and extension of 5 fingers and the whole hand, 3 times.
    assert_eq!(d.trials().len(), 3 * (1 + 12));
    assert_eq!(
        (d.prepare_us, d.hold_us, d.relax_us),
        (3_000_000, 5_000_000, 5_000_000)
    );
    let short = Protocol::parse(
        "repetitions = 2\nprepare_s = 0.5\nhold_s = 1.5\nrelax_s = 1\nfingers = [\"Index\", \"all\"]",
        "short",
    )
    .expect("valid");
    assert_eq!(short.trials().len(), 2 * (1 + 4));
    assert_eq!(
        Protocol::parse(&short.to_toml(), "again").expect("reads back"),
        short
    );
    assert_eq!(
        Protocol::parse(&d.to_toml(), "again").expect("reads back"),
        d
    );
}
