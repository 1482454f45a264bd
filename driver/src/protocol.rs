//! The technicians' control protocol between `handctl` and `handd`: one JSON object per line
//! over a Unix socket, one request and one reply per connection.

use serde::{Deserialize, Serialize};

use crate::stats::Percentiles;

/// A request from `handctl`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "cmd", rename_all = "snake_case", deny_unknown_fields)]
pub enum Request {
    /// State, faults, per-finger values, latency percentiles.
    Status,
    /// Change one finger's gains; the fields left out keep their value.
    Tune {
        /// Finger name or number ("index", "1").
        finger: String,
        /// New kF, N per label unit.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        kf: Option<f64>,
        /// New kα, rad/s² per label unit.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        kalpha: Option<f64>,
    },
    /// Clear latched faults.
    Arm,
    /// Go to SAFE and stay there until `arm`.
    Stop,
}

/// One finger's live values in a status reply.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
pub struct FingerStatus {
    /// Conditioned label.
    pub label: f64,
    /// Commanded force, N.
    pub force_n: f64,
    /// Commanded velocity, rad/s.
    pub velocity_rad_s: f64,
    /// Force the controller reports, N.
    pub reported_force_n: f64,
    /// Whether the finger is disabled (its controller fell silent).
    pub disabled: bool,
    /// kF in force.
    pub kf: f64,
    /// kα in force.
    pub kalpha: f64,
}

/// The daemon's status.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
pub struct Status {
    /// BOOT, READY, RUNNING or SAFE.
    pub state: String,
    /// Faults in force, comma separated, or "none".
    pub faults: String,
    /// Ticks since start.
    pub ticks: u64,
    /// Deadline misses since start.
    pub deadline_misses: u64,
    /// EMG samples lost (bridged) since start.
    pub samples_lost: u64,
    /// Frames with an unknown id or a wrong length since start.
    pub bad_frames: u64,
    /// Newest sample frame received -> setpoints written.
    pub latency: Percentiles,
    /// Compute time of the tick.
    pub compute: Percentiles,
    /// How late ticks started after their deadlines (a miss is beyond the configured slack).
    #[serde(default)]
    pub lateness: Percentiles,
    /// Per finger, 0 thumb .. 4 pinky.
    pub fingers: Vec<FingerStatus>,
    /// The model running (absent from a daemon older than this field).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub model: Option<ModelStatus>,
}

/// The model a daemon runs, as `handctl status` shows it.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize, Default)]
pub struct ModelStatus {
    /// The model file.
    pub path: String,
    /// Its fingerprint as in HAND_HEARTBEAT, 8 hex digits.
    pub id: String,
    /// resdd, ln, mlp or cnn.
    pub kind: String,
    /// The verification its file records, one line: "verified: 0 of 3375 rays reverse beyond
    /// 0.01 (exact)", "FORCED: ...", or "NOT verified ...".
    pub verification: String,
    /// True when the file records no verification, or one that reverses (forced or not).
    pub unverified: bool,
}

/// The daemon's answer.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "result", rename_all = "snake_case")]
#[allow(
    clippy::large_enum_variant,
    reason = "one reply per request, built and sent once: boxing the status would save nothing"
)]
pub enum Reply {
    /// The request was carried out.
    Ok {
        /// What was done, for the technician.
        message: String,
        /// The status, for `status`.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        status: Option<Status>,
    },
    /// The request was refused; nothing changed.
    Refused {
        /// Why, with the allowed range where one applies.
        reason: String,
    },
}

/// Longest request line accepted, bytes: a request is a few dozen bytes, so anything longer
/// is refused rather than buffered.
pub const MAX_REQUEST_BYTES: usize = 4096;

/// Parse one request line, with a message fit for the technician on error.
pub fn parse_request(line: &str) -> Result<Request, String> {
    if line.len() > MAX_REQUEST_BYTES {
        return Err(format!("request longer than {MAX_REQUEST_BYTES} bytes"));
    }
    serde_json::from_str(line.trim()).map_err(|e| format!("malformed request: {e}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn requests_round_trip() {
        for r in [
            Request::Status,
            Request::Arm,
            Request::Stop,
            Request::Tune {
                finger: "index".into(),
                kf: Some(0.8),
                kalpha: None,
            },
        ] {
            let line = serde_json::to_string(&r).unwrap();
            assert_eq!(parse_request(&line).unwrap(), r, "{line}");
        }
        assert_eq!(
            parse_request(r#"{"cmd":"tune","finger":"ring","kf":1.5,"kalpha":3}"#).unwrap(),
            Request::Tune {
                finger: "ring".into(),
                kf: Some(1.5),
                kalpha: Some(3.0)
            }
        );
    }

    #[test]
    fn malformed_requests_are_refused_with_a_reason() {
        assert!(parse_request("").unwrap_err().contains("malformed"));
        assert!(parse_request(r#"{"cmd":"explode"}"#)
            .unwrap_err()
            .contains("explode"));
        assert!(parse_request(r#"{"cmd":"tune","finger":"index","kf":"x"}"#).is_err());
        assert!(parse_request(&"x".repeat(5000))
            .unwrap_err()
            .contains("longer"));
    }
}
