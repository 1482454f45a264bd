//! Issue 29: HAND_HEARTBEAT's FaultMask as cantools reads hand.dbc names exactly the bits handd
//! sends. For every fault, handd's engine raises it and sends its heartbeat; cantools loads
//! hand.dbc, decodes each frame's FaultMask and names its set bits from the signal's comment
//! ("bit N name"); the names must be handd's (`Fault::name`), bit for bit, and the comment must
//! name no bit handd does not send. A bit missing from the comment, named differently, or
//! named twice fails.

use std::path::PathBuf;
use std::process::Command;

use decoder::dsp::ChainConfig;
use driver::engine::{Engine, EngineSettings};
use driver::safety::Fault;
use hand_dbc::messages::HandHeartbeat;
use serde_json::Value;

fn python() -> PathBuf {
    if let Some(p) = std::env::var_os("HANDSTACK_PYTHON") {
        return PathBuf::from(p);
    }
    let fallback = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../.venv/bin/python"));
    assert!(
        fallback.exists(),
        "no Python for the cantools check ({} missing): run ./scripts/test (it creates .venv) or \
         set HANDSTACK_PYTHON to a python with cantools",
        fallback.display()
    );
    fallback
}

/// Reads hand.dbc with cantools; for each frame (hex payload, one per line on stdin) prints
/// the FaultMask cantools decodes and the names its set bits get from the comment's
/// "bit N name" table. Also prints the whole table and the signal's length.
const SCRIPT: &str = r#"
import json, re, sys
import cantools
db = cantools.database.load_file(sys.argv[1])
msg = db.get_message_by_name("HAND_HEARTBEAT")
sig = msg.get_signal_by_name("FaultMask")
pairs = re.findall(r"\bbit (\d+) ([a-z0-9_]+)", sig.comment or "")
table = {}
for bit, name in pairs:
    table.setdefault(int(bit), []).append(name)
frames = []
for line in sys.stdin.read().split():
    mask = int(msg.decode(bytes.fromhex(line), decode_choices=False)["FaultMask"])
    names = [n for b in range(sig.length) if mask >> b & 1 for n in table.get(b, ["<unnamed>"])]
    frames.append({"mask": mask, "names": names})
print(json.dumps({"length": sig.length, "start": sig.start,
                  "table": {str(b): n for b, n in table.items()}, "frames": frames}))
"#;

/// The heartbeat handd's engine sends with `fault` raised (with `no_model` too: the engine
/// runs without a model, which is a fault of its own).
fn heartbeat_with(fault: Fault) -> Vec<u8> {
    let chain = ChainConfig::default()
        .validate()
        .expect("the default chain");
    let mut e = Engine::without_model(&chain, EngineSettings::default(), 0);
    e.validated(0);
    e.raise(10_000, fault);
    // HAND_HEARTBEAT goes out every other tick.
    let mut beat = None;
    for n in 1..=2u64 {
        let frames = e.tick(n * 50_000, n * 50_000);
        if let Some(f) = frames.iter().find(|f| f.raw_id() == HandHeartbeat::ID) {
            beat = Some(f.data().to_vec());
        }
    }
    beat.expect("two ticks send a HAND_HEARTBEAT")
}

#[test]
fn cantools_names_every_fault_mask_bit_as_handd_sends_it() {
    let dbc = concat!(env!("CARGO_MANIFEST_DIR"), "/../can-dbc/hand.dbc");
    let stdin: String = Fault::ALL
        .iter()
        .map(|&f| {
            let hex: String = heartbeat_with(f)
                .iter()
                .map(|b| format!("{b:02x}"))
                .collect();
            hex + "\n"
        })
        .collect();
    let mut child = Command::new(python())
        .args(["-c", SCRIPT, dbc])
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("python starts");
    std::io::Write::write_all(&mut child.stdin.take().expect("stdin"), stdin.as_bytes())
        .expect("frames to python");
    let out = child.wait_with_output().expect("python ran");
    assert!(
        out.status.success(),
        "cantools could not read hand.dbc or decode handd's heartbeats: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: Value = serde_json::from_slice(&out.stdout).expect("the script's JSON");

    assert_eq!(
        v["length"].as_u64(),
        Some(Fault::ALL.len() as u64),
        "FaultMask in hand.dbc is not one bit per fault of handd's"
    );
    // The comment's table, bit by bit, is handd's list: nothing missing, renamed, doubled or
    // extra.
    let table = v["table"].as_object().expect("the comment's table");
    for (bit, f) in Fault::ALL.iter().enumerate() {
        assert_eq!(f.bit(), 1 << bit, "{}: handd's bit", f.name());
        let named = table.get(&bit.to_string()).and_then(Value::as_array);
        assert_eq!(
            named.map(|n| n.iter().filter_map(Value::as_str).collect::<Vec<_>>()),
            Some(vec![f.name()]),
            "hand.dbc's FaultMask comment (as cantools reads it) names bit {bit} otherwise than \
             handd ({})",
            f.name()
        );
    }
    assert_eq!(
        table.len(),
        Fault::ALL.len(),
        "hand.dbc's FaultMask comment names bits handd does not have: {table:?}"
    );
    // What handd sends decodes, through cantools and the comment, to the faults it raised.
    let frames = v["frames"].as_array().expect("decoded frames");
    assert_eq!(frames.len(), Fault::ALL.len());
    for (f, d) in Fault::ALL.iter().zip(frames) {
        let mask = d["mask"].as_u64().expect("a mask") as u16;
        assert!(
            mask & f.bit() != 0,
            "handd raised {} but its heartbeat's FaultMask is {mask:#06x}",
            f.name()
        );
        // Every bit on the bus (the raised fault, no_model, any the engine raised itself),
        // named by handd and by cantools.
        let expected: Vec<&str> = Fault::ALL
            .iter()
            .filter(|g| mask & g.bit() != 0)
            .map(|g| g.name())
            .collect();
        let names: Vec<&str> = d["names"]
            .as_array()
            .expect("names")
            .iter()
            .filter_map(Value::as_str)
            .collect();
        assert_eq!(
            names,
            expected,
            "handd raised {} (FaultMask {mask:#06x} on the bus): cantools names the bits \
             otherwise",
            f.name()
        );
    }
}
