//! `handd.toml`: any text gives a configuration or an error naming the line or the field.

use std::path::Path;

use driver::config::{Config, ConfigError};
use driver::units::FINGER_NAMES;
use proptest::prelude::*;

use crate::mutate::{arbitrary_bytes, mutated, names_lines_of, seeded};

const VALID: &str = r#"interface = "can0"
model = "/var/lib/handstack/model.hsm"
tick_ms = 50
deadline_slack_ms = 5
mains_hz = 50
state_dir = "/var/lib/handstack"

[timeouts]
emg_silence_ms = 100
finger_silence_ms = 100
recovery_ms = 500

[fingers.thumb]
kf = 1.0
kalpha = 2.0
omega_max = 3.0
deadband = 0.05
slew = 5.0
damping = 0.0

[fingers.index]
kf = 0.8
kalpha = 3.0

[control]
socket = "/run/handstack/handctl.sock"
group = "handstack"
audit_log = "/var/lib/handstack/audit.log"
"#;

/// A file with a CiA 402 drive on the index finger and handd's CANopen table (issue 26).
const VALID_DRIVES: &str = r#"interface = "can0"

[fingers.index]
kf = 0.8

[fingers.index.drive]
profile = "cia402"
node_id = 5
mode = "cst"
rated_torque_mnm = 25.0
gear_ratio = 64.0
moment_arm_m = 0.04
max_torque_permille = 1000
max_speed_rpm = 8000

[canopen]
master_node_id = 127
sync_cob_id = 0x07F
"#;

/// Whether `field` is a field of the file, as `Config::validate` names them.
fn is_field(field: &str) -> bool {
    const TOP: &[&str] = &[
        "interface",
        "model",
        "tick_ms",
        "deadline_slack_ms",
        "mains_hz",
        "timeouts.emg_silence_ms",
        "timeouts.finger_silence_ms",
        "timeouts.recovery_ms",
        "control.socket",
        "deploy.max_tolerance",
        "deploy.min_rays",
        "state_dir",
        "canopen.master_node_id",
        "canopen.sync_cob_id",
    ];
    const FINGER: &[&str] = &[
        "kf",
        "kalpha",
        "omega_max",
        "deadband",
        "slew",
        "damping",
        "rest_damping",
        "ramp_s",
        "drive.profile",
        "drive.node_id",
        "drive.mode",
        "drive.rated_torque_mnm",
        "drive.gear_ratio",
        "drive.moment_arm_m",
        "drive.max_torque_permille",
        "drive.max_speed_rpm",
    ];
    TOP.contains(&field)
        || field.strip_prefix("fingers.").is_some_and(|rest| {
            rest.split_once('.')
                .is_some_and(|(f, k)| FINGER_NAMES.contains(&f) && FINGER.contains(&k))
        })
}

fn check(bytes: &[u8]) -> Result<(), TestCaseError> {
    let text = String::from_utf8_lossy(bytes);
    match Config::from_toml(&text, Path::new("handd.toml")) {
        Ok(cfg) => {
            let again = Config::from_toml(&cfg.to_toml(), Path::new("again.toml"));
            prop_assert_eq!(again.ok(), Some(cfg));
        }
        Err(ConfigError::Parse { message, .. }) => {
            prop_assert!(
                names_lines_of(&message, bytes),
                "no line of the file: {message}"
            );
        }
        Err(ConfigError::Invalid { field, .. }) => {
            prop_assert!(is_field(&field), "not a field: {field:?}");
        }
        Err(other) => prop_assert!(false, "unexpected kind of error: {other}"),
    }
    Ok(())
}

#[test]
fn the_valid_file_parses() {
    let cfg = Config::from_toml(VALID, Path::new("handd.toml")).expect("valid");
    assert_eq!(cfg.fingers.index.kf, 0.8);
    let cfg = Config::from_toml(VALID_DRIVES, Path::new("handd.toml")).expect("valid");
    assert!(cfg.drives().expect("valid drives").any_cia402());
}

// Regression: bytes that are not UTF-8 were refused without saying where.
#[test]
fn a_file_that_is_not_text_is_refused_with_line_and_column() {
    let path = std::env::temp_dir().join(format!("handstack-handd-{}.toml", std::process::id()));
    let mut bytes = VALID.as_bytes().to_vec();
    let at = VALID.find("tick_ms").expect("key");
    bytes.splice(at..at, [0xc3, 0x28]);
    std::fs::write(&path, &bytes).expect("write");
    let err = Config::load(&path).expect_err("not text");
    std::fs::remove_file(&path).expect("clean up");
    assert!(
        err.to_string()
            .ends_with("not UTF-8 text at line 3, column 1"),
        "{err}"
    );
}

proptest! {
    #![proptest_config(seeded(2000, 0x4A4D_0001))]

    #[test]
    fn arbitrary_bytes_never_panic(bytes in arbitrary_bytes(400)) {
        check(&bytes)?;
    }

    #[test]
    fn mutated_files_never_panic(bytes in mutated(VALID.as_bytes().to_vec())) {
        check(&bytes)?;
    }

    #[test]
    fn mutated_drive_tables_never_panic(bytes in mutated(VALID_DRIVES.as_bytes().to_vec())) {
        check(&bytes)?;
    }
}
