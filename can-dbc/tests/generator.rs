//! The code generator (build.rs, compiled in here as a module) refuses inconsistent DBCs with
//! a message naming the message and signal, and accepts hand.dbc.

#[allow(dead_code, reason = "build.rs's main() is only the build entry point")]
#[path = "../build.rs"]
mod generator;

const HEADER: &str = "VERSION \"\"\n\nNS_ :\n\nBS_:\n\nBU_: A B\n\n";
const ATTRS: &str = "BA_DEF_ BO_ \"GenMsgCycleTime\" INT 0 65535;\n\
BA_DEF_ BO_ \"HandE2EDataId\" INT 0 65535;\n\
BA_DEF_DEF_ \"GenMsgCycleTime\" 10;\n\
BA_DEF_DEF_ \"HandE2EDataId\" 0;\n";

fn dbc(body: &str, extra: &str) -> String {
    format!("{HEADER}{body}\n\n{ATTRS}{extra}\n")
}

fn refused(body: &str, extra: &str) -> String {
    match generator::generate(&dbc(body, extra)) {
        Ok(_) => panic!("generator accepted:\n{body}\n{extra}"),
        Err(e) => e,
    }
}

#[test]
fn hand_dbc_generates() {
    let code = generator::generate(include_str!("../hand.dbc")).expect("hand.dbc is valid");
    assert!(code.contains("pub struct FingerSetpoint"));
    assert!(code.contains("pub enum FingerMode"));
}

#[test]
fn a_minimal_valid_dbc_generates() {
    let body = "BO_ 16 M: 2 A\n SG_ X : 0|12@1- (0.5,1) [-100|100] \"V\" B\n";
    let code = generator::generate(&dbc(body, "")).expect("valid");
    assert!(code.contains("pub struct M"));
    assert!(code.contains("pub const X_FACTOR: f64 = 0.5;"));
}

#[test]
fn inconsistent_dbcs_are_refused_with_the_signal_named() {
    let cases = [
        // Range the bits cannot hold.
        ("BO_ 16 M: 1 A\n SG_ X : 0|8@1+ (1,0) [0|300] \"u\" B\n", "", "M.X: range"),
        // Signal beyond the DLC.
        ("BO_ 16 M: 1 A\n SG_ X : 4|8@1+ (1,0) [0|255] \"u\" B\n", "", "M.X: bits 4..12"),
        // Overlap.
        (
            "BO_ 16 M: 2 A\n SG_ X : 0|8@1+ (1,0) [0|255] \"u\" B\n SG_ Y : 4|8@1+ (1,0) [0|255] \"u\" B\n",
            "",
            "M.Y: overlaps",
        ),
        // Motorola byte order.
        ("BO_ 16 M: 1 A\n SG_ X : 7|8@0+ (1,0) [0|255] \"u\" B\n", "", "M.X: only little-endian"),
        // No range given.
        ("BO_ 16 M: 1 A\n SG_ X : 0|8@1+ (1,0) [0|0] \"u\" B\n", "", "M.X: give a range"),
        // A value-table entry outside the range.
        (
            "BO_ 16 M: 1 A\n SG_ X : 0|4@1+ (1,0) [0|2] \"u\" B\n",
            "VAL_ 16 X 3 \"C\" 0 \"A\" ;",
            "M.X: value 3",
        ),
        // E2E without the fixed CRC/counter layout.
        (
            "BO_ 16 M: 2 A\n SG_ Crc : 0|8@1+ (1,0) [0|255] \"u\" B\n SG_ Counter : 8|3@1+ (1,0) [0|7] \"u\" B\n",
            "BA_ \"HandE2EDataId\" BO_ 16 4112;",
            "M: E2E messages need",
        ),
        // DLC beyond classic CAN.
        ("BO_ 16 M: 9 A\n SG_ X : 0|8@1+ (1,0) [0|255] \"u\" B\n", "", "M: DLC 9"),
    ];
    for (body, extra, want) in cases {
        let err = refused(body, extra);
        assert!(err.contains(want), "expected {want:?} in {err:?}");
    }
}
