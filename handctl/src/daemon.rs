//! `handctl status`, `tune`, `arm` and `stop`: requests to a running `handd` over its control
//! socket.

use std::path::PathBuf;

use driver::config::{Config, DEFAULT_CONFIG_PATH};
use driver::control::{request, ControlError};
use driver::protocol::{Reply, Request, Status};
use driver::units::FINGER_NAMES;

use super::args::{ArmArgs, DaemonOpts, TuneArgs};
use super::error::CliError;

/// The socket to talk to: `--socket`, else the one named in the config file, else the default.
pub fn socket_of(o: &DaemonOpts) -> Result<PathBuf, CliError> {
    if let Some(s) = &o.socket {
        return Ok(s.clone());
    }
    let path = o
        .config
        .clone()
        .unwrap_or_else(|| PathBuf::from(DEFAULT_CONFIG_PATH));
    match Config::load(&path) {
        Ok(c) => Ok(c.control.socket),
        // Without an explicit --config, a missing default file just means the default socket.
        Err(_) if o.config.is_none() && !path.exists() => Ok(Config::default().control.socket),
        Err(e) => Err(CliError::Config(e)),
    }
}

pub(crate) fn ask(o: &DaemonOpts, req: &Request) -> Result<Reply, CliError> {
    let socket = socket_of(o)?;
    Ok(request(&socket, req)?)
}

pub(crate) fn done(reply: Reply) -> Result<Option<Status>, CliError> {
    match reply {
        Reply::Ok { message, status } => {
            if status.is_none() {
                println!("{message}");
            }
            Ok(status)
        }
        Reply::Refused { reason } => Err(CliError::Usage(format!("handd refused: {reason}"))),
    }
}

/// The model lines of the status: which file runs and what its verification says.
fn format_model(s: &Status) -> String {
    match &s.model {
        Some(m) => format!(
            "model {} ({}, id {})\n{}{}\n{}\n{}{}\n",
            m.path,
            m.kind,
            m.id,
            if m.unverified { "!! " } else { "" },
            m.verification,
            if m.provenance.is_empty() {
                "unknown patient (this handd does not report provenance)"
            } else {
                &m.provenance
            },
            if m.unguarded { "!! " } else { "" },
            if m.guard.is_empty() {
                "beyond the calibration: not reported by this handd"
            } else {
                &m.guard
            }
        ),
        None => "model: not reported by this handd\n".into(),
    }
}

/// The status as a table: the model, the counters, the fingers, the drives, the late ticks.
pub fn format_status(s: &Status) -> String {
    let mut out = format_model(s);
    out += &counters_section(s);
    out += &fingers_section(s);
    out += &drives_section(&s.drives);
    out += &late_ticks_section(&s.late_ticks);
    out
}

/// State and faults (invalid_window with its reason, when this handd reports one), the
/// engine's counters, the latency figures and the bus's.
fn counters_section(s: &Status) -> String {
    let faults = match &s.window {
        Some(w) if s.faults.split(',').any(|f| f == "invalid_window") => {
            format!("{} (window: {w})", s.faults)
        }
        _ => s.faults.clone(),
    };
    let controller = if s.bus.controller.is_empty() {
        "?"
    } else {
        &s.bus.controller
    };
    let c = &s.bus.counters;
    format!(
        "state {}   faults {}\n\
         ticks {}   deadline misses {}   EMG samples lost {}   bad frames {}   windows beyond \
         the calibration {}   implausible {}\n\
         latency (newest sample -> setpoints) p50 {} us  p99 {} us  max {} us\n\
         compute per tick                     p50 {} us  p99 {} us  max {} us\n\
         tick start after its deadline        p50 {} us  p99 {} us  max {} us\n\
         CAN controller {controller}   errors: warning {} passive {} bus-off {} restarted {} \
         no-ACK {} overflow {} protocol {} other {}; transmit queue full {}; reopen failures {}; \
         wall-clock steps {}; receive queue drops (kernel) {}\n",
        s.state,
        faults,
        s.ticks,
        s.deadline_misses,
        s.samples_lost,
        s.bad_frames,
        s.beyond_calibration,
        s.implausible,
        s.latency.p50_us,
        s.latency.p99_us,
        s.latency.max_us,
        s.compute.p50_us,
        s.compute.p99_us,
        s.compute.max_us,
        s.lateness.p50_us,
        s.lateness.p99_us,
        s.lateness.max_us,
        c.warning,
        c.passive,
        c.bus_off,
        c.restarted,
        c.no_ack,
        c.controller_overflow,
        c.protocol,
        c.other,
        c.tx_queue_full,
        c.reopen_failures,
        c.clock_steps,
        c.kernel_drops,
    )
}

/// One line per finger: label, setpoints, reported force, gains, disabled.
fn fingers_section(s: &Status) -> String {
    let mut out = format!(
        "\n{:<7} {:>7} {:>9} {:>11} {:>11} {:>7} {:>7}  {}\n",
        "finger", "label", "force N", "vel rad/s", "reported N", "kf", "kalpha", "",
    );
    for (f, st) in s.fingers.iter().enumerate() {
        out.push_str(&format!(
            "{:<7} {:>7.3} {:>9.2} {:>11.3} {:>11.2} {:>7.2} {:>7.2}  {}\n",
            FINGER_NAMES.get(f).copied().unwrap_or("?"),
            st.label,
            st.force_n,
            st.velocity_rad_s,
            st.reported_force_n,
            st.kf,
            st.kalpha,
            if st.disabled { "DISABLED" } else { "" }
        ));
    }
    out
}

/// The CiA 402 drives, a stopped one flagged (empty without drives).
fn drives_section(drives: &[driver::protocol::DriveLine]) -> String {
    let mut out = String::new();
    if drives.is_empty() {
        return out;
    }
    out += "\nCiA 402 drives\n";
    for d in drives {
        out += &format!(
            "{}{:<7} node {:>3}  {}\n",
            if d.faulted { "!! " } else { "" },
            d.finger,
            d.node,
            d.state
        );
        if let Some(detail) = drive_detail(d) {
            out += &format!("{:18}{detail}\n", "");
        }
    }
    out
}

/// The newest late ticks and where each one's time went (empty when none was late).
fn late_ticks_section(late: &[driver::protocol::LateTick]) -> String {
    let mut out = String::new();
    if late.is_empty() {
        return out;
    }
    // The status keeps up to LATE_TICKS_KEPT; the screen shows the newest few.
    const SHOWN: usize = 8;
    let older = late.len().saturating_sub(SHOWN);
    out += "\nlast late ticks (woke after the deadline + read the bus before starting)\n";
    if older > 0 {
        out += &format!("  ({older} older ones kept: handctl status --json)\n");
    }
    for l in &late[older..] {
        out += &format!(
            "  {:>6} us late = woke {:>6} us + read {:>5} us ({} frames), CPU {}, at \
             CLOCK_MONOTONIC {:.3} s; asleep past the deadline {} us, the loop ran {} us, \
             waited {}x, preempted {}x\n",
            l.lateness_us(),
            l.wake_us,
            l.read_us,
            l.frames,
            l.cpu,
            l.deadline_mono_us as f64 / 1e6,
            l.asleep_us,
            l.ran_us,
            l.waited,
            l.preempted
        );
    }
    out
}

/// `handctl status`.
pub fn status(o: &DaemonOpts, json: bool) -> Result<(), CliError> {
    let status = done(ask(o, &Request::Status)?)?
        .ok_or_else(|| ControlError::BadReply("a reply without the status".into()))?;
    if json {
        println!(
            "{}",
            serde_json::to_string_pretty(&status).map_err(|e| CliError::Usage(e.to_string()))?
        );
    } else {
        print!("{}", format_status(&status));
    }
    Ok(())
}

/// `handctl tune`.
pub fn tune(a: &TuneArgs) -> Result<(), CliError> {
    done(ask(
        &a.daemon,
        &Request::Tune {
            finger: a.finger.clone(),
            kf: a.kf,
            kalpha: a.kalpha,
        },
    )?)
    .map(drop)
}

/// `handctl arm`: handd first compares the last second of the patient at rest with the
/// running model's calibration.
pub fn arm(a: &ArmArgs) -> Result<(), CliError> {
    done(ask(
        &a.daemon,
        &Request::Arm {
            force_rest_mismatch: a.force_rest_mismatch,
        },
    )?)
    .map(drop)
}

/// `handctl stop`.
pub fn stop(o: &DaemonOpts) -> Result<(), CliError> {
    done(ask(o, &Request::Stop)?).map(drop)
}

/// A drive's second line: NMT, CiA 402 power state, feedback age, the EMCY that stopped it
/// (None from a daemon older than these fields).
fn drive_detail(d: &driver::protocol::DriveLine) -> Option<String> {
    if d.nmt.is_empty() {
        return None;
    }
    let mut parts = vec![format!("NMT {}", d.nmt)];
    if let Some(p) = &d.power_state {
        parts.push(format!("CiA 402 {p}"));
    }
    parts.push(match d.feedback_age_ms {
        Some(a) => format!("TPDO1 {a} ms ago"),
        None => "no TPDO1 yet".into(),
    });
    if let Some(e) = &d.emcy {
        parts.push(format!("EMCY {e}"));
    }
    Some(parts.join(", "))
}

/// The status as a table.
#[cfg(test)]
mod tests {
    use super::*;
    use driver::protocol::ModelStatus;

    #[test]
    fn status_shows_the_model_and_its_verification() {
        let model = |verification: &str, unverified| ModelStatus {
            path: "/var/lib/handstack/model.hsm".into(),
            id: "0badf00d".into(),
            kind: "resdd".into(),
            verification: verification.into(),
            unverified,
            patient: Some("P-017".into()),
            provenance: "patient P-017, session fitting-1, calibrated 2026-12-02T13:15:28Z".into(),
            guard: "beyond the calibration: bounded by its envelope; a channel standing alone \
                    is implausible (the calibration's reached 2.36x the next)"
                .into(),
            unguarded: false,
        };
        let mut s = Status {
            model: Some(model(
                "verified: 0 of 3375 rays reverse beyond 0.01 (exact)",
                false,
            )),
            ..Status::default()
        };
        let text = format_status(&s);
        assert!(
            text.starts_with(
                "model /var/lib/handstack/model.hsm (resdd, id 0badf00d)\n\
                 verified: 0 of 3375 rays reverse beyond 0.01 (exact)\n\
                 patient P-017, session fitting-1, calibrated 2026-12-02T13:15:28Z\n\
                 beyond the calibration: bounded by its envelope; a channel standing alone is \
                 implausible (the calibration's reached 2.36x the next)\n"
            ),
            "{text}"
        );
        // A model file from before the alone test: flagged, as an unverified one is.
        let (guard, unguarded) = decoder::model::Envelope::describe(None);
        s.model = Some(ModelStatus {
            guard,
            unguarded,
            ..model(
                "verified: 0 of 3375 rays reverse beyond 0.01 (exact)",
                false,
            )
        });
        assert!(
            format_status(&s).contains("\n!! beyond the calibration: NOT bounded"),
            "{}",
            format_status(&s)
        );
        s.model = Some(model("FORCED: 12 of 3375 rays reverse beyond 0.01", true));
        assert!(format_status(&s).contains("\n!! FORCED: 12 of 3375"));
        s.model = None;
        assert!(format_status(&s).starts_with("model: not reported"));
        // An older daemon's reply, without the field, still parses.
        let json = serde_json::to_value(Status::default()).unwrap();
        assert!(json.get("model").is_none());
        let back: Status = serde_json::from_value(json).unwrap();
        assert_eq!(back.model, None);
    }

    #[test]
    fn status_lists_each_cia402_drive_and_flags_a_stopped_one() {
        use driver::protocol::DriveLine;
        use hand_canopen::master::{DriveFault, DriveStatus};
        use hand_canopen::startup::Identity;
        let running = DriveStatus::Running {
            enabled: true,
            identity: Identity {
                vendor: 0xFB,
                product: Some(0x6050_0000),
                ..Identity::default()
            },
            feedback: None,
        };
        let with_feedback = DriveStatus::Running {
            enabled: true,
            identity: Identity::default(),
            feedback: Some(hand_canopen::master::Feedback {
                statusword: hand_canopen::Statusword::of(
                    hand_canopen::PowerState::OperationEnabled,
                ),
                torque_permille: 0,
                velocity_rpm: 0,
                at_us: 1_000_000,
            }),
        };
        let trip = hand_canopen::Emcy {
            node: hand_canopen::NodeId::try_new(8).unwrap(),
            code: 0x2310,
            register: 0x03,
            vendor: [0; 5],
        };
        let s = Status {
            drives: vec![
                DriveLine::of("index", 5, &running, 1_000_000),
                DriveLine::of(
                    "middle",
                    6,
                    &DriveStatus::Faulted(DriveFault::Rebooted),
                    1_000_000,
                ),
                DriveLine::of("ring", 7, &with_feedback, 1_012_500),
                DriveLine::of("pinky", 8, &DriveStatus::Faulted(DriveFault::Emcy(trip)), 0),
            ],
            ..Status::default()
        };
        let text = format_status(&s);
        assert!(
            text.contains(
                "\nCiA 402 drives\nindex   node   5  Operation enabled, following its setpoint \
                 (vendor 0x000000FB, product 0x60500000)\n                  NMT operational, \
                 no TPDO1 yet\n"
            ),
            "{text}"
        );
        assert!(
            text.contains(
                "\n!! middle  node   6  stopped: booted while configured (power cycle or reset); \
                 reconfigured on arm; `handctl arm` starts it again\n                  NMT \
                 stopped, no TPDO1 yet\n"
            ),
            "{text}"
        );
        assert!(
            text.contains("NMT operational, CiA 402 Operation enabled, TPDO1 12 ms ago\n"),
            "{text}"
        );
        assert!(
            text.contains("NMT stopped, no TPDO1 yet, EMCY 0x2310 "),
            "the EMCY that stopped the drive, with its meaning: {text}"
        );
        // Every finger native: no drive section, and the field is not sent.
        assert!(!format_status(&Status::default()).contains("CiA 402"));
        let json = serde_json::to_value(Status::default()).unwrap();
        assert!(json.get("drives").is_none());
    }

    #[test]
    fn status_says_where_each_late_ticks_time_went() {
        let s = Status {
            late_ticks: vec![driver::protocol::LateTick {
                deadline_mono_us: 224_400_123,
                wake_us: 27_000,
                read_us: 1_500,
                frames: 96,
                cpu: 1,
                asleep_us: 26_000,
                ran_us: 900,
                waited: 2,
                preempted: 0,
            }],
            ..Status::default()
        };
        let text = format_status(&s);
        assert!(
            text.contains(
                "\n   28500 us late = woke  27000 us + read  1500 us (96 frames), CPU 1, at \
                 CLOCK_MONOTONIC 224.400 s; asleep past the deadline 26000 us, the loop ran \
                 900 us, waited 2x, preempted 0x\n"
            ),
            "{text}"
        );
        assert!(!format_status(&Status::default()).contains("late ticks"));
        // Of many, the newest eight are shown, and where the rest are.
        let tick = |i: u64| driver::protocol::LateTick {
            deadline_mono_us: 1_000_000 * (i + 1),
            wake_us: 26_000,
            ..Default::default()
        };
        let many = Status {
            late_ticks: (0..12).map(tick).collect(),
            ..Status::default()
        };
        let text = format_status(&many);
        assert!(
            text.contains("(4 older ones kept: handctl status --json)"),
            "{text}"
        );
        assert_eq!(text.matches(" us late = ").count(), 8, "{text}");
        assert!(
            !text.contains("CLOCK_MONOTONIC 4.000 s") && text.contains("CLOCK_MONOTONIC 5.000 s"),
            "{text}"
        );
        // invalid_window with its reason; none for another fault.
        let s = Status {
            state: "SAFE".into(),
            faults: "emg_silence,invalid_window".into(),
            window: Some("no EMG frame for 34.0 ms".into()),
            ..Status::default()
        };
        assert!(format_status(&s).contains(
            "state SAFE   faults emg_silence,invalid_window (window: no EMG frame for 34.0 ms)\n"
        ));
        let s = Status {
            faults: "estop".into(),
            ..s
        };
        assert!(!format_status(&s).contains("window:"));
        let json = serde_json::to_value(Status::default()).unwrap();
        assert!(json.get("late_ticks").is_none());
    }
}
