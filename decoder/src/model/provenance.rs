//! Which patient, which session: the model file's `provenance` section ([`Provenance`]).
//! Written by `handctl train` and `handctl calibrate`, shown by `handctl deploy` and `handctl
//! status`; `handd` refuses to swap a model for another patient over the running one unless
//! the deploy says the technician confirmed it. The section only describes the model, so it is
//! not `required` (see the file module's docs): a file without one (written before it existed)
//! loads and is for an "unknown patient".

use std::fmt;

use serde::{Deserialize, Serialize};

/// Longest patient id, characters.
pub const MAX_PATIENT_ID: usize = 64;
/// Longest session id, characters.
pub const MAX_SESSION_ID: usize = 256;

/// Where a model's calibration came from, as its file records it.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Provenance {
    /// The patient's id as the technician gave it (`--patient`); None when none was given.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub patient: Option<String>,
    /// The calibration session: its directory's name (or the importer's description).
    pub session: String,
    /// When the calibration session was recorded (its `session.toml`'s `recorded_utc`), UTC,
    /// to the second: `2026-12-02T13:15:28Z`; when the model was trained, for a session that
    /// records no date (an imported recording).
    pub calibrated_utc: String,
    /// Training was told to go on whatever the quality gates found (`--ignore-gates`).
    pub ignore_gates: bool,
    /// What the quality gates found and training went past, one line per finding (empty: no
    /// gate fired).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub gates_bypassed: Vec<String>,
}

/// Checks a patient id: 1 to [`MAX_PATIENT_ID`] characters, ASCII letters, digits, `.`, `_`,
/// `-` (it goes into the audit log's `key=value` lines as it is).
pub fn check_patient_id(id: &str) -> Result<(), String> {
    if id.is_empty() || id.chars().count() > MAX_PATIENT_ID {
        return Err(format!(
            "patient id {id:?}: must be 1 to {MAX_PATIENT_ID} characters"
        ));
    }
    if let Some(c) = id
        .chars()
        .find(|c| !(c.is_ascii_alphanumeric() || matches!(c, '.' | '_' | '-')))
    {
        return Err(format!(
            "patient id {id:?}: {c:?} is not allowed (letters, digits, '.', '_' and '-' only)"
        ));
    }
    Ok(())
}

/// The UTC time `unix_s` seconds after 1970-01-01T00:00:00Z as `YYYY-MM-DDTHH:MM:SSZ`.
pub fn utc_text(unix_s: u64) -> String {
    // Howard Hinnant's days-to-civil, for the proleptic Gregorian calendar.
    let days = (unix_s / 86_400) as i64;
    let secs = unix_s % 86_400;
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    format!(
        "{y:04}-{m:02}-{d:02}T{:02}:{:02}:{:02}Z",
        secs / 3600,
        secs / 60 % 60,
        secs % 60
    )
}

/// Now, UTC, as [`utc_text`] writes it (the Unix epoch if the clock is before it).
pub fn utc_now() -> String {
    let s = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    utc_text(s)
}

/// True when `t` has the shape [`utc_text`] writes, with months 01-12, days 01-31, hours
/// 00-23, minutes and seconds 00-59 (leap seconds: up to 60).
pub fn is_utc_text(t: &str) -> bool {
    let b = t.as_bytes();
    if b.len() != 20 {
        return false;
    }
    let shape = b.iter().enumerate().all(|(i, c)| match i {
        4 | 7 => *c == b'-',
        10 => *c == b'T',
        13 | 16 => *c == b':',
        19 => *c == b'Z',
        _ => c.is_ascii_digit(),
    });
    let num = |r: std::ops::Range<usize>| t[r].parse::<u32>().unwrap_or(u32::MAX);
    shape
        && (1..=12).contains(&num(5..7))
        && (1..=31).contains(&num(8..10))
        && num(11..13) <= 23
        && num(14..16) <= 59
        && num(17..19) <= 60
}

impl Provenance {
    /// Checks a record read from a file (or built by a program): what is wrong with it.
    pub fn check(&self) -> Result<(), String> {
        if let Some(p) = &self.patient {
            check_patient_id(p)?;
        }
        if self.session.is_empty()
            || self.session.chars().count() > MAX_SESSION_ID
            || self.session.chars().any(char::is_control)
        {
            return Err(format!(
                "session id {:?}: must be 1 to {MAX_SESSION_ID} characters without control \
                 characters",
                self.session
            ));
        }
        if !is_utc_text(&self.calibrated_utc) {
            return Err(format!(
                "calibration date {:?}: expected UTC as YYYY-MM-DDTHH:MM:SSZ",
                self.calibrated_utc
            ));
        }
        if !self.ignore_gates && !self.gates_bypassed.is_empty() {
            return Err(format!(
                "{} quality gate finding(s) bypassed without --ignore-gates",
                self.gates_bypassed.len()
            ));
        }
        if let Some(g) = self
            .gates_bypassed
            .iter()
            .find(|g| g.contains(['\n', '\r']))
        {
            return Err(format!("bypassed gate finding {g:?} spans lines"));
        }
        Ok(())
    }

    /// "patient P-017" or "unknown patient".
    pub fn patient_words(&self) -> String {
        patient_words(self.patient.as_deref())
    }
}

/// "patient P-017", or "unknown patient" for None.
pub fn patient_words(patient: Option<&str>) -> String {
    match patient {
        Some(p) => format!("patient {p}"),
        None => "unknown patient".into(),
    }
}

/// One line: "patient P-017, session fitting-2026-12-02, calibrated 2026-12-02T13:15:28Z",
/// then "; QUALITY GATES BYPASSED (--ignore-gates): 2 finding(s): ..." or "; --ignore-gates
/// given, no gate fired" when training was told to go past them.
impl fmt::Display for Provenance {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}, session {}, calibrated {}",
            self.patient_words(),
            self.session,
            self.calibrated_utc
        )?;
        match (self.ignore_gates, self.gates_bypassed.len()) {
            (false, _) => Ok(()),
            (true, 0) => write!(f, "; --ignore-gates given, no gate fired"),
            (true, n) => write!(
                f,
                "; QUALITY GATES BYPASSED (--ignore-gates): {n} finding(s): {}",
                self.gates_bypassed.join("; ")
            ),
        }
    }
}

/// The provenance line of a model file that may have none.
pub fn describe_provenance(p: Option<&Provenance>) -> String {
    match p {
        Some(p) => p.to_string(),
        None => "unknown patient (the model file records no provenance)".into(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn utc_text_matches_known_dates() {
        assert_eq!(utc_text(0), "1970-01-01T00:00:00Z");
        assert_eq!(utc_text(951_782_400), "2000-02-29T00:00:00Z");
        assert_eq!(utc_text(1_798_373_728), "2026-12-27T12:15:28Z");
        assert!(is_utc_text(&utc_now()));
        for bad in [
            "2026-13-01T00:00:00Z",
            "2026-12-02 13:15:28Z",
            "yesterday",
            "",
        ] {
            assert!(!is_utc_text(bad), "{bad}");
        }
    }

    #[test]
    fn bad_records_are_refused_with_the_field_named() {
        let good = Provenance {
            patient: Some("P-017".into()),
            session: "fitting-1".into(),
            calibrated_utc: "2026-12-02T13:15:28Z".into(),
            ignore_gates: false,
            gates_bypassed: Vec::new(),
        };
        assert_eq!(good.check(), Ok(()));
        let bad = |p: Provenance, want: &str| {
            let e = p.check().expect_err(want);
            assert!(e.contains(want), "{e}");
        };
        bad(
            Provenance {
                patient: Some("P 017".into()),
                ..good.clone()
            },
            "patient id \"P 017\": ' ' is not allowed",
        );
        bad(
            Provenance {
                session: String::new(),
                ..good.clone()
            },
            "session id",
        );
        bad(
            Provenance {
                calibrated_utc: "today".into(),
                ..good.clone()
            },
            "calibration date \"today\"",
        );
        bad(
            Provenance {
                gates_bypassed: vec!["trial 3: flat".into()],
                ..good.clone()
            },
            "without --ignore-gates",
        );
        assert_eq!(
            describe_provenance(None),
            "unknown patient (the model file records no provenance)"
        );
    }
}
