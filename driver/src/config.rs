//! The daemon's configuration: `/etc/handstack/handd.toml` by default.
//!
//! Every field is validated once at start (and on every `handctl tune`); an error names the
//! field, the value and the allowed range, and the daemon refuses to start on it. Saving is
//! atomic (temp file, fsync, rename, fsync of the directory), so a crash never leaves a broken
//! file behind.

use std::fmt;
use std::path::{Path, PathBuf};

use decoder::fsio::write_atomic;
use serde::{Deserialize, Serialize};

use crate::conditioner::FingerGains;
use crate::drive_config::{validate_drives, CanopenConfig, DriveConfig, Drives};
use crate::units::{FINGER_NAMES, N_FINGERS};

/// The default location of the config file.
pub const DEFAULT_CONFIG_PATH: &str = "/etc/handstack/handd.toml";

/// Allowed ranges, inclusive. Force and velocity limits match the FINGER_SETPOINT signal
/// ranges of hand.dbc, so a valid config can never ask for a value the bus cannot carry.
pub mod limits {
    /// kF, N per label unit.
    pub const KF: (f64, f64) = (0.0, crate::conditioner::KF_MAX);
    /// kα, rad/s² per label unit.
    pub const KALPHA: (f64, f64) = (0.0, crate::conditioner::KALPHA_MAX);
    /// ω_max, rad/s.
    pub const OMEGA_MAX: (f64, f64) = (0.01, 10.0);
    /// Deadband, label units.
    pub const DEADBAND: (f64, f64) = (0.0, 0.5);
    /// Slew limit, label units per second.
    pub const SLEW: (f64, f64) = (0.1, 100.0);
    /// Velocity damping (while acting and at rest), 1/s.
    pub const DAMPING: (f64, f64) = (0.0, 50.0);
    /// Time a gain ramps across its whole range, s.
    pub const RAMP_S: (f64, f64) = (0.1, 10.0);
    /// Largest label change per tick the slew limit may allow (`slew · tick`): half the
    /// label's range, so a sign reversal (+1 to -1) takes at least four ticks and no single
    /// window, however wrong, can reverse a finger.
    pub const SLEW_PER_TICK_MAX: f64 = 0.5;
    /// Tick period, ms.
    pub const TICK_MS: (u64, u64) = (10, 100);
    /// EMG silence and finger silence timeouts, ms.
    pub const SILENCE_MS: (u64, u64) = (20, 1000);
    /// Lateness of a tick's start that still meets its deadline, ms (at most half a tick).
    pub const DEADLINE_SLACK_MS: (u64, u64) = (1, 50);
    /// Recovery time of transient faults, ms.
    pub const RECOVERY_MS: (u64, u64) = (100, 10_000);
}

/// A configuration error. Keeps the cause and names what to fix.
#[derive(Debug, thiserror::Error)]
pub enum ConfigError {
    /// The file could not be read or written.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        #[source]
        source: std::io::Error,
    },
    /// The file could not be replaced atomically.
    #[error(transparent)]
    Write(#[from] decoder::fsio::WriteError),
    /// The file is not valid TOML or has unknown or mistyped fields.
    #[error("{path}: {message}")]
    Parse {
        /// The file.
        path: PathBuf,
        /// The parser's message, with line and column.
        message: String,
    },
    /// A field is out of its allowed range.
    #[error("{field} = {value} is not allowed: {allowed}")]
    Invalid {
        /// The field, as `fingers.index.kf`.
        field: String,
        /// The value found.
        value: String,
        /// The allowed range or values.
        allowed: String,
    },
}

/// Per-finger settings as written in the file.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FingerConfig {
    /// Force per label unit, N.
    pub kf: f64,
    /// Angular acceleration per label unit, rad/s².
    pub kalpha: f64,
    /// Largest commanded velocity, rad/s.
    pub omega_max: f64,
    /// Deadband on the label.
    pub deadband: f64,
    /// Slew limit on the label, per second.
    pub slew: f64,
    /// Velocity damping toward zero while the patient acts, 1/s (0 with `rest_damping` 0
    /// reproduces the paper's pure integrator).
    pub damping: f64,
    /// Velocity damping toward zero while the label is inside the deadband, 1/s.
    pub rest_damping: f64,
    /// Seconds a gain takes to ramp across its whole range (a live tune, every start from rest).
    pub ramp_s: f64,
    /// How its setpoints reach the motor: hand.dbc's (default) or a CiA 402 drive's.
    #[serde(skip_serializing_if = "DriveConfig::is_default")]
    pub drive: DriveConfig,
}

impl Default for FingerConfig {
    fn default() -> Self {
        let g = FingerGains::default();
        Self {
            kf: g.kf,
            kalpha: g.kalpha,
            omega_max: g.omega_max,
            deadband: g.deadband,
            slew: g.slew_per_s,
            damping: g.damping_per_s,
            rest_damping: g.rest_damping_per_s,
            ramp_s: g.ramp_s,
            drive: DriveConfig::default(),
        }
    }
}

impl FingerConfig {
    /// The conditioner's view of these settings.
    pub fn gains(&self) -> FingerGains {
        FingerGains {
            kf: self.kf,
            kalpha: self.kalpha,
            omega_max: self.omega_max,
            deadband: self.deadband,
            slew_per_s: self.slew,
            damping_per_s: self.damping,
            rest_damping_per_s: self.rest_damping,
            ramp_s: self.ramp_s,
        }
    }
}

/// The five fingers' settings, by name.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields, default)]
pub struct Fingers {
    /// Finger 0.
    pub thumb: FingerConfig,
    /// Finger 1.
    pub index: FingerConfig,
    /// Finger 2.
    pub middle: FingerConfig,
    /// Finger 3.
    pub ring: FingerConfig,
    /// Finger 4.
    pub pinky: FingerConfig,
}

impl Fingers {
    /// Finger `f`'s settings (0 thumb .. 4 pinky).
    pub fn get(&self, f: usize) -> &FingerConfig {
        match f {
            0 => &self.thumb,
            1 => &self.index,
            2 => &self.middle,
            3 => &self.ring,
            _ => &self.pinky,
        }
    }

    /// Finger `f`'s settings, mutable.
    pub fn get_mut(&mut self, f: usize) -> &mut FingerConfig {
        match f {
            0 => &mut self.thumb,
            1 => &mut self.index,
            2 => &mut self.middle,
            3 => &mut self.ring,
            _ => &mut self.pinky,
        }
    }
}

/// Timeouts, ms.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Timeouts {
    /// No EMG frame for this long is a fault.
    pub emg_silence_ms: u64,
    /// A finger controller silent for this long is disabled.
    pub finger_silence_ms: u64,
    /// Transient faults clear after this long of good signal.
    pub recovery_ms: u64,
}

impl Default for Timeouts {
    fn default() -> Self {
        Self {
            emg_silence_ms: 100,
            finger_silence_ms: 100,
            recovery_ms: 500,
        }
    }
}

/// The technicians' control socket.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ControlConfig {
    /// Path of the Unix socket.
    pub socket: PathBuf,
    /// Group allowed to connect (besides root and the daemon's user); none = owner only.
    pub group: Option<String>,
    /// Audit log of every accepted change.
    pub audit_log: PathBuf,
}

impl Default for ControlConfig {
    fn default() -> Self {
        Self {
            socket: PathBuf::from("/run/handstack/handctl.sock"),
            group: Some("handstack".into()),
            audit_log: PathBuf::from("/var/lib/handstack/audit.log"),
        }
    }
}

/// What a deployed model's recorded verification must show (issue 32): a model verified with a
/// loose tolerance, or on a handful of rays, proves little, and `deploy` refuses it without
/// `--force` as it refuses a failed one.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct DeployConfig {
    /// The largest verification tolerance accepted (label units; `handctl train` verifies at
    /// 0.01 unless told otherwise).
    pub max_tolerance: f64,
    /// The fewest calibration rays the verification must have checked.
    pub min_rays: usize,
}

impl Default for DeployConfig {
    fn default() -> Self {
        Self {
            max_tolerance: 0.05,
            min_rays: 100,
        }
    }
}

/// The input plausibility check (issue 25): a window with one channel standing alone (a
/// pressed, lifted, knocked or hit electrode, not an effort), or whose channel pattern lies off
/// every combination of the calibration's movements (a band turned on the forearm), gives rest
/// and raises `signal_quality` for as long as it lasts.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PlausibilityConfig {
    /// A window is implausible when its top channel (RMS over the calibration's largest) is
    /// above `decoder::model::PLAUSIBLE_FLOOR` and more than the next channel's times the
    /// larger of `spread` and the calibration's own ratio with its margin, or above 1 and more
    /// than `spread` times the median channel's
    /// (`decoder::model::Envelope::implausible`). Lower catches
    /// smaller artefacts and risks stopping a genuine uneven contraction; higher the reverse.
    /// 1.5 to 100.
    pub spread: f64,
    /// A window is implausible when its top channel is above the floor and its per-channel
    /// power misfits the calibration's channel patterns by more than `pattern_margin` times the
    /// worst misfit of the calibration's own windows (at least
    /// `decoder::model::CONE_LEAST`; `decoder::model::PatternCone`). Lower catches a smaller
    /// turn of the band and risks stopping a genuine combination of movements; higher the
    /// reverse. 1.2 to 100.
    pub pattern_margin: f64,
}

impl Default for PlausibilityConfig {
    fn default() -> Self {
        Self {
            spread: decoder::model::PLAUSIBLE_SPREAD,
            pattern_margin: decoder::model::CONE_MARGIN,
        }
    }
}

/// The whole configuration.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Config {
    /// SocketCAN interface name.
    pub interface: String,
    /// Path of the trained model file.
    pub model: PathBuf,
    /// Tick period, ms (50 in the paper).
    pub tick_ms: u64,
    /// A tick starting more than this after its deadline counts as a deadline miss (and the
    /// systemd watchdog is not fed for it), ms; at most half of `tick_ms`.
    pub deadline_slack_ms: u64,
    /// Mains frequency for the notch, Hz: 50 or 60.
    pub mains_hz: u32,
    /// Timeouts.
    pub timeouts: Timeouts,
    /// Per-finger gains and limits.
    pub fingers: Fingers,
    /// The control socket.
    pub control: ControlConfig,
    /// What `deploy` demands of a model's verification.
    pub deploy: DeployConfig,
    /// The input plausibility check.
    pub plausibility: PlausibilityConfig,
    /// Where handd keeps what must survive a restart (its latches: see `driver::persist`).
    pub state_dir: PathBuf,
    /// handd as a CANopen master, for fingers with a `cia402` drive.
    #[serde(skip_serializing_if = "is_default_canopen")]
    pub canopen: CanopenConfig,
}

fn is_default_canopen(c: &CanopenConfig) -> bool {
    *c == CanopenConfig::default()
}

impl Default for Config {
    fn default() -> Self {
        Self {
            interface: "can0".into(),
            model: PathBuf::from("/var/lib/handstack/model.hsm"),
            tick_ms: 50,
            deadline_slack_ms: 5,
            mains_hz: 50,
            timeouts: Timeouts::default(),
            fingers: Fingers::default(),
            control: ControlConfig::default(),
            deploy: DeployConfig::default(),
            plausibility: PlausibilityConfig::default(),
            state_dir: PathBuf::from("/var/lib/handstack"),
            canopen: CanopenConfig::default(),
        }
    }
}

fn check_f64(field: String, v: f64, (lo, hi): (f64, f64)) -> Result<(), ConfigError> {
    if v.is_finite() && v >= lo && v <= hi {
        Ok(())
    } else {
        Err(ConfigError::Invalid {
            field,
            value: v.to_string(),
            allowed: format!("{lo} to {hi}"),
        })
    }
}

fn check_u64(field: &str, v: u64, (lo, hi): (u64, u64)) -> Result<(), ConfigError> {
    if (lo..=hi).contains(&v) {
        Ok(())
    } else {
        Err(ConfigError::Invalid {
            field: field.into(),
            value: v.to_string(),
            allowed: format!("{lo} to {hi}"),
        })
    }
}

impl FingerConfig {
    /// Check every field; `name` prefixes the field in errors (`fingers.index`).
    pub fn validate(&self, name: &str) -> Result<(), ConfigError> {
        use limits::*;
        check_f64(format!("{name}.kf"), self.kf, KF)?;
        check_f64(format!("{name}.kalpha"), self.kalpha, KALPHA)?;
        check_f64(format!("{name}.omega_max"), self.omega_max, OMEGA_MAX)?;
        check_f64(format!("{name}.deadband"), self.deadband, DEADBAND)?;
        check_f64(format!("{name}.slew"), self.slew, SLEW)?;
        check_f64(format!("{name}.damping"), self.damping, DAMPING)?;
        check_f64(format!("{name}.rest_damping"), self.rest_damping, DAMPING)?;
        check_f64(format!("{name}.ramp_s"), self.ramp_s, RAMP_S)
    }

    /// The slew limit against the tick: at most [`limits::SLEW_PER_TICK_MAX`] per tick.
    pub fn validate_slew(&self, name: &str, tick_ms: u64) -> Result<(), ConfigError> {
        let per_tick = self.slew * tick_ms as f64 * 1e-3;
        if per_tick <= limits::SLEW_PER_TICK_MAX + 1e-12 {
            return Ok(());
        }
        Err(ConfigError::Invalid {
            field: format!("{name}.slew"),
            value: self.slew.to_string(),
            allowed: format!(
                "at most {} per second with tick_ms = {tick_ms} (half the label's range per \
                 tick, so that no single window can reverse a finger)",
                limits::SLEW_PER_TICK_MAX / (tick_ms as f64 * 1e-3)
            ),
        })
    }
}

impl Config {
    /// Check every field against its allowed range.
    pub fn validate(&self) -> Result<(), ConfigError> {
        let name_ok = !self.interface.is_empty()
            && self.interface.len() < 16
            && self
                .interface
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || "-_.".contains(c));
        if !name_ok {
            return Err(ConfigError::Invalid {
                field: "interface".into(),
                value: format!("{:?}", self.interface),
                allowed: "a network interface name of 1 to 15 characters [A-Za-z0-9._-]".into(),
            });
        }
        if self.model.as_os_str().is_empty() {
            return Err(ConfigError::Invalid {
                field: "model".into(),
                value: "\"\"".into(),
                allowed: "the path of a model file made by `handctl train`".into(),
            });
        }
        check_u64("tick_ms", self.tick_ms, limits::TICK_MS)?;
        check_u64(
            "deadline_slack_ms",
            self.deadline_slack_ms,
            (
                limits::DEADLINE_SLACK_MS.0,
                limits::DEADLINE_SLACK_MS.1.min(self.tick_ms / 2),
            ),
        )?;
        if self.mains_hz != 50 && self.mains_hz != 60 {
            return Err(ConfigError::Invalid {
                field: "mains_hz".into(),
                value: self.mains_hz.to_string(),
                allowed: "50 or 60".into(),
            });
        }
        let t = &self.timeouts;
        check_u64(
            "timeouts.emg_silence_ms",
            t.emg_silence_ms,
            limits::SILENCE_MS,
        )?;
        check_u64(
            "timeouts.finger_silence_ms",
            t.finger_silence_ms,
            limits::SILENCE_MS,
        )?;
        check_u64("timeouts.recovery_ms", t.recovery_ms, limits::RECOVERY_MS)?;
        for (f, name) in FINGER_NAMES.iter().enumerate().take(N_FINGERS) {
            let finger = self.fingers.get(f);
            finger.validate(&format!("fingers.{name}"))?;
            finger.validate_slew(&format!("fingers.{name}"), self.tick_ms)?;
        }
        check_f64(
            "deploy.max_tolerance".into(),
            self.deploy.max_tolerance,
            (0.0, 0.5),
        )?;
        check_f64(
            "plausibility.spread".into(),
            self.plausibility.spread,
            (1.5, 100.0),
        )?;
        check_f64(
            "plausibility.pattern_margin".into(),
            self.plausibility.pattern_margin,
            (1.2, 100.0),
        )?;
        if !(1..=10_000_000).contains(&self.deploy.min_rays) {
            return Err(ConfigError::Invalid {
                field: "deploy.min_rays".into(),
                value: self.deploy.min_rays.to_string(),
                allowed: "1 to 10000000".into(),
            });
        }
        if self.control.socket.as_os_str().is_empty() {
            return Err(ConfigError::Invalid {
                field: "control.socket".into(),
                value: "\"\"".into(),
                allowed: "a filesystem path for the Unix socket".into(),
            });
        }
        self.drives()?;
        if !self.state_dir.is_absolute() {
            return Err(ConfigError::Invalid {
                field: "state_dir".into(),
                value: format!("{:?}", self.state_dir),
                allowed: "an absolute directory path handd may write (its systemd StateDirectory, /var/lib/handstack)".into(),
            });
        }
        Ok(())
    }

    /// Every finger's drive, checked against the others, handd's node and hand.dbc
    /// ([`crate::drive_config`]).
    pub fn drives(&self) -> Result<Drives, ConfigError> {
        validate_drives(&self.fingers, &self.canopen)
    }

    /// Parse and validate TOML text; `path` only names the source in errors.
    pub fn from_toml(text: &str, path: &Path) -> Result<Self, ConfigError> {
        let cfg: Config = toml::from_str(text).map_err(|e| ConfigError::Parse {
            path: path.to_owned(),
            message: e.to_string().trim_end().to_owned(),
        })?;
        cfg.validate()?;
        Ok(cfg)
    }

    /// Read, parse and validate a config file.
    pub fn load(path: &Path) -> Result<Self, ConfigError> {
        let text = decoder::textfile::read_text(path).map_err(|source| ConfigError::Io {
            path: path.to_owned(),
            source,
        })?;
        Self::from_toml(&text, path)
    }

    /// The config as TOML text.
    pub fn to_toml(&self) -> String {
        toml::to_string_pretty(self).expect("a Config always serialises to TOML")
    }

    /// Validate, then save atomically ([`decoder::fsio::write_atomic`]): write a temp file
    /// beside the target, fsync it, rename it over the target, fsync the directory. A crash at any point leaves either the old or the
    /// new file, never a mix.
    pub fn save_atomic(&self, path: &Path) -> Result<(), ConfigError> {
        self.validate()?;
        Ok(write_atomic(path, self.to_toml().as_bytes())?)
    }
}

impl fmt::Display for FingerConfig {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "kf={} N kalpha={} rad/s² omega_max={} rad/s deadband={} slew={}/s damping={}/s \
             rest_damping={}/s ramp_s={} s",
            self.kf,
            self.kalpha,
            self.omega_max,
            self.deadband,
            self.slew,
            self.damping,
            self.rest_damping,
            self.ramp_s
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::fs;

    #[test]
    fn default_config_is_valid_and_round_trips() {
        let c = Config::default();
        c.validate().unwrap();
        let back = Config::from_toml(&c.to_toml(), Path::new("x.toml")).unwrap();
        assert_eq!(back, c);
    }

    #[test]
    fn partial_file_takes_defaults() {
        let c = Config::from_toml(
            "interface = \"vcan0\"\n[fingers.index]\nkf = 0.8\nkalpha = 3\n",
            Path::new("h.toml"),
        )
        .unwrap();
        assert_eq!(c.interface, "vcan0");
        assert_eq!(c.fingers.index.kf, 0.8);
        assert_eq!(c.fingers.thumb, FingerConfig::default());
    }

    #[test]
    fn out_of_range_names_field_value_and_range() {
        let e = Config::from_toml("[fingers.ring]\nkf = 99.0\n", Path::new("h.toml")).unwrap_err();
        let msg = e.to_string();
        assert!(
            msg.contains("fingers.ring.kf") && msg.contains("99") && msg.contains("0 to 40"),
            "{msg}"
        );
        let e = Config::from_toml("mains_hz = 55\n", Path::new("h.toml")).unwrap_err();
        assert!(e.to_string().contains("mains_hz = 55"), "{e}");
        let e =
            Config::from_toml("[timeouts]\nrecovery_ms = 5\n", Path::new("h.toml")).unwrap_err();
        assert!(e.to_string().contains("timeouts.recovery_ms"), "{e}");
        let e = Config::from_toml("interface = \"a b\"\n", Path::new("h.toml")).unwrap_err();
        assert!(e.to_string().contains("interface"), "{e}");
        // The slack is at most half a tick: a later tick would run into the next one.
        let e = Config::from_toml(
            "tick_ms = 20\ndeadline_slack_ms = 11\n",
            Path::new("h.toml"),
        )
        .unwrap_err();
        assert!(
            e.to_string()
                .contains("deadline_slack_ms = 11 is not allowed: 1 to 10"),
            "{e}"
        );
        let c = Config::from_toml("deadline_slack_ms = 20\n", Path::new("h.toml")).unwrap();
        assert_eq!(c.deadline_slack_ms, 20);
        let e = Config::from_toml("state_dir = \"state\"\n", Path::new("h.toml")).unwrap_err();
        assert!(e.to_string().contains("state_dir = \"state\""), "{e}");
    }

    #[test]
    fn unknown_field_and_bad_syntax_are_refused_with_location() {
        let e = Config::from_toml("[fingers.index]\nkff = 1\n", Path::new("h.toml")).unwrap_err();
        assert!(e.to_string().contains("kff"), "{e}");
        let e = Config::from_toml("tick_ms = \n", Path::new("h.toml")).unwrap_err();
        let msg = e.to_string();
        assert!(msg.contains("h.toml") && msg.contains("line 1"), "{msg}");
        let e = Config::from_toml("kf = nan\n", Path::new("h.toml")).unwrap_err();
        assert!(matches!(e, ConfigError::Parse { .. }), "{e}");
    }

    #[test]
    fn a_slew_that_allows_more_than_half_the_range_per_tick_is_refused() {
        // 10/s at 50 ms is 0.5 per tick: the most allowed; 12/s is 0.6: refused.
        let ok = "tick_ms = 50\n[fingers.middle]\nslew = 10.0\n";
        Config::from_toml(ok, Path::new("h.toml")).unwrap();
        let bad = "tick_ms = 50\n[fingers.middle]\nslew = 12.0\n";
        let e = Config::from_toml(bad, Path::new("h.toml")).unwrap_err();
        let msg = e.to_string();
        assert!(
            msg.contains("fingers.middle.slew") && msg.contains("10 per second"),
            "{msg}"
        );
        // The default slew (10/s) at the longest tick (100 ms) is 1.0 per tick: refused, with
        // the most that tick allows.
        let e = Config::from_toml("tick_ms = 100\n", Path::new("h.toml")).unwrap_err();
        assert!(e.to_string().contains("at most 5 per second"), "{e}");
    }

    #[test]
    fn the_plausibility_spread_is_read_and_checked() {
        let c = Config::from_toml("[plausibility]\nspread = 4.0\n", Path::new("h.toml")).unwrap();
        assert_eq!(c.plausibility.spread, 4.0);
        assert_eq!(
            crate::startup::engine_settings(&c, 0).plausible_spread,
            4.0,
            "the engine gets it"
        );
        assert_eq!(
            Config::default().plausibility.spread,
            decoder::model::PLAUSIBLE_SPREAD
        );
        let c = Config::from_toml(
            "[plausibility]\npattern_margin = 3.0\n",
            Path::new("h.toml"),
        )
        .unwrap();
        assert_eq!(crate::startup::engine_settings(&c, 0).pattern_margin, 3.0);
        assert_eq!(
            Config::default().plausibility.pattern_margin,
            decoder::model::CONE_MARGIN
        );
        for bad in ["1.1", "101.0"] {
            let e = Config::from_toml(
                &format!("[plausibility]\npattern_margin = {bad}\n"),
                Path::new("h.toml"),
            )
            .unwrap_err();
            assert!(
                e.to_string().contains("plausibility.pattern_margin"),
                "{bad}: {e}"
            );
        }
        for bad in ["1.0", "101.0", "nan"] {
            let e = Config::from_toml(
                &format!("[plausibility]\nspread = {bad}\n"),
                Path::new("h.toml"),
            )
            .unwrap_err();
            assert!(
                e.to_string().contains("plausibility.spread") || bad == "nan",
                "{bad}: {e}"
            );
        }
    }

    #[test]
    fn nan_gain_is_refused() {
        let mut c = Config::default();
        c.fingers.pinky.kalpha = f64::NAN;
        let e = c.validate().unwrap_err();
        assert!(e.to_string().contains("fingers.pinky.kalpha"), "{e}");
    }

    #[test]
    fn atomic_save_replaces_the_file_and_refuses_invalid() {
        let dir = std::env::temp_dir().join(format!("handd-cfg-{}", std::process::id()));
        fs::create_dir_all(&dir).unwrap();
        let path = dir.join("handd.toml");
        let mut c = Config::default();
        c.save_atomic(&path).unwrap();
        c.fingers.index.kf = 0.8;
        c.save_atomic(&path).unwrap();
        assert_eq!(Config::load(&path).unwrap().fingers.index.kf, 0.8);
        c.fingers.index.kf = -1.0;
        assert!(c.save_atomic(&path).is_err());
        assert_eq!(
            Config::load(&path).unwrap().fingers.index.kf,
            0.8,
            "unchanged on refusal"
        );
        let leftovers: Vec<_> = fs::read_dir(&dir)
            .unwrap()
            .filter_map(|e| e.ok())
            .filter(|e| e.file_name().to_string_lossy().contains(".tmp."))
            .collect();
        assert!(leftovers.is_empty());
        fs::remove_dir_all(&dir).unwrap();
    }
}

#[cfg(test)]
mod shipped {
    use super::*;

    #[test]
    fn the_shipped_example_config_is_valid_and_holds_the_defaults() {
        let path = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/dist/handd.toml"));
        let c = Config::load(path).unwrap();
        assert_eq!(
            c,
            Config::default(),
            "dist/handd.toml must document the defaults"
        );
    }
}
