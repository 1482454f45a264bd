//! The generator refuses inconsistent DBCs with an error naming the message and signal, and
//! accepts hand.dbc (moved from hand-dbc's tests/generator.rs).

use hand_dbc_codegen::{generate, Bus, DbcError};

const HEADER: &str = "VERSION \"\"\n\nNS_ :\n\nBS_:\n\nBU_: A B\n\n";
const ATTRS: &str = "BA_DEF_ BO_ \"GenMsgCycleTime\" INT 0 65535;\n\
BA_DEF_ BO_ \"HandE2EDataId\" INT 0 65535;\n\
BA_DEF_DEF_ \"GenMsgCycleTime\" 10;\n\
BA_DEF_DEF_ \"HandE2EDataId\" 0;\n";

fn dbc(body: &str, extra: &str) -> String {
    format!("{HEADER}{body}\n\n{ATTRS}{extra}\n")
}

fn refused(body: &str, extra: &str) -> DbcError {
    match Bus::from_dbc(&dbc(body, extra)) {
        Ok(_) => panic!("generator accepted:\n{body}\n{extra}"),
        Err(e) => e,
    }
}

fn names(message: &str, signal: &str) -> (String, String) {
    (message.to_string(), signal.to_string())
}

#[test]
fn hand_dbc_generates() {
    let code = generate(include_str!("../../hand.dbc")).expect("hand.dbc is valid");
    assert!(code.starts_with("// @generated from can-dbc/hand.dbc"));
    assert!(code.contains("pub struct FingerSetpoint"));
    assert!(code.contains("pub enum FingerMode"));
    assert!(code.contains("pub const EMG0_RAW_MIN: i16 = -2048;"));
}

#[test]
fn a_minimal_valid_dbc_generates() {
    let body = "BO_ 16 M: 2 A\n SG_ X : 0|12@1- (0.5,1) [-100|100] \"V\" B\n";
    let code = generate(&dbc(body, "")).expect("valid");
    assert!(code.contains("pub struct M"));
    assert!(code.contains("pub const X_FACTOR: f64 = 0.5;"));
    assert!(code.contains("pub const X_RAW_MIN: i16 = -202;"));
}

#[test]
fn families_become_one_type_with_an_instance() {
    let body = "BO_ 16 F_0: 1 A\n SG_ X : 0|8@1+ (1,0) [0|255] \"u\" B\n\n\
                BO_ 17 F_1: 1 A\n SG_ X : 0|8@1+ (1,0) [0|255] \"u\" B\n";
    let bus = Bus::from_dbc(&dbc(body, "")).expect("valid");
    assert_eq!(bus.groups.len(), 1);
    assert!(bus.groups[0].is_family());
    assert_eq!(bus.groups[0].ty, "F");
}

#[test]
fn signal_refusals_name_message_and_signal() {
    let m_x = names("M", "X");
    let range = refused("BO_ 16 M: 1 A\n SG_ X : 0|8@1+ (1,0) [0|300] \"u\" B\n", "");
    assert!(
        matches!(&range, DbcError::RangeTooWide { message, signal, raw_max, .. }
        if (message.clone(), signal.clone()) == m_x && *raw_max == 300.0)
    );
    assert!(range
        .to_string()
        .starts_with("M.X: range [0|300] needs raw"));
    let beyond = refused("BO_ 16 M: 1 A\n SG_ X : 4|8@1+ (1,0) [0|255] \"u\" B\n", "");
    assert!(matches!(
        beyond,
        DbcError::Bits {
            start: 4,
            size: 8,
            dlc: 1,
            ..
        }
    ));
    assert!(beyond.to_string().starts_with("M.X: bits 4..12"));
    let overlap = refused(
        "BO_ 16 M: 2 A\n SG_ X : 0|8@1+ (1,0) [0|255] \"u\" B\n SG_ Y : 4|8@1+ (1,0) [0|255] \"u\" B\n",
        "",
    );
    assert_eq!(
        overlap,
        DbcError::Overlap {
            message: "M".into(),
            signal: "Y".into()
        }
    );
    assert_eq!(overlap.to_string(), "M.Y: overlaps another signal");
    let motorola = refused("BO_ 16 M: 1 A\n SG_ X : 7|8@0+ (1,0) [0|255] \"u\" B\n", "");
    assert_eq!(
        motorola,
        DbcError::ByteOrder {
            message: "M".into(),
            signal: "X".into()
        }
    );
    let no_range = refused("BO_ 16 M: 1 A\n SG_ X : 0|8@1+ (1,0) [0|0] \"u\" B\n", "");
    assert!(matches!(no_range, DbcError::NoRange { .. }));
    assert!(no_range.to_string().starts_with("M.X: give a range"));
}

#[test]
fn value_table_refusals_name_message_and_signal() {
    let outside = refused(
        "BO_ 16 M: 1 A\n SG_ X : 0|4@1+ (1,0) [0|2] \"u\" B\n",
        "VAL_ 16 X 3 \"C\" 0 \"A\" ;",
    );
    assert!(matches!(&outside, DbcError::ValueOutOfRange { value: 3, name, .. } if name == "C"));
    assert!(outside.to_string().starts_with("M.X: value 3"));
    let scaled = refused(
        "BO_ 16 M: 1 A\n SG_ X : 0|4@1+ (2,0) [0|30] \"u\" B\n",
        "VAL_ 16 X 1 \"A\" ;",
    );
    assert_eq!(
        scaled,
        DbcError::ScaledEnum {
            message: "M".into(),
            signal: "X".into()
        }
    );
}

#[test]
fn message_refusals_name_the_message() {
    let e2e = refused(
        "BO_ 16 M: 2 A\n SG_ Crc : 0|8@1+ (1,0) [0|255] \"u\" B\n SG_ Counter : 8|3@1+ (1,0) [0|7] \"u\" B\n",
        "BA_ \"HandE2EDataId\" BO_ 16 4112;",
    );
    assert_eq!(
        e2e,
        DbcError::E2eLayout {
            message: "M".into()
        }
    );
    assert!(e2e.to_string().starts_with("M: E2E messages need"));
    let dlc = refused("BO_ 16 M: 9 A\n SG_ X : 0|8@1+ (1,0) [0|255] \"u\" B\n", "");
    assert_eq!(
        dlc,
        DbcError::Dlc {
            message: "M".into(),
            dlc: 9
        }
    );
    assert!(dlc.to_string().starts_with("M: DLC 9"));
    let shared = refused(
        "BO_ 16 M: 1 A\n SG_ X : 0|8@1+ (1,0) [0|255] \"u\" B\n\nBO_ 16 N: 1 A\n SG_ X : 0|8@1+ (1,0) [0|255] \"u\" B\n",
        "",
    );
    assert!(matches!(shared, DbcError::SharedId { id: 16, .. }));
    let wide = refused(
        "BO_ 2048 M: 1 A\n SG_ X : 0|8@1+ (1,0) [0|255] \"u\" B\n",
        "",
    );
    assert!(matches!(wide, DbcError::IdTooWide { id: 2048, .. }));
}

#[test]
fn layout_and_scaling_refusals() {
    let mux = refused(
        "BO_ 16 M: 2 A\n SG_ Mux M : 0|8@1+ (1,0) [0|255] \"u\" B\n SG_ X m0 : 8|8@1+ (1,0) [0|255] \"u\" B\n",
        "",
    );
    assert_eq!(
        mux,
        DbcError::Multiplexed {
            message: "M".into(),
            signal: "Mux".into()
        }
    );
    let factor = refused("BO_ 16 M: 1 A\n SG_ X : 0|8@1+ (0,0) [0|255] \"u\" B\n", "");
    assert_eq!(
        factor,
        DbcError::Factor {
            message: "M".into(),
            signal: "X".into()
        }
    );
    let extended = refused(
        "BO_ 2147483664 M: 1 A\n SG_ X : 0|8@1+ (1,0) [0|255] \"u\" B\n",
        "",
    );
    assert_eq!(
        extended,
        DbcError::ExtendedId {
            message: "M".into()
        }
    );
    assert!(matches!(
        Bus::from_dbc("not a dbc"),
        Err(DbcError::Parse(_))
    ));
}

#[test]
fn two_value_tables_for_one_enum_name_are_refused() {
    // M.X_Y and M_X.Y both become enum `MXY`, with different values.
    let conflict = refused(
        "BO_ 16 M: 1 A\n SG_ X_Y : 0|2@1+ (1,0) [0|1] \"\" B\n\n\
         BO_ 17 M_X: 1 A\n SG_ Y : 0|2@1+ (1,0) [0|2] \"\" B\n",
        "VAL_ 16 X_Y 0 \"A\" 1 \"B\" ;\nVAL_ 17 Y 0 \"A\" 2 \"C\" ;",
    );
    assert_eq!(
        conflict,
        DbcError::EnumConflict {
            message: "M_X".into(),
            signal: "Y".into(),
            name: "MXY".into()
        }
    );
}

#[test]
fn a_message_without_a_cycle_time_is_refused() {
    let text = format!(
        "{HEADER}BO_ 16 M: 1 A\n SG_ X : 0|8@1+ (1,0) [0|255] \"u\" B\n\n\
         BA_DEF_ BO_ \"GenMsgCycleTime\" INT 0 65535;\n"
    );
    let err = Bus::from_dbc(&text).expect_err("no GenMsgCycleTime");
    assert_eq!(
        err,
        DbcError::NoCycleTime {
            message: "M".into()
        }
    );
}

/// A protected message `name` at CAN id `id`, `dlc` bytes, with a counter of `bits` bits.
fn protected(name: &str, id: u32, dlc: u32, bits: u32) -> String {
    format!(
        "BO_ {id} {name}: {dlc} A\n SG_ Crc : 0|8@1+ (1,0) [0|255] \"u\" B\n \
         SG_ Counter : 8|{bits}@1+ (1,0) [0|{}] \"u\" B\n",
        (1u32 << bits) - 1
    )
}

#[test]
fn protected_messages_whose_crc_registers_collide_are_refused() {
    use hand_dbc_codegen::model::crc_register_after_id;
    // The pair hand.dbc had: FINGER_STATUS_3 (0x1283) and HAND_HEARTBEAT at version 1 (0x1300).
    assert_eq!(crc_register_after_id(0x1283), 0xAB);
    assert_eq!(crc_register_after_id(0x1300), 0xAB);
    let ids = "BA_ \"HandE2EDataId\" BO_ 16 4739;\nBA_ \"HandE2EDataId\" BO_ 17 4864;";
    let body = format!("{}\n{}", protected("S", 16, 8, 4), protected("H", 17, 8, 4));
    let err = refused(&body, ids);
    assert_eq!(
        err,
        DbcError::E2eCollision {
            message: "S".into(),
            data_id: 0x1283,
            other: "H".into(),
            other_data_id: 0x1300,
            dlc: 8,
            register: 0xAB,
        }
    );
    assert!(err.to_string().starts_with(
        "S (data id 0x1283) and H (data id 0x1300): both 8 bytes with CRC register 0xab"
    ));
    // The counter width does not save the pair: a 4-bit and an 8-bit counter collide too.
    let mixed = format!("{}\n{}", protected("S", 16, 8, 4), protected("H", 17, 8, 8));
    assert!(matches!(
        refused(&mixed, ids),
        DbcError::E2eCollision { register: 0xAB, .. }
    ));
    // Different lengths never collide: the receiver checks the length first.
    let lengths = format!("{}\n{}", protected("S", 16, 8, 4), protected("H", 17, 7, 4));
    assert!(Bus::from_dbc(&dbc(&lengths, ids)).is_ok());
    // The next layout version of H (0x2300) has another register: accepted.
    let bumped = "BA_ \"HandE2EDataId\" BO_ 16 4739;\nBA_ \"HandE2EDataId\" BO_ 17 8960;";
    assert!(Bus::from_dbc(&dbc(&body, bumped)).is_ok());
}

/// The register table of hand.dbc: every protected message, its length and register, no two
/// of one length alike. `cargo test -p hand-dbc-codegen --test refusals e2e_register_table --
/// --nocapture` prints it.
#[test]
fn e2e_register_table() {
    let bus = Bus::from_dbc(include_str!("../../hand.dbc")).expect("hand.dbc is valid");
    let mut seen = std::collections::BTreeMap::new();
    println!("message              dlc  data id  register");
    for m in bus.groups.iter().flat_map(|g| &g.messages) {
        let Some(e2e) = m.e2e else { continue };
        let register = e2e.register();
        println!(
            "{:<20} {:>3}  {:#06x}   {register:#04x}",
            m.name, m.dlc, e2e.data_id
        );
        if let Some(other) = seen.insert((m.dlc, register), m.name.clone()) {
            panic!("{} and {other} share register {register:#04x}", m.name);
        }
    }
    assert_eq!(seen.len(), 17, "hand.dbc protects 17 messages");
}
