//! A finger's drive profile in handd.toml (issue 26; DESIGN.md 2b): `native`, hand.dbc's
//! FINGER_SETPOINT / FINGER_STATUS (the default), or `cia402`, a CANopen CiA 402 drive
//! (maxon EPOS4, Faulhaber MC, Nanotec, Elmo) with its node id, operating mode and the
//! scaling from the daemon's units (N at the fingertip, rad/s at the joint) to the drive's.
//!
//! Validated once with the rest of the config, and by `handd --check`: a missing or bad node
//! id, a node id two fingers share or handd's own, a node whose COB-IDs (CiA 301's predefined
//! connection set) fall on one of hand.dbc's ids, a SYNC COB-ID on one of them, a missing or
//! impossible scale: each refused naming the field. Whether the drive lists the mode in
//! 0x6502 can only be known from the drive: its start-up checks that.

use std::collections::BTreeMap;

use hand_canopen::cia402::Mode;
use hand_canopen::scaling::{Scaling, ScalingSettings};
use hand_canopen::{CobId, NodeId};
use hand_dbc::messages::MESSAGES;
use serde::{Deserialize, Serialize};

use crate::config::{ConfigError, Fingers};
use crate::units::{FINGER_NAMES, N_FINGERS};

/// How a finger's setpoints reach its motor.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Profile {
    /// hand.dbc's FINGER_SETPOINT and FINGER_STATUS.
    #[default]
    Native,
    /// A CANopen CiA 402 drive.
    Cia402,
}

/// The CiA 402 operating mode (0x6060) as written in handd.toml.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum DriveMode {
    /// Cyclic synchronous torque (10): the force setpoint.
    Cst,
    /// Cyclic synchronous velocity (9): the velocity setpoint.
    Csv,
    /// Profile velocity (3): the velocity setpoint.
    Pv,
}

impl DriveMode {
    /// The CANopen core's mode.
    pub fn mode(self) -> Mode {
        match self {
            Self::Cst => Mode::CyclicSyncTorque,
            Self::Csv => Mode::CyclicSyncVelocity,
            Self::Pv => Mode::ProfileVelocity,
        }
    }
}

/// One finger's `[fingers.NAME.drive]` table. Every field but `profile` is for `cia402` only
/// and required there.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields, default)]
pub struct DriveConfig {
    /// `native` (default) or `cia402`.
    pub profile: Profile,
    /// The drive's CANopen node id, 1 to 127.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub node_id: Option<u8>,
    /// `cst`, `csv` or `pv`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mode: Option<DriveMode>,
    /// The motor's rated torque (the drive's 0x6076), mNm.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rated_torque_mnm: Option<f64>,
    /// Gear ratio, motor turns per joint turn.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gear_ratio: Option<f64>,
    /// Moment arm from the joint to the fingertip, m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub moment_arm_m: Option<f64>,
    /// The largest torque target sent, per mille of rated torque (1 to 32767).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_torque_permille: Option<u16>,
    /// The largest velocity target sent, rpm at the motor.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_speed_rpm: Option<u32>,
}

impl DriveConfig {
    /// True for the default (native, nothing else set): not written back to the file.
    pub fn is_default(&self) -> bool {
        *self == Self::default()
    }
}

/// The `[canopen]` table: handd as the CANopen master, used when a finger has a `cia402`
/// drive.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CanopenConfig {
    /// handd's own node id (its heartbeat, which every drive watches), 1 to 127.
    pub master_node_id: u8,
    /// The SYNC COB-ID handd produces, written to each drive's 0x1005 by its start-up
    /// (`hand_canopen::StartupSettings::sync_cob_id`). CiA 301's default, 0x080, is
    /// HAND_ESTOP's id in hand.dbc, so it is refused.
    pub sync_cob_id: u16,
}

impl Default for CanopenConfig {
    fn default() -> Self {
        Self {
            master_node_id: 127,
            sync_cob_id: 0x07F,
        }
    }
}

/// A finger's validated drive.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Drive {
    /// hand.dbc's setpoints.
    Native,
    /// A CiA 402 drive.
    Cia402 {
        /// Its node id.
        node: NodeId,
        /// Its operating mode.
        mode: Mode,
        /// Daemon units to its units.
        scaling: Scaling,
    },
}

/// Every finger's validated drive, and handd's CANopen settings when one is `cia402`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Drives {
    /// Per finger, thumb to pinky.
    pub fingers: [Drive; N_FINGERS],
    /// handd's node id and SYNC COB-ID (None: every finger is native).
    pub master: Option<(NodeId, CobId)>,
}

impl Default for Drives {
    /// Every finger native.
    fn default() -> Self {
        Self {
            fingers: [Drive::Native; N_FINGERS],
            master: None,
        }
    }
}

impl Drives {
    /// Whether any finger has a CiA 402 drive.
    pub fn any_cia402(&self) -> bool {
        self.master.is_some()
    }
}

fn invalid(field: String, value: impl ToString, allowed: impl Into<String>) -> ConfigError {
    ConfigError::Invalid {
        field,
        value: value.to_string(),
        allowed: allowed.into(),
    }
}

/// hand.dbc's message on `id`, if any.
fn dbc_message_on(id: u16) -> Option<&'static str> {
    MESSAGES
        .iter()
        .find(|m| m.id == u32::from(id))
        .map(|m| m.name)
}

/// Validates every finger's drive against the others, handd's own node and hand.dbc.
pub fn validate_drives(fingers: &Fingers, canopen: &CanopenConfig) -> Result<Drives, ConfigError> {
    let mut drives = [Drive::Native; N_FINGERS];
    // Node id -> the field that named it first.
    let mut taken: BTreeMap<u8, String> = BTreeMap::new();
    for (f, name) in FINGER_NAMES.iter().enumerate().take(N_FINGERS) {
        let d = &fingers.get(f).drive;
        let at = |field: &str| format!("fingers.{name}.drive.{field}");
        if d.profile == Profile::Native {
            if *d != DriveConfig::default() {
                return Err(invalid(
                    at("profile"),
                    "\"native\"",
                    "\"cia402\" when node_id, mode or a scale is set (a native finger takes none)",
                ));
            }
            continue;
        }
        let node = node_of(d, &at, canopen, &mut taken)?;
        let mode = d
            .mode
            .ok_or_else(|| invalid(at("mode"), "(missing)", "\"cst\", \"csv\" or \"pv\""))?
            .mode();
        drives[f] = Drive::Cia402 {
            node,
            mode,
            scaling: scaling_of(d, &at)?,
        };
    }
    let master = if taken.is_empty() {
        None
    } else {
        Some(master_of(canopen, &taken)?)
    };
    Ok(Drives {
        fingers: drives,
        master,
    })
}

/// A cia402 finger's node id: present, in range, no other finger's nor handd's, and its
/// predefined COB-IDs clear of hand.dbc's ids; recorded in `taken`.
fn node_of(
    d: &DriveConfig,
    at: &dyn Fn(&str) -> String,
    canopen: &CanopenConfig,
    taken: &mut BTreeMap<u8, String>,
) -> Result<NodeId, ConfigError> {
    let raw = d
        .node_id
        .ok_or_else(|| invalid(at("node_id"), "(missing)", "the drive's node id, 1 to 127"))?;
    let node = NodeId::try_new(raw).map_err(|_| invalid(at("node_id"), raw, "1 to 127"))?;
    if let Some(other) = taken.insert(raw, at("node_id")) {
        return Err(invalid(
            at("node_id"),
            raw,
            format!("a node id no other finger has ({other} is {raw} too)"),
        ));
    }
    if raw == canopen.master_node_id {
        return Err(invalid(
            at("node_id"),
            raw,
            "another node id than handd's own (canopen.master_node_id)",
        ));
    }
    let clashes: Vec<String> = CobId::all_of(node)
        .iter()
        .filter_map(|c| dbc_message_on(c.raw()).map(|m| format!("{:#05x} ({m})", c.raw())))
        .collect();
    if !clashes.is_empty() {
        return Err(invalid(
            at("node_id"),
            raw,
            format!(
                "a node whose COB-IDs miss hand.dbc's ids (node {raw} uses {}; nodes 5 to 127 \
                 are clear)",
                clashes.join(", ")
            ),
        ));
    }
    Ok(node)
}

/// A cia402 finger's scaling: every field present and hand-canopen's checks passed.
fn scaling_of(d: &DriveConfig, at: &dyn Fn(&str) -> String) -> Result<Scaling, ConfigError> {
    let need = |field: &str, v: Option<f64>| {
        v.ok_or_else(|| invalid(at(field), "(missing)", "required for a cia402 drive"))
    };
    let settings = ScalingSettings {
        rated_torque_mnm: need("rated_torque_mnm", d.rated_torque_mnm)?,
        gear_ratio: need("gear_ratio", d.gear_ratio)?,
        moment_arm_m: need("moment_arm_m", d.moment_arm_m)?,
        max_torque_permille: d
            .max_torque_permille
            .ok_or_else(|| invalid(at("max_torque_permille"), "(missing)", "1 to 32767"))?,
        max_speed_rpm: d
            .max_speed_rpm
            .ok_or_else(|| invalid(at("max_speed_rpm"), "(missing)", "1 to 2147483647"))?,
    };
    settings.validate().map_err(|e| match e {
        hand_canopen::scaling::ScalingError::NotPositive { field, value } => {
            invalid(at(field), value, "finite and > 0")
        }
        hand_canopen::scaling::ScalingError::Limit(field) => invalid(
            at(field),
            match field {
                "max_torque_permille" => settings.max_torque_permille.to_string(),
                _ => settings.max_speed_rpm.to_string(),
            },
            "1 to the drive object's range (32767 per mille, 2147483647 rpm)",
        ),
    })
}

/// handd's node id and SYNC COB-ID, when a finger has a cia402 drive: the SYNC id on no
/// hand.dbc id, not NMT's and none of a drive's (the node ids in `taken`).
fn master_of(
    canopen: &CanopenConfig,
    taken: &BTreeMap<u8, String>,
) -> Result<(NodeId, CobId), ConfigError> {
    let master = NodeId::try_new(canopen.master_node_id).map_err(|_| {
        invalid(
            "canopen.master_node_id".into(),
            canopen.master_node_id,
            "1 to 127",
        )
    })?;
    let sync = CobId::try_new(canopen.sync_cob_id)
        .filter(|c| *c != CobId::NMT)
        .ok_or_else(|| {
            invalid(
                "canopen.sync_cob_id".into(),
                canopen.sync_cob_id,
                "an 11-bit id, 0x001 to 0x7FF",
            )
        })?;
    let clash = dbc_message_on(sync.raw())
        .map(|m| format!("{m}'s id in hand.dbc"))
        .or_else(|| {
            taken.keys().find_map(|&n| {
                let node = NodeId::try_new(n).ok()?;
                CobId::all_of(node)
                    .contains(&sync)
                    .then(|| format!("a COB-ID of drive node {n}"))
            })
        });
    if let Some(what) = clash {
        return Err(invalid(
            "canopen.sync_cob_id".into(),
            format!("{:#05x}", sync.raw()),
            format!(
                "an id no other message uses (it is {what}; the default 0x07F is clear: CiA 301 \
                 leaves 0x001 to 0x07F unused)"
            ),
        ));
    }
    Ok((master, sync))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::Config;

    /// A field's name and how a case spoils it.
    type Case = (&'static str, fn(&mut DriveConfig));

    /// A complete cia402 drive table for node `node`.
    fn cia402(node: u8) -> DriveConfig {
        DriveConfig {
            profile: Profile::Cia402,
            node_id: Some(node),
            mode: Some(DriveMode::Cst),
            rated_torque_mnm: Some(25.0),
            gear_ratio: Some(64.0),
            moment_arm_m: Some(0.04),
            max_torque_permille: Some(1000),
            max_speed_rpm: Some(8000),
        }
    }

    fn with(f: usize, d: DriveConfig) -> Config {
        let mut c = Config::default();
        c.fingers.get_mut(f).drive = d;
        c
    }

    /// The field an invalid config names.
    fn refused(c: &Config) -> (String, String) {
        match c.drives() {
            Err(ConfigError::Invalid { field, allowed, .. }) => (field, allowed),
            other => panic!("expected a refusal, got {other:?}"),
        }
    }

    #[test]
    fn every_finger_is_native_by_default_and_nothing_is_written_back() {
        let c = Config::default();
        let d = c.drives().expect("valid");
        assert!(d.fingers.iter().all(|f| *f == Drive::Native));
        assert!(!d.any_cia402());
        let text = c.to_toml();
        assert!(
            !text.contains("drive") && !text.contains("canopen"),
            "{text}"
        );
    }

    #[test]
    fn a_complete_cia402_drive_is_taken_with_its_mode_and_scaling() {
        let c = with(1, cia402(5));
        let d = c.drives().expect("valid");
        let Drive::Cia402 {
            node,
            mode,
            scaling,
        } = d.fingers[1]
        else {
            panic!("index is cia402: {:?}", d.fingers[1]);
        };
        assert_eq!((node.get(), mode), (5, Mode::CyclicSyncTorque));
        // 1 N at 40 mm through 64:1 on a 25 mNm motor: 0.625 mNm, 25 per mille.
        assert_eq!(scaling.torque_permille(1.0), 25);
        assert_eq!(
            d.master.map(|(m, s)| (m.get(), s.raw())),
            Some((127, 0x07F))
        );
        assert!(d
            .fingers
            .iter()
            .enumerate()
            .all(|(f, x)| f == 1 || *x == Drive::Native));
        // And through the file: the table parses, validates and comes back the same.
        let back = Config::from_toml(&c.to_toml(), std::path::Path::new("t.toml")).expect("parses");
        assert_eq!(back, c);
    }

    #[test]
    fn each_missing_field_is_named() {
        let cases: [Case; 7] = [
            ("node_id", |d| d.node_id = None),
            ("mode", |d| d.mode = None),
            ("rated_torque_mnm", |d| d.rated_torque_mnm = None),
            ("gear_ratio", |d| d.gear_ratio = None),
            ("moment_arm_m", |d| d.moment_arm_m = None),
            ("max_torque_permille", |d| d.max_torque_permille = None),
            ("max_speed_rpm", |d| d.max_speed_rpm = None),
        ];
        for (field, clear) in cases {
            let mut d = cia402(9);
            clear(&mut d);
            let (named, _) = refused(&with(2, d));
            assert_eq!(named, format!("fingers.middle.drive.{field}"));
        }
    }

    #[test]
    fn impossible_scales_and_limits_are_named() {
        let cases: [Case; 6] = [
            ("rated_torque_mnm", |d| d.rated_torque_mnm = Some(0.0)),
            ("gear_ratio", |d| d.gear_ratio = Some(-3.0)),
            ("moment_arm_m", |d| d.moment_arm_m = Some(f64::NAN)),
            ("max_torque_permille", |d| d.max_torque_permille = Some(0)),
            ("max_torque_permille", |d| {
                d.max_torque_permille = Some(40_000)
            }),
            ("max_speed_rpm", |d| d.max_speed_rpm = Some(0)),
        ];
        for (field, spoil) in cases {
            let mut d = cia402(9);
            spoil(&mut d);
            assert_eq!(
                refused(&with(0, d)).0,
                format!("fingers.thumb.drive.{field}")
            );
        }
    }

    #[test]
    fn a_node_id_out_of_range_shared_or_handds_own_is_refused() {
        for bad in [0, 128, 255] {
            assert_eq!(
                refused(&with(3, cia402(bad))).0,
                "fingers.ring.drive.node_id"
            );
        }
        let mut c = with(0, cia402(9));
        c.fingers.get_mut(4).drive = cia402(9);
        let (field, allowed) = refused(&c);
        assert_eq!(field, "fingers.pinky.drive.node_id");
        assert!(allowed.contains("fingers.thumb.drive.node_id"), "{allowed}");
        let (field, allowed) = refused(&with(0, cia402(127)));
        assert_eq!(field, "fingers.thumb.drive.node_id");
        assert!(allowed.contains("master_node_id"), "{allowed}");
    }

    /// Every node id against hand.dbc: exactly the ones whose predefined COB-IDs fall on one of
    /// its ids are refused (1-4: FINGER_SETPOINT / FINGER_STATUS; 1 also HAND_DIAG).
    #[test]
    fn exactly_the_nodes_whose_cob_ids_fall_on_hand_dbc_are_refused() {
        let dbc: Vec<u32> = MESSAGES.iter().map(|m| m.id).collect();
        for n in 1..=126u8 {
            let collides = CobId::all_of(NodeId::try_new(n).unwrap())
                .iter()
                .any(|c| dbc.contains(&u32::from(c.raw())));
            match with(1, cia402(n)).drives() {
                Ok(_) => assert!(!collides, "node {n} collides and was taken"),
                Err(ConfigError::Invalid { field, allowed, .. }) => {
                    assert!(collides, "node {n} was refused: {allowed}");
                    assert_eq!(field, "fingers.index.drive.node_id");
                    assert!(allowed.contains("hand.dbc"), "{allowed}");
                }
                Err(e) => panic!("{e}"),
            }
        }
        assert!(
            matches!(with(1, cia402(2)).drives(), Err(ConfigError::Invalid { allowed, .. })
            if allowed.contains("0x202") && allowed.contains("FINGER_SETPOINT_2"))
        );
    }

    #[test]
    fn a_sync_cob_id_on_hand_dbc_a_drive_or_nmt_is_refused() {
        for (sync, names) in [
            (0x080, "HAND_ESTOP"),
            (0x085, "drive node 5"),
            (0x705, "drive node 5"),
            (0x000, "0x001 to 0x7FF"),
            (0x800, "0x001 to 0x7FF"),
        ] {
            let mut c = with(0, cia402(5));
            c.canopen.sync_cob_id = sync;
            let (field, allowed) = refused(&c);
            assert_eq!(field, "canopen.sync_cob_id");
            assert!(allowed.contains(names), "{sync:#x}: {allowed}");
        }
        // All native: the CANopen table is not consulted.
        let mut c = Config::default();
        c.canopen.sync_cob_id = 0x080;
        assert!(c.drives().is_ok());
    }

    #[test]
    fn a_native_finger_with_drive_fields_is_refused() {
        let d = DriveConfig {
            profile: Profile::Native,
            ..cia402(9)
        };
        assert_eq!(refused(&with(2, d)).0, "fingers.middle.drive.profile");
    }

    #[test]
    fn the_file_names_a_bad_profile_or_mode_and_an_unknown_field() {
        for (text, says) in [
            ("[fingers.index.drive]\nprofile = \"canopen\"\n", "canopen"),
            (
                "[fingers.index.drive]\nprofile = \"cia402\"\nmode = \"csp\"\n",
                "csp",
            ),
            ("[fingers.index.drive]\nnode = 5\n", "node"),
        ] {
            match Config::from_toml(text, std::path::Path::new("t.toml")) {
                Err(ConfigError::Parse { message, .. }) => {
                    assert!(message.contains(says), "{message}")
                }
                other => panic!("{text}: {other:?}"),
            }
        }
    }
}
