//! hand-canopen against python `canopen` 2.4 (see ref/canopen_drive.py), an implementation no
//! one on the project wrote:
//!
//! - our tables (the simulated drive's object dictionary, abort codes, EMCY classes,
//!   statusword decoding, CiA 402 transitions) against the EDS as `canopen` parses it and
//!   against `canopen`'s own tables;
//! - our master core's start-up, PDOs, SDO aborts and EMCY decoding in a frame exchange with
//!   a `canopen.LocalNode` built from `eds/finger_drive.eds`, with the CiA 402 behaviour
//!   scripted around it from `canopen`'s State402 tables.

use std::io::{BufRead, BufReader, Write};
use std::path::PathBuf;
use std::process::{Child, ChildStdin, ChildStdout, Command, Stdio};

use hand_canopen::cia402::{Controlword, Statusword, TRANSITIONS};
use hand_canopen::emcy::{Emcy, ErrorClass, ERROR_CODES};
use hand_canopen::heartbeat::HeartbeatProducer;
use hand_canopen::master::cyclic::rpdo1;
use hand_canopen::master::{Setpoint, TorqueLimit};
use hand_canopen::pdo::{finger_pdos, Direction, PdoConfig};
use hand_canopen::sdo::{SdoClient, SdoError, ABORT_CODES};
use hand_canopen::sim::od::{Access, ObjectDictionary, FINGER_DRIVE_OBJECTS, SIM_VENDOR_ID};
use hand_canopen::startup::{Startup, StartupSettings, ABORT_CONNECTION_QUICK_STOP};
use hand_canopen::{
    AbortCode, CanFrame, Mode, NmtState, NodeId, ObjectAddr, PowerState, StartupStatus,
    SyncProducer,
};
use serde_json::{json, Value};

const DRIVE: u8 = 3;
const MASTER: u8 = 100;
/// The SYNC COB-ID the start-up writes to 0x1005 (not 0x080: hand.dbc's HAND_ESTOP).
const SYNC_COB: u16 = 0x07F;

fn python() -> PathBuf {
    if let Some(p) = std::env::var_os("HANDSTACK_PYTHON") {
        return PathBuf::from(p);
    }
    let fallback = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../.venv/bin/python"));
    assert!(
        fallback.exists(),
        "no Python for the canopen cross-check ({} missing): run ./scripts/test (it creates \
         .venv) or set HANDSTACK_PYTHON to a python with canopen 2.4 (scripts/requirements.txt)",
        fallback.display()
    );
    fallback
}

fn node(id: u8) -> NodeId {
    NodeId::try_new(id).expect("test node id in range")
}

struct PyDrive {
    child: Child,
    stdin: ChildStdin,
    stdout: BufReader<ChildStdout>,
    /// Every frame the Python drive sent, with the time.
    heard: Vec<(u64, CanFrame)>,
}

impl PyDrive {
    fn line(&mut self) -> String {
        let mut s = String::new();
        let n = self
            .stdout
            .read_line(&mut s)
            .expect("read from the canopen script");
        assert!(
            n > 0,
            "the canopen script ended early (see its stderr above)"
        );
        s
    }

    fn send_line(&mut self, l: &str) {
        writeln!(self.stdin, "{l}").expect("write to the canopen script");
        self.stdin.flush().expect("flush");
    }

    /// Sends one line, returns the frames the drive answered.
    fn exchange(&mut self, l: &str, now: u64) -> Vec<CanFrame> {
        self.send_line(l);
        let mut out = Vec::new();
        loop {
            let s = self.line();
            let s = s.trim();
            if s == "." {
                return out;
            }
            let mut p = s.split(' ').skip(1);
            let id = u16::from_str_radix(p.next().expect("id"), 16).expect("hex id");
            let hex = p.next().unwrap_or("");
            let data: Vec<u8> = (0..hex.len() / 2)
                .map(|i| u8::from_str_radix(&hex[2 * i..2 * i + 2], 16).expect("hex byte"))
                .collect();
            let f = CanFrame::new(id, &data).expect("a classic CAN frame");
            self.heard.push((now, f));
            out.push(f);
        }
    }

    fn frame(&mut self, f: &CanFrame, now: u64) -> Vec<CanFrame> {
        let hex: String = f.payload().iter().map(|b| format!("{b:02x}")).collect();
        self.exchange(&format!("F {now} {:03X} {hex}", f.cob_id()), now)
    }

    fn tick(&mut self, now: u64) -> Vec<CanFrame> {
        self.exchange(&format!("T {now}"), now)
    }
}

/// Our tables, for the script to compare with canopen's.
fn init_json() -> Value {
    let od = ObjectDictionary::new(node(DRIVE), FINGER_DRIVE_OBJECTS);
    let objects: Vec<Value> = FINGER_DRIVE_OBJECTS
        .iter()
        .map(|d| {
            let access = match d.access {
                Access::Ro => "ro",
                Access::Rw => "rw",
                Access::Const => "const",
            };
            json!([
                d.addr.index,
                d.addr.sub,
                d.bytes,
                d.signed,
                access,
                d.mappable,
                od.get(d.addr)
            ])
        })
        .collect();
    let aborts: Vec<Value> = ABORT_CODES
        .iter()
        .map(|(a, code, _)| json!([code, format!("{a:?}")]))
        .collect();
    let emcy: Vec<Value> = (0..=0xFFFu16)
        .map(|k| k << 4)
        .chain(ERROR_CODES.iter().map(|(c, _)| *c))
        .map(|c| json!([c, format!("{:?}", ErrorClass::of(c))]))
        .collect();
    let statuswords: Vec<Value> = (0..=0xFFu16)
        .chain((0..=0x7Fu16).map(|s| s | 0x0200 | 0x0400))
        .map(|sw| json!([sw, Statusword(sw).state().map(|s| s.to_string())]))
        .collect();
    let transitions: Vec<Value> = TRANSITIONS
        .iter()
        .map(|t| {
            json!([
                t.from.to_string(),
                t.command.controlword().0,
                t.to.to_string()
            ])
        })
        .collect();
    json!({
        "eds": concat!(env!("CARGO_MANIFEST_DIR"), "/eds/finger_drive.eds"),
        "node": DRIVE,
        "objects": objects,
        "abort_codes": aborts,
        "emcy": emcy,
        "statuswords": statuswords,
        "transitions": transitions,
    })
}

/// The master side: start-up, handd's heartbeat, SYNC, stepping 1 ms at a time.
struct Master {
    now: u64,
    startup: Startup,
    heartbeat: Option<HeartbeatProducer>,
    sync: Option<SyncProducer>,
}

impl Master {
    fn deliver(&mut self, py: &mut PyDrive, first: Vec<CanFrame>) {
        let mut queue = first;
        while !queue.is_empty() {
            let f = queue.remove(0);
            // An answer arrives after its request was sent (about 100 us at 1 Mbit/s).
            self.now += 100;
            for r in py.frame(&f, self.now) {
                queue.extend(self.startup.on_frame(&r, self.now));
            }
        }
    }

    fn step(&mut self, py: &mut PyDrive) {
        self.now += 1_000;
        let now = self.now;
        let mut out = Vec::new();
        if let Some(hb) = self.heartbeat.as_mut() {
            out.extend(hb.poll(now, NmtState::Operational));
        }
        if let Some(s) = self.sync.as_mut() {
            out.extend(s.poll(now));
        }
        while let Some(f) = self.startup.poll(now) {
            out.push(f);
        }
        self.deliver(py, out);
        let replies = py.tick(now);
        let next: Vec<CanFrame> = replies
            .iter()
            .filter_map(|r| self.startup.on_frame(r, now))
            .collect();
        self.deliver(py, next);
    }
}

fn assert_maps_agree(ours: &[PdoConfig], theirs: &Value, direction: Direction) {
    let theirs = theirs.as_array().expect("list of maps");
    let ours: Vec<&PdoConfig> = ours.iter().filter(|p| p.direction == direction).collect();
    assert_eq!(ours.len(), theirs.len(), "{direction:?} count");
    for (p, t) in ours.iter().zip(theirs) {
        assert_eq!(t["number"], json!(p.number));
        assert_eq!(
            t["enabled"],
            json!(p.enabled()),
            "{direction:?}{} validity",
            p.number
        );
        if !p.enabled() {
            continue;
        }
        assert_eq!(
            t["cob_id"],
            json!(p.cob_id.raw()),
            "{direction:?}{}",
            p.number
        );
        assert_eq!(t["trans_type"], json!(p.transmission_type));
        let vars: Vec<Value> = p
            .entries
            .iter()
            .map(|e| json!([e.addr.index, e.addr.sub, e.bits]))
            .collect();
        assert_eq!(t["vars"], json!(vars), "{direction:?}{} mapping", p.number);
    }
}

/// The canopen script started, our tables checked against it (its first answer).
fn spawn_with_tables_checked() -> PyDrive {
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/ref/canopen_drive.py");
    let mut child = Command::new(python())
        .arg(script)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .spawn()
        .expect("start the canopen script");
    let stdin = child.stdin.take().expect("stdin");
    let stdout = BufReader::new(child.stdout.take().expect("stdout"));
    let mut py = PyDrive {
        child,
        stdin,
        stdout,
        heard: Vec::new(),
    };

    py.send_line(&init_json().to_string());
    let report: Value = serde_json::from_str(&py.line()).expect("report JSON");
    let mismatches = report["mismatches"].as_array().expect("mismatch list");
    assert!(
        mismatches.is_empty(),
        "hand-canopen and canopen disagree:\n{}",
        serde_json::to_string_pretty(mismatches).unwrap_or_default()
    );
    for (what, at_least) in [
        ("objects", FINGER_DRIVE_OBJECTS.len()),
        ("abort_codes", 20),
        ("statuswords", 256),
        ("transitions", 12),
    ] {
        let n = report["checked"][what].as_u64().unwrap_or(0);
        assert!(n as usize >= at_least, "only {n} {what} compared");
    }
    py
}

/// Our start-up in `mode` against the LocalNode drive, to Operation enabled.
fn start_up(py: &mut PyDrive, mode: Mode) -> Master {
    let settings = StartupSettings {
        node: node(DRIVE),
        master: node(MASTER),
        mode,
        sync_period_us: 10_000,
        // Not 0x080 (hand.dbc's HAND_ESTOP): canopen's drive must take SYNC where 0x1005 says.
        sync_cob_id: hand_canopen::CobId::try_new(SYNC_COB).expect("11 bits"),
        master_heartbeat_timeout_ms: 100,
        drive_heartbeat_ms: 20,
        abort_connection: ABORT_CONNECTION_QUICK_STOP,
        quick_stop_option: hand_canopen::startup::QUICK_STOP_RAMP_THEN_DISABLE,
        sdo_timeout_us: 20_000,
        step_timeout_us: 200_000,
    };
    let steps = settings.plan().expect("valid settings");
    let mut m = Master {
        now: 0,
        startup: Startup::new(node(DRIVE), steps, 20_000, 200_000),
        heartbeat: Some(HeartbeatProducer::new(node(MASTER), 10_000)),
        sync: None,
    };
    while m.now < 2_000_000 && matches!(m.startup.status(), StartupStatus::Running(_)) {
        m.step(py);
    }
    let StartupStatus::Done { identity, .. } = m.startup.status() else {
        panic!(
            "start-up in {mode:?} against canopen's LocalNode: {:?}",
            m.startup.status()
        );
    };
    assert_eq!(identity.vendor, SIM_VENDOR_ID);
    m
}

/// Delivers `rpdo1`, then one SYNC: the drive's TPDO1 in answer, decoded by `tpdo1`.
fn rpdo_then_sync(
    m: &mut Master,
    py: &mut PyDrive,
    rpdo1: CanFrame,
    tpdo1: &PdoConfig,
) -> Vec<u32> {
    m.deliver(py, vec![rpdo1]);
    m.sync = Some(
        SyncProducer::try_new(10_000)
            .expect("period")
            .on_cob_id(hand_canopen::CobId::try_new(SYNC_COB).expect("11 bits")),
    );
    let heard = py.heard.len();
    m.step(py);
    let tpdo = py.heard[heard..]
        .iter()
        .find(|(_, f)| f.cob_id() == tpdo1.cob_id.raw())
        .map(|(_, f)| *f)
        .expect("TPDO1 on SYNC from the canopen drive");
    tpdo1.decode(&tpdo).expect("TPDO1 decodes")
}

#[test]
fn master_core_against_python_canopen() {
    // 1. Tables.
    let mut py = spawn_with_tables_checked();

    // 2. Start-up against the LocalNode drive.
    let mode = Mode::CyclicSyncTorque;
    let mut m = start_up(&mut py, mode);

    // 3. A setpoint RPDO and SYNC: the TPDO canopen's PdoMap encoded, decoded by us.
    let pdos = finger_pdos(node(DRIVE), mode);
    let rpdo = &pdos[0];
    let tpdo1 = pdos
        .iter()
        .find(|p| p.direction == Direction::Tx && p.number == 1)
        .expect("TPDO1");
    let target: i16 = 250;
    let f = rpdo.encode(&[0x000F, target as u16 as u32]).expect("RPDO1");
    let v = rpdo_then_sync(&mut m, &mut py, f, tpdo1);
    assert_eq!(
        Statusword(v[0] as u16).state(),
        Some(PowerState::OperationEnabled)
    );
    assert_eq!(v[1] as u16 as i16, target);

    // 4. SDO aborts from canopen's SdoServer, named by our client.
    let mut sdo = SdoClient::new(node(DRIVE), 20_000);
    for (addr, code) in [
        (ObjectAddr::new(0x2000, 0), AbortCode::NoObject),
        // A record's missing subindex (LocalNode answers any subindex of a VAR object
        // with the VAR's value, so 0x6041:07 would not test this).
        (ObjectAddr::new(0x1018, 7), AbortCode::NoSubIndex),
    ] {
        let req = sdo.upload(addr, m.now).expect("idle");
        let replies = py.frame(&req, m.now);
        let result = replies
            .iter()
            .find_map(|r| sdo.on_frame(r))
            .expect("a reply");
        assert_eq!(
            result,
            Err(SdoError::Aborted {
                node: node(DRIVE),
                addr,
                code
            })
        );
    }
    let req = sdo
        .download(
            ObjectAddr::new(0x6041, 0),
            hand_canopen::SdoData::u16(0),
            m.now,
        )
        .expect("idle");
    let replies = py.frame(&req, m.now);
    assert!(matches!(
        replies.iter().find_map(|r| sdo.on_frame(r)),
        Some(Err(SdoError::Aborted {
            code: AbortCode::ReadOnly,
            ..
        }))
    ));

    // 5. handd's heartbeat stops: the drive's watchdog quick-stops it, and canopen's
    //    EmcyProducer frame decodes with our EMCY decoder.
    for _ in 0..50 {
        m.step(&mut py);
    }
    m.heartbeat = None;
    m.sync = None;
    let heard = py.heard.len();
    for _ in 0..150 {
        m.step(&mut py);
    }
    let emcy = py.heard[heard..]
        .iter()
        .find_map(|(_, f)| Emcy::decode(f).ok())
        .expect("EMCY from the canopen drive's watchdog");
    assert_eq!(emcy.code, 0x8130);
    assert_eq!(emcy.class(), ErrorClass::Monitoring);
    assert!(emcy.meaning().contains("heartbeat"));

    py.send_line("Q");
    let summary: Value = serde_json::from_str(&py.line()).expect("summary JSON");
    assert_eq!(summary["quick_stops"], json!(1));
    assert_eq!(summary["watchdog_trips"], json!(1));
    assert_eq!(summary["state"], json!("SWITCH ON DISABLED"));
    assert_eq!(summary["nmt"], json!("OPERATIONAL"));
    assert_eq!(summary["mode"], json!(mode.value()));
    assert_eq!(
        summary["consumer_heartbeat"],
        json!((u32::from(MASTER) << 16) | 100)
    );
    // The PDO configuration our plan wrote, as canopen reads it back from its dictionary.
    assert_maps_agree(&pdos, &summary["rpdo"], Direction::Rx);
    assert_maps_agree(&pdos, &summary["tpdo"], Direction::Tx);
    let status = py.child.wait().expect("the canopen script exits");
    assert!(status.success(), "the canopen script failed: {status}");
}

/// CSV: RPDO1 = controlword + target velocity + max torque (0x6072), as handd's fixed layout
/// encodes it, mapped by our start-up into canopen's dictionary (0x6072 PDO-mappable in the
/// EDS) and applied there on SYNC; the mapping read back agrees.
#[test]
fn csv_rpdo1_with_the_torque_limit_against_python_canopen() {
    let mut py = spawn_with_tables_checked();
    let mode = Mode::CyclicSyncVelocity;
    let mut m = start_up(&mut py, mode);
    let pdos = finger_pdos(node(DRIVE), mode);
    let tpdo1 = pdos
        .iter()
        .find(|p| p.direction == Direction::Tx && p.number == 1)
        .expect("TPDO1");
    let f = rpdo1(
        node(DRIVE),
        mode,
        Controlword(0x000F),
        Setpoint {
            value: -2_500,
            max_torque: TorqueLimit(375),
        },
    );
    assert_eq!(f.payload().len(), 8);
    let v = rpdo_then_sync(&mut m, &mut py, f, tpdo1);
    assert_eq!(
        Statusword(v[0] as u16).state(),
        Some(PowerState::OperationEnabled)
    );
    assert_eq!(v[2] as i32, -2_500, "velocity actual follows the target");
    py.send_line("Q");
    let summary: Value = serde_json::from_str(&py.line()).expect("summary JSON");
    assert_eq!(summary["mode"], json!(mode.value()));
    assert_eq!(summary["max_torque"], json!(375), "0x6072 as RPDO1 set it");
    assert_eq!(summary["rpdo_length_errors"], json!(0));
    assert_maps_agree(&pdos, &summary["rpdo"], Direction::Rx);
    assert_maps_agree(&pdos, &summary["tpdo"], Direction::Tx);
    let status = py.child.wait().expect("the canopen script exits");
    assert!(status.success(), "the canopen script failed: {status}");
}
