//! Live tuning by technicians: a `tune` request checked against the allowed ranges, persisted
//! atomically to the config file and appended to the audit log, or refused with nothing changed.

use std::fs::OpenOptions;
use std::io::Write;
use std::path::Path;

use crate::config::{limits, Config, FingerConfig};
use crate::units::{finger_index, FINGER_NAMES};

/// An accepted change of one finger's gains.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TuneChange {
    /// Finger index, 0 thumb .. 4 pinky.
    pub finger: usize,
    /// Settings before.
    pub old: FingerConfig,
    /// Settings after.
    pub new: FingerConfig,
}

/// Check a tune request against `config`; on success return the change (nothing is applied).
/// A refusal says what is wrong and the allowed range.
pub fn plan_tune(
    config: &Config,
    finger: &str,
    kf: Option<f64>,
    kalpha: Option<f64>,
) -> Result<TuneChange, String> {
    let f = finger_index(finger).ok_or_else(|| {
        format!(
            "unknown finger {finger:?}: use one of {} or 0 to 4",
            FINGER_NAMES.join(", ")
        )
    })?;
    if kf.is_none() && kalpha.is_none() {
        return Err("nothing to change: give --kf and/or --kalpha".into());
    }
    let old = *config.fingers.get(f);
    let mut new = old;
    if let Some(v) = kf {
        new.kf = v;
    }
    if let Some(v) = kalpha {
        new.kalpha = v;
    }
    new.validate(&format!("fingers.{}", FINGER_NAMES[f]))
        .map_err(|e| {
            format!(
                "{e} (kf {} to {} N, kalpha {} to {} rad/s²); nothing changed",
                limits::KF.0,
                limits::KF.1,
                limits::KALPHA.0,
                limits::KALPHA.1
            )
        })?;
    Ok(TuneChange {
        finger: f,
        old,
        new,
    })
}

/// Persist `change` into the config file (atomically) and append a line to the audit log.
/// Returns the new config. On error nothing on disk changed, except that the audit log may
/// hold a line for a save that then failed (it says so).
pub fn commit_tune(
    config: &Config,
    change: &TuneChange,
    config_path: &Path,
    user: &str,
) -> Result<Config, String> {
    let mut next = config.clone();
    *next.fingers.get_mut(change.finger) = change.new;
    next.save_atomic(config_path)
        .map_err(|e| format!("could not save the config: {e}; nothing changed"))?;
    if let Err(e) = append_audit(&config.control.audit_log, change, user) {
        tracing::warn!(error = %e, path = %config.control.audit_log.display(), "audit log not written");
    }
    Ok(next)
}

fn append_audit(path: &Path, change: &TuneChange, user: &str) -> std::io::Result<()> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)?;
    }
    let mut f = OpenOptions::new().create(true).append(true).open(path)?;
    writeln!(
        f,
        "{}",
        audit_line(&crate::deploy::audit_times(), user, change)
    )?;
    f.sync_data()
}

/// One audit record: times (`time=… mono=…`, [`crate::deploy::audit_times`]), user, finger,
/// old and new values (space-separated key=value).
pub fn audit_line(times: &str, user: &str, c: &TuneChange) -> String {
    format!(
        "{times} user={user} finger={} kf={}->{} kalpha={}->{}",
        FINGER_NAMES[c.finger], c.old.kf, c.new.kf, c.old.kalpha, c.new.kalpha
    )
}

/// A user's name from `/etc/passwd`, or `uid:N` when unknown.
pub fn user_name(uid: u32) -> String {
    std::fs::read_to_string("/etc/passwd")
        .ok()
        .and_then(|t| {
            t.lines().find_map(|l| {
                let mut it = l.split(':');
                let name = it.next()?;
                let _pw = it.next()?;
                (it.next()?.parse::<u32>().ok()? == uid).then(|| name.to_owned())
            })
        })
        .unwrap_or_else(|| format!("uid:{uid}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tune_is_planned_validated_and_refused_with_the_range() {
        let c = Config::default();
        let ch = plan_tune(&c, "index", Some(0.8), Some(3.0)).unwrap();
        assert_eq!(ch.finger, 1);
        assert_eq!((ch.new.kf, ch.new.kalpha), (0.8, 3.0));
        let e = plan_tune(&c, "index", Some(90.0), None).unwrap_err();
        assert!(
            e.contains("fingers.index.kf")
                && e.contains("0 to 40")
                && e.contains("nothing changed"),
            "{e}"
        );
        assert!(plan_tune(&c, "toe", Some(1.0), None)
            .unwrap_err()
            .contains("unknown finger"));
        assert!(plan_tune(&c, "ring", None, None)
            .unwrap_err()
            .contains("nothing to change"));
        assert!(plan_tune(&c, "ring", Some(f64::NAN), None).is_err());
    }

    #[test]
    fn commit_persists_and_audits() {
        let dir = std::env::temp_dir().join(format!("handd-tune-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("handd.toml");
        let mut c = Config::default();
        c.control.audit_log = dir.join("audit.log");
        c.save_atomic(&path).unwrap();
        let ch = plan_tune(&c, "2", Some(4.5), None).unwrap();
        let next = commit_tune(&c, &ch, &path, "tech").unwrap();
        assert_eq!(next.fingers.middle.kf, 4.5);
        assert_eq!(Config::load(&path).unwrap().fingers.middle.kf, 4.5);
        let audit = std::fs::read_to_string(dir.join("audit.log")).unwrap();
        assert!(
            audit.contains("user=tech finger=middle kf=10->4.5 kalpha=3->3"),
            "{audit}"
        );
        let mono: f64 = audit
            .split(' ')
            .find_map(|kv| kv.strip_prefix("mono="))
            .and_then(|v| v.parse().ok())
            .expect("a mono= field");
        assert!(mono > 0.0 && audit.starts_with("time="), "{audit}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn root_has_a_name() {
        assert_eq!(user_name(0), "root");
        assert_eq!(user_name(4_000_000_000), "uid:4000000000");
    }
}
