//! The technicians' control protocol between `handctl` and `handd`: one JSON object per line
//! over a Unix socket, one request and one reply per connection; after a `subscribe` reply the
//! daemon goes on writing one [`crate::live::Live`] per line until the client closes.

use serde::{Deserialize, Serialize};

use crate::stats::Percentiles;
use crate::units::{FINGER_NAMES, N_FINGERS};

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
    /// Clear latched faults, once the live rest pattern per channel matches the running
    /// model's calibration ([`crate::rest_check`]); the patient must be at rest.
    Arm {
        /// Arm although the live rest pattern differs from the calibration's (audited).
        #[serde(default, skip_serializing_if = "std::ops::Not::not")]
        force_rest_mismatch: bool,
    },
    /// Go to SAFE and stay there until `arm`.
    Stop,
    /// Stream one [`crate::live::Live`] line every `every_ms` (rounded to whole ticks) until
    /// the client closes.
    Subscribe {
        /// Period, ms: at least one tick, at most [`MAX_SUBSCRIBE_MS`]; [`DEFAULT_SUBSCRIBE_MS`]
        /// when left out.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        every_ms: Option<u64>,
    },
    /// A calibration begins: hold the hand in safe stop until a model is deployed (or rolled
    /// back) and an explicit `arm` follows.
    Calibrating,
    /// Check the model file at `path` off the control loop and swap it in at a tick boundary;
    /// the model it replaces is kept for `rollback`. Refused with the reason, nothing
    /// changed, for a bad model.
    Deploy {
        /// The model file, an absolute path on the daemon's machine.
        path: String,
        /// Deploy a model whose file records no verification, or a failed (or forced) one.
        #[serde(default, skip_serializing_if = "std::ops::Not::not")]
        force: bool,
        /// The technician confirmed replacing the running model with one for another (or an
        /// unknown) patient; without it such a deploy is refused.
        #[serde(default, skip_serializing_if = "std::ops::Not::not")]
        confirmed: bool,
        /// Only check: every check but the patient's, then answer without installing or
        /// swapping anything (`handctl deploy` asks this first, so a model handd would refuse
        /// anyway is refused before the technician is asked about the patient).
        #[serde(default, skip_serializing_if = "std::ops::Not::not")]
        check_only: bool,
    },
    /// Swap back the model the last deploy replaced.
    Rollback,
}

/// A subscription's period when the request names none, ms.
pub const DEFAULT_SUBSCRIBE_MS: u64 = 100;
/// The longest subscription period, ms.
pub const MAX_SUBSCRIBE_MS: u64 = 60_000;

/// The ticks between two lines of a subscription asking for `every_ms` on a loop ticking every
/// `tick_ms`: `every_ms` rounded to whole ticks. Refused, with the allowed range, below one
/// tick or above [`MAX_SUBSCRIBE_MS`].
pub fn subscribe_ticks(every_ms: Option<u64>, tick_ms: u64) -> Result<u64, String> {
    let every = every_ms.unwrap_or(DEFAULT_SUBSCRIBE_MS);
    let tick_ms = tick_ms.max(1);
    if every < tick_ms || every > MAX_SUBSCRIBE_MS {
        return Err(format!(
            "every_ms {every} is out of range: {tick_ms} (one tick) to {MAX_SUBSCRIBE_MS}"
        ));
    }
    Ok(((every + tick_ms / 2) / tick_ms).max(1))
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
    /// Why the EMG window cannot drive the fingers now (the reason of `invalid_window`), if it
    /// cannot (absent from a daemon older than this field).
    #[serde(default)]
    pub window: Option<String>,
    /// Ticks since start.
    pub ticks: u64,
    /// Deadline misses since start.
    pub deadline_misses: u64,
    /// EMG samples lost (bridged) since start.
    pub samples_lost: u64,
    /// Frames with an unknown id or a wrong length since start.
    pub bad_frames: u64,
    /// Windows beyond the calibration's envelope since start, held inside it before the model
    /// (absent from a daemon older than this field).
    #[serde(default)]
    pub beyond_calibration: u64,
    /// Windows found implausible since start (one channel far beyond the calibration while
    /// the others are not): rest and `signal_quality` (absent from a daemon older than this
    /// field).
    #[serde(default)]
    pub implausible: u64,
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
    /// The CAN bus: the controller's error state and every error class counted (absent from
    /// a daemon older than this field).
    #[serde(default)]
    pub bus: BusStatus,
    /// Each CiA 402 finger's drive (none when every finger is native, and from a daemon older
    /// than this field).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub drives: Vec<DriveLine>,
    /// The last ticks that started later than the deadline slack, oldest first (at most
    /// [`LATE_TICKS_KEPT`]; none on time, and from a daemon older than this field).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub late_ticks: Vec<LateTick>,
}

/// Late ticks a status keeps.
pub const LATE_TICKS_KEPT: usize = 32;

/// A tick that started later than the deadline slack, and where its time went: the loop
/// waking up after the deadline (the scheduler, or a machine that did not run), then the bus
/// read and the commands before the tick's own work.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
pub struct LateTick {
    /// The tick's deadline on the machine's CLOCK_MONOTONIC, µs (to line it up with what
    /// other processes on the machine saw at that time).
    pub deadline_mono_us: u64,
    /// From the deadline to the loop awake, µs.
    pub wake_us: u64,
    /// The bus read and the commands after waking, µs.
    pub read_us: u64,
    /// Frames that read took in.
    pub frames: u64,
    /// The CPU the loop ran the tick on.
    pub cpu: u32,
    /// Of the lateness, how long the loop still slept past the deadline (its timer had expired
    /// and the kernel had not run it yet: the scheduler, or a machine that did not run), µs.
    #[serde(default)]
    pub asleep_us: u64,
    /// Thread CPU time the loop used from its last wake-up to the tick's start (reading the bus
    /// between ticks and at the deadline: handd's own work), µs. The rest of the lateness
    /// after `asleep_us` is time the loop was awake but not running.
    #[serde(default)]
    pub ran_us: u64,
    /// Times the loop gave up its CPU to wait from its last wake-up to the tick's start
    /// (voluntary context switches: a lock, a page, the kernel): not zero when it was blocked.
    #[serde(default)]
    pub waited: u32,
    /// Times another thread took its CPU in that time (involuntary context switches: a higher
    /// priority, or the kernel's RT throttling).
    #[serde(default)]
    pub preempted: u32,
}

impl LateTick {
    /// How late the tick started, µs.
    pub fn lateness_us(&self) -> u64 {
        self.wake_us + self.read_us
    }
}

/// One CiA 402 finger's drive as `handctl status` shows it.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize, Default)]
pub struct DriveLine {
    /// The finger.
    pub finger: String,
    /// The drive's node id.
    pub node: u8,
    /// What it is doing, or why it is stopped.
    pub state: String,
    /// A latched fault: the finger is stopped until `handctl arm`.
    pub faulted: bool,
    /// Its NMT state as handd drives it: `starting` (start-up: reset, pre-operational,
    /// configuration), `operational`, or `stopped` after a fault (empty from an older daemon).
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub nmt: String,
    /// Its CiA 402 power state from the newest TPDO1 statusword (`None` before the first).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub power_state: Option<String>,
    /// Age of the newest TPDO1 at the time of the status, ms (`None` before the first).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub feedback_age_ms: Option<u64>,
    /// The EMCY that stopped it: code and meaning (`None` unless an EMCY did).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub emcy: Option<String>,
}

/// Every CiA 402 finger's line, from the loop's per-finger drive states at `now_us`.
pub fn drive_lines(
    drives: &[Option<(u8, hand_canopen::DriveStatus)>; N_FINGERS],
    now_us: u64,
) -> Vec<DriveLine> {
    drives
        .iter()
        .enumerate()
        .filter_map(|(f, d)| {
            let (node, st) = d.as_ref()?;
            Some(DriveLine::of(FINGER_NAMES[f], *node, st, now_us))
        })
        .collect()
}

impl DriveLine {
    /// The line for finger `finger`'s drive on `node` in `status` at `now_us` (the status's
    /// time, for the feedback's age).
    pub fn of(finger: &str, node: u8, status: &hand_canopen::DriveStatus, now_us: u64) -> Self {
        use hand_canopen::DriveStatus as S;
        let state = match status {
            S::Starting(step) => format!("starting: {step}"),
            S::Running {
                enabled, identity, ..
            } => format!(
                "{} (vendor 0x{:08X}{})",
                if *enabled {
                    "Operation enabled, following its setpoint"
                } else {
                    "held in quick stop (handd is not running the hand)"
                },
                identity.vendor,
                identity
                    .product
                    .map(|p| format!(", product 0x{p:08X}"))
                    .unwrap_or_default()
            ),
            S::Faulted(fault) => format!("stopped: {fault}; `handctl arm` starts it again"),
        };
        let feedback = match status {
            S::Running { feedback, .. } => *feedback,
            _ => None,
        };
        Self {
            finger: finger.into(),
            node,
            state,
            faulted: matches!(status, S::Faulted(_)),
            nmt: match status {
                S::Starting(_) => "starting",
                S::Running { .. } => "operational",
                S::Faulted(_) => "stopped",
            }
            .into(),
            power_state: feedback.map(|fb| {
                fb.statusword
                    .state()
                    .map_or("unknown".into(), |p| p.to_string())
            }),
            feedback_age_ms: feedback.map(|fb| now_us.saturating_sub(fb.at_us) / 1000),
            emcy: match status {
                S::Faulted(hand_canopen::DriveFault::Emcy(e)) => {
                    Some(format!("0x{:04X} {}", e.code, e.meaning()))
                }
                _ => None,
            },
        }
    }
}

/// The CAN bus as `handctl status` shows it.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize, Default)]
pub struct BusStatus {
    /// error_active, warning, error_passive or bus_off.
    pub controller: String,
    /// Every error class since start.
    pub counters: crate::transport::BusCounters,
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
    /// The patient its file records; None for an unknown patient (a file without provenance,
    /// a model trained without `--patient`, or a daemon older than this field).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub patient: Option<String>,
    /// Its provenance, one line: "patient P-017, session S, calibrated 2026-12-02T13:15:28Z"
    /// (and any quality gates bypassed), or "unknown patient (...)"; empty from an older daemon.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub provenance: String,
    /// Its guard beyond the calibration, one line (`decoder::model::Envelope::describe`);
    /// empty from an older daemon.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub guard: String,
    /// True when the file lacks a guard a model trained today has (no envelope, or the alone
    /// test off): retrain it.
    #[serde(default)]
    pub unguarded: bool,
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
    parse_request_bytes(line.as_bytes())
}

/// Parse one request line as received (not necessarily UTF-8), with a message fit for the
/// technician on error.
pub fn parse_request_bytes(line: &[u8]) -> Result<Request, String> {
    if line.len() > MAX_REQUEST_BYTES {
        return Err(format!("request longer than {MAX_REQUEST_BYTES} bytes"));
    }
    let line = std::str::from_utf8(line)
        .map_err(|e| format!("malformed request: not UTF-8 text ({e})"))?;
    let malformed = |e: serde_json::Error| format!("malformed request: {e}");
    let value: serde_json::Value = serde_json::from_str(line.trim()).map_err(malformed)?;
    let req: Request = Request::deserialize(&value).map_err(|e| name_the_field(&value, e))?;
    // serde ignores unknown fields beside the tag of a variant without fields: check them all.
    let allowed = req.fields();
    if let Some(extra) = value.as_object().and_then(|o| {
        o.keys()
            .find(|k| k.as_str() != "cmd" && !allowed.contains(&k.as_str()))
    }) {
        return Err(format!(
            "malformed request: unknown field `{extra}` (this command takes {})",
            if allowed.is_empty() {
                "none".to_owned()
            } else {
                allowed.join(", ")
            }
        ));
    }
    Ok(req)
}

/// A request that is valid JSON but not a valid command, with the field at fault named: the
/// tagged enum is read from a parsed value, whose errors carry no position, so the field is
/// found by reading the command with each field alone (the one that fails for a reason other
/// than the fields left out is the one at fault).
fn name_the_field(value: &serde_json::Value, e: serde_json::Error) -> String {
    let msg = e.to_string();
    let Some(obj) = value.as_object() else {
        return format!(
            "malformed request: at line 1 column 1: a request is one JSON object ({msg})"
        );
    };
    if msg.contains("variant") || msg.contains("`cmd`") || !obj.contains_key("cmd") {
        return format!("malformed request: field `cmd`: {msg}");
    }
    let culprit = obj
        .iter()
        .filter(|(k, _)| k.as_str() != "cmd")
        .find(|(k, v)| {
            let alone = serde_json::json!({ "cmd": obj["cmd"], k.as_str(): v });
            Request::deserialize(&alone).is_err_and(|e| !e.to_string().starts_with("missing field"))
        });
    match culprit {
        Some((k, _)) => format!("malformed request: field `{k}`: {msg}"),
        None => format!("malformed request: {msg}"),
    }
}

impl Request {
    /// The fields this command takes besides `cmd`.
    fn fields(&self) -> &'static [&'static str] {
        match self {
            Request::Status | Request::Stop | Request::Calibrating | Request::Rollback => &[],
            Request::Deploy { .. } => &["path", "force", "confirmed", "check_only"],
            Request::Arm { .. } => &["force_rest_mismatch"],
            Request::Tune { .. } => &["finger", "kf", "kalpha"],
            Request::Subscribe { .. } => &["every_ms"],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn requests_round_trip() {
        for r in [
            Request::Status,
            Request::Arm {
                force_rest_mismatch: false,
            },
            Request::Arm {
                force_rest_mismatch: true,
            },
            Request::Stop,
            Request::Subscribe { every_ms: None },
            Request::Subscribe {
                every_ms: Some(250),
            },
            Request::Tune {
                finger: "index".into(),
                kf: Some(0.8),
                kalpha: None,
            },
            Request::Calibrating,
            Request::Rollback,
            Request::Deploy {
                path: "/m.hsm".into(),
                force: false,
                confirmed: false,
                check_only: false,
            },
            Request::Deploy {
                path: "/m.hsm".into(),
                force: true,
                confirmed: true,
                check_only: true,
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
    fn subscription_periods_round_to_ticks_within_range() {
        assert_eq!(
            parse_request(r#"{"cmd":"subscribe"}"#).unwrap(),
            Request::Subscribe { every_ms: None }
        );
        assert_eq!(subscribe_ticks(None, 50), Ok(2));
        assert_eq!(subscribe_ticks(Some(50), 50), Ok(1));
        assert_eq!(subscribe_ticks(Some(74), 50), Ok(1));
        assert_eq!(subscribe_ticks(Some(75), 50), Ok(2));
        assert_eq!(subscribe_ticks(Some(60_000), 50), Ok(1200));
        for bad in [0, 49, 60_001] {
            let e = subscribe_ticks(Some(bad), 50).unwrap_err();
            assert!(
                e.contains(&bad.to_string()) && e.contains("50 (one tick)"),
                "{e}"
            );
        }
        assert!(parse_request(r#"{"cmd":"subscribe","every_ms":-5}"#).is_err());
    }

    #[test]
    fn malformed_requests_are_refused_with_a_reason() {
        assert!(parse_request("").unwrap_err().contains("malformed"));
        assert!(parse_request(r#"{"cmd":"explode"}"#)
            .unwrap_err()
            .contains("explode"));
        let e = parse_request(r#"{"cmd":"tune","finger":"index","kf":"x"}"#).unwrap_err();
        assert!(
            e.contains("field `kf`") && e.contains("invalid type"),
            "{e}"
        );
        let e = parse_request(r#"{"cmd":"subscribe","every_ms":-5}"#).unwrap_err();
        assert!(e.contains("field `every_ms`"), "{e}");
        let e = parse_request(r#"{"cmd":"tune","kf":1}"#).unwrap_err();
        assert!(e.contains("missing field `finger`"), "{e}");
        let e = parse_request(r#"{"cmd":"explode"}"#).unwrap_err();
        assert!(e.contains("field `cmd`"), "{e}");
        let e = parse_request("[1,2]").unwrap_err();
        assert!(e.contains("one JSON object"), "{e}");
        assert!(parse_request(&"x".repeat(5000))
            .unwrap_err()
            .contains("longer"));
        for (line, field) in [
            (r#"{"cmd":"status","extra":1}"#, "extra"),
            (r#"{"cmd":"stop","force":true}"#, "force"),
            (r#"{"cmd":"tune","finger":"index","kff":1}"#, "kff"),
            (r#"{"cmd":"subscribe","every":100}"#, "every"),
        ] {
            let e = parse_request(line).unwrap_err();
            assert!(
                e.contains(&format!("unknown field `{field}`")),
                "{line}: {e}"
            );
        }
        // The requests of issue 14, exactly as the calibrating tool sends them.
        assert_eq!(
            parse_request(r#"{"cmd":"deploy","path":"/abs/model.hsm"}"#).unwrap(),
            Request::Deploy {
                path: "/abs/model.hsm".into(),
                force: false,
                confirmed: false,
                check_only: false,
            }
        );
        assert_eq!(
            parse_request(r#"{"cmd":"calibrating"}"#).unwrap(),
            Request::Calibrating
        );
        for (line, want) in [
            (r#"{"cmd":"deploy","path":7}"#, "field `path`"),
            (
                r#"{"cmd":"deploy","path":"/m","confirmed":1}"#,
                "field `confirmed`",
            ),
            (
                r#"{"cmd":"deploy","path":"/m","force":"yes"}"#,
                "field `force`",
            ),
            (r#"{"cmd":"deploy"}"#, "missing field `path`"),
            (
                r#"{"cmd":"deploy","path":"/m","model":1}"#,
                "unknown field `model`",
            ),
            (r#"{"cmd":"rollback","path":"/m"}"#, "unknown field `path`"),
            (
                r#"{"cmd":"calibrating","force":true}"#,
                "unknown field `force`",
            ),
        ] {
            let e = parse_request(line).unwrap_err();
            assert!(e.contains(want), "{line}: {e}");
        }
        assert!(parse_request_bytes(b"{\"cmd\":\"st\xffatus\"}")
            .unwrap_err()
            .contains("UTF-8"));
    }
}
