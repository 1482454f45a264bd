//! hand.dbc and the Rust codec agree with cantools bit for bit (see ref/cantools_check.py).
//!
//! Rust writes >= 1000 random in-range vectors per message (values + bytes, E2E counter and
//! CRC computed by the Rust protector side), cantools re-encodes and decodes them, checks the
//! CRC independently and writes its own random vectors, which Rust then decodes and re-encodes.
//! Each message's first vector also carries the generated `MESSAGES` entry (sender, receivers,
//! cycle time, E2E data id, units, value tables), which cantools compares with what it read.

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::process::Command;

use hand_dbc::messages::{self, MESSAGES};
use hand_dbc::{MessageInfo, SignalInfo};
use rand::{Rng, SeedableRng};
use serde_json::{json, Value};

const PER_MESSAGE: usize = 1000;

fn python() -> PathBuf {
    if let Some(p) = std::env::var_os("HANDSTACK_PYTHON") {
        return PathBuf::from(p);
    }
    let fallback = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../.venv/bin/python"));
    assert!(
        fallback.exists(),
        "no Python for the cantools cross-check ({} missing): run ./scripts/test (it creates \
         .venv) or set HANDSTACK_PYTHON to a python with numpy, scipy, cantools",
        fallback.display()
    );
    fallback
}

fn random_raw(rng: &mut impl Rng, s: &SignalInfo, k: usize) -> i64 {
    if !s.values.is_empty() {
        return s.values[rng.gen_range(0..s.values.len())].0;
    }
    match k {
        0 => s.raw_min,
        1 => s.raw_max,
        _ => rng.gen_range(s.raw_min..=s.raw_max),
    }
}

/// One Rust vector: random values, encoded by the Rust codec, CRC filled for E2E messages.
fn rust_vector(rng: &mut impl Rng, info: &MessageInfo, k: usize) -> Value {
    let values: BTreeMap<&str, f64> = info
        .signals
        .iter()
        .map(|s| (s.name, s.physical(random_raw(rng, s, k))))
        .collect();
    let mut msg = messages::from_signals(info.id, &mut |n| values.get(n).copied())
        .unwrap_or_else(|e| panic!("{}: Rust refused its own in-range values: {e}", info.name));
    let mut frame = msg.to_frame();
    if let Some(profile) = info.e2e {
        // CRC over data id + payload, as the protector writes it; cantools treats it as a
        // plain signal and gets the value from here.
        frame.data_mut()[0] = profile.crc(frame.data());
        msg = messages::decode(info.id, frame.data()).expect("own frame decodes");
    }
    let mut out = serde_json::Map::new();
    msg.for_each_signal(&mut |n, v| {
        let v = if v.fract() == 0.0 && v.abs() < 1e15 {
            json!(v as i64)
        } else {
            json!(v)
        };
        out.insert(n.to_string(), v);
    });
    let hex: String = frame.data().iter().map(|b| format!("{b:02x}")).collect();
    let mut v = json!({ "id": info.id, "name": info.name, "values": out, "data": hex });
    if k == 0 {
        v["info"] = info_json(info);
    }
    v
}

/// The generated description of a message, for cantools to compare with the DBC it read.
fn info_json(info: &MessageInfo) -> Value {
    let signals: serde_json::Map<String, Value> = info
        .signals
        .iter()
        .map(|s| {
            let choices: serde_json::Map<String, Value> = s
                .values
                .iter()
                .map(|(raw, name)| (raw.to_string(), json!(name)))
                .collect();
            let sig = json!({ "unit": s.unit, "choices": choices });
            (s.name.to_string(), sig)
        })
        .collect();
    json!({
        "senders": info.senders,
        "receivers": info.receivers,
        "cycle_time_ms": info.cycle_time_ms,
        "e2e_data_id": info.e2e.map_or(0, |p| p.data_id()),
        "signals": signals,
    })
}

fn unhex(s: &str) -> Vec<u8> {
    (0..s.len())
        .step_by(2)
        .map(|i| u8::from_str_radix(&s[i..i + 2], 16).expect("hex from cantools"))
        .collect()
}

#[test]
fn cantools_and_the_rust_codec_agree_bit_for_bit() {
    let dir =
        PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("cantools-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let rust_path = dir.join("rust_vectors.json");
    let py_path = dir.join("py_vectors.json");

    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(0x4841_4e44);
    let vectors: Vec<Value> = MESSAGES
        .iter()
        .flat_map(|info| (0..PER_MESSAGE).map(move |k| (info, k)))
        .map(|(info, k)| rust_vector(&mut rng, info, k))
        .collect();
    std::fs::write(&rust_path, serde_json::to_string(&vectors).expect("json")).expect("write");

    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/ref/cantools_check.py");
    let dbc = concat!(env!("CARGO_MANIFEST_DIR"), "/hand.dbc");
    let py = python();
    let output = Command::new(&py)
        .arg(script)
        .args(["--dbc", dbc, "--n", &PER_MESSAGE.to_string()])
        .arg("--rust")
        .arg(&rust_path)
        .arg("--out")
        .arg(&py_path)
        .output()
        .unwrap_or_else(|e| {
            panic!(
                "cannot run {} ({e}): run ./scripts/test (it creates .venv) or set \
                 HANDSTACK_PYTHON to a python with numpy, scipy, cantools",
                py.display()
            )
        });
    let stdout = String::from_utf8_lossy(&output.stdout);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        output.status.success(),
        "cantools check failed:\n{stdout}\n{stderr}"
    );
    assert!(
        stdout.contains("agree bit for bit"),
        "unexpected output: {stdout}"
    );

    // cantools' vectors: Rust decodes them to the same values and re-encodes the same bytes.
    let py_vectors: Vec<Value> =
        serde_json::from_str(&std::fs::read_to_string(&py_path).expect("cantools wrote vectors"))
            .expect("valid JSON");
    let mut per_message: BTreeMap<u32, usize> = BTreeMap::new();
    for v in &py_vectors {
        let id = v["id"].as_u64().expect("id") as u32;
        let data = unhex(v["data"].as_str().expect("data"));
        let values = v["values"].as_object().expect("values");
        let msg = messages::decode(id, &data).unwrap_or_else(|e| {
            panic!("Rust cannot decode cantools frame {id:#x} {data:02x?}: {e}")
        });
        let info = MessageInfo::by_id(id).expect("known id");
        let mut seen = 0;
        msg.for_each_signal(&mut |name, got| {
            seen += 1;
            let want = values[name].as_f64().expect("number");
            let factor = info
                .signals
                .iter()
                .find(|s| s.name == name)
                .map_or(1.0, |s| s.factor);
            assert!(
                (got - want).abs() <= factor * 1e-6 + 1e-9 * want.abs().max(1.0),
                "{}.{name}: Rust decodes {got}, cantools encoded {want} ({data:02x?})",
                info.name
            );
        });
        assert_eq!(seen, values.len(), "{}: signal count", info.name);
        let rebuilt = messages::from_signals(id, &mut |n| values.get(n).and_then(Value::as_f64))
            .unwrap_or_else(|e| panic!("{}: Rust refused cantools' values: {e}", info.name));
        assert_eq!(
            rebuilt.to_frame().data(),
            &data[..],
            "{}: Rust bytes differ",
            info.name
        );
        *per_message.entry(id).or_default() += 1;
    }
    for info in MESSAGES {
        assert!(
            per_message.get(&info.id).copied().unwrap_or(0) >= PER_MESSAGE,
            "{}: too few cantools vectors",
            info.name
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}
