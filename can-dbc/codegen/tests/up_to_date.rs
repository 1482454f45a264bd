//! The checked-in `can-dbc/core/src/messages/generated.rs` is exactly what hand.dbc generates now.

use hand_dbc_codegen::files::{regenerate, Paths};
use hand_dbc_codegen::REGENERATE;

#[test]
fn checked_in_codec_matches_hand_dbc() {
    let paths = Paths::workspace();
    let fresh = regenerate(&paths).expect("hand.dbc generates and rustfmt runs");
    let checked_in = std::fs::read_to_string(&paths.output).unwrap_or_default();
    assert!(
        checked_in == fresh,
        "{} is out of date with hand.dbc (or was edited by hand): run `{REGENERATE}` and commit \
         the result",
        paths.output.display()
    );
}

#[test]
fn formatting_is_stable() {
    let paths = Paths::workspace();
    let once = regenerate(&paths).expect("generates");
    let twice = hand_dbc_codegen::format::rustfmt(&once, &paths.rustfmt_config).expect("formats");
    assert!(
        once == twice,
        "rustfmt is not idempotent on the generated code"
    );
}
