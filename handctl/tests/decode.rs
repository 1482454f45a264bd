//! `handctl decode` end to end, and recordings from other front ends: import (with a reference
//! column), train, decode; the agreement figures against an independent numpy computation
//! (tests/decode_reference.py); 4, 8 and 16 channels at 200 Hz to 1 kHz; the clear errors.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn handctl(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_handctl"))
        .args(args)
        .output()
        .expect("run handctl")
}

/// Runs a command line given as one string (the test's paths have no spaces).
fn run(line: &str) -> Output {
    handctl(&line.split_whitespace().collect::<Vec<_>>())
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

fn ok(out: Output) -> String {
    assert!(
        out.status.success(),
        "{}{}",
        text(&out.stdout),
        text(&out.stderr)
    );
    text(&out.stdout)
}

fn fails(out: Output) -> String {
    assert_eq!(out.status.code(), Some(1), "{}", text(&out.stdout));
    text(&out.stderr)
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("handctl-decode-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn python() -> PathBuf {
    if let Some(p) = std::env::var_os("HANDSTACK_PYTHON") {
        return PathBuf::from(p);
    }
    let p = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../.venv/bin/python"));
    assert!(
        p.exists(),
        "run ./scripts/test (it creates .venv) or set HANDSTACK_PYTHON to a python with numpy"
    );
    p
}

/// numpy's figures for `finger` in a decode CSV against `reference` in the source CSV.
fn numpy_agreement(
    decoded: &Path,
    source: &Path,
    reference: &str,
    rate: f64,
    window_len: usize,
    finger: &str,
) -> serde_json::Value {
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/decode_reference.py");
    let out = Command::new(python())
        .args([script, s(decoded), s(source), reference])
        .args([rate.to_string(), window_len.to_string(), finger.to_string()])
        .output()
        .expect("run python");
    serde_json::from_str(&ok(out)).expect("numpy's JSON")
}

/// Decode's JSON figures for its one finger equal numpy's to 1e-12 relative, and decode's
/// reference column equals numpy's own resampling.
fn assert_same_figures(decode_json: &str, numpy: &serde_json::Value) {
    let ours: serde_json::Value = serde_json::from_str(decode_json).expect("decode's JSON");
    let f = &ours["fingers"][0];
    assert_eq!(f["windows"], numpy["windows"], "{ours} vs {numpy}");
    let diff = numpy["reference_max_rel_diff"].as_f64().unwrap();
    assert!(diff <= 1e-12, "the reference column differs by {diff}");
    for key in [
        "r2",
        "rmse",
        "pearson_r",
        "r2_line",
        "rmse_line",
        "slope",
        "intercept",
    ] {
        let (a, b) = (f[key].as_f64().unwrap(), numpy[key].as_f64().unwrap());
        assert!(
            (a - b).abs() <= 1e-12 * b.abs().max(1.0),
            "{key}: decode {a}, numpy {b}"
        );
    }
}

fn plux_csv() -> PathBuf {
    let p = PathBuf::from(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../shared/data/plux-emg-force/emg_force_1khz.csv"
    ));
    assert!(p.exists(), "{} is missing (../shared/data)", p.display());
    p
}

/// The real EMG + force recording: rest, a 2 s hold, rest. A ResDD trained on it with the
/// force as the reference (one channel and a flexion alone: the gates refuse it, so training
/// takes --ignore-gates and --allow-one-direction); decode's R² equals numpy's on the same
/// outputs.
#[test]
fn decode_a_real_recording_against_its_force() {
    let dir = tmp("plux");
    let labels = dir.join("labels.csv");
    std::fs::write(
        &labels,
        "finger,kind,repetition,start_sample,end_sample\n\
         all,rest,1,0,1200\nall,flexion,1,1800,3700\nall,rest,2,4300,5000\n",
    )
    .unwrap();
    let (session, model, decoded) = (dir.join("s"), dir.join("m.hsm"), dir.join("d.csv"));
    let (session, model, decoded) = (s(&session), s(&model), s(&decoded));
    let csv = plux_csv();
    let out = ok(run(&format!(
        "import --samples {} --labels {} --channels 1 --reference force \
         --ignore-columns time_s -o {session}",
        s(&csv),
        s(&labels)
    )));
    assert!(out.contains("reference \"force\""), "{out}");
    ok(run(&format!(
        "train {session} -o {model} --epochs 40 --validation none --ignore-gates \
         --allow-one-direction --seed 1"
    )));
    let json = ok(run(&format!(
        "decode {session} --model {model} -o {decoded} --finger index --json"
    )));
    let numpy = numpy_agreement(Path::new(decoded), &csv, "force", 1000.0, 200, "index");
    assert_same_figures(&json, &numpy);
    // 5001 samples, 200-sample windows every 50: 97 windows.
    assert_eq!(numpy["windows"], 97, "{numpy}");
    let r = numpy["pearson_r"].as_f64().unwrap();
    assert!(r > 0.8, "the index output follows the force at r = {r}");
    // The table for a technician: every finger, both R².
    let table = ok(run(&format!(
        "decode {session} --model {model} -o {decoded}"
    )));
    assert!(
        table.contains("97 windows") && table.contains("R² line") && table.contains("pinky"),
        "{table}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Pseudo-random noise in [-1, 1): a 64-bit LCG.
fn noise(state: &mut u64) -> f64 {
    *state = state
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    ((*state >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
}

/// A recording as CSV (`time_s`, `ch0`.., `angle`) and its label table: per repetition rest,
/// index flexion, index extension, whole-hand flexion, 2 s each; the index's channels are 0 and
/// 1, the angle is +1 for index flexion, -1 for extension, 0.5 for the whole hand, 0 at rest.
fn synthesise(dir: &Path, channels: usize, rate: f64) -> (PathBuf, PathBuf) {
    let plan: [(&str, &str, f64, f64, f64); 4] = [
        ("all", "rest", 5.0, 5.0, 0.0),
        ("index", "flexion", 120.0, 20.0, 1.0),
        ("index", "extension", 20.0, 120.0, -1.0),
        ("all", "flexion", 100.0, 100.0, 0.5),
    ];
    let per_trial = (2.0 * rate) as usize;
    let mut csv = String::from("time_s");
    for c in 0..channels {
        csv.push_str(&format!(",ch{c}"));
    }
    csv.push_str(",angle\n");
    let mut labels = String::from("finger,kind,repetition,start_sample,end_sample\n");
    let (mut rng, mut n) = (11u64, 0usize);
    for rep in 1..=2 {
        for (finger, kind, a0, a1, angle) in plan {
            labels.push_str(&format!("{finger},{kind},{rep},{n},{}\n", n + per_trial));
            for _ in 0..per_trial {
                csv.push_str(&format!("{}", n as f64 / rate));
                for c in 0..channels {
                    let amp = match c {
                        0 => a0,
                        1 => a1,
                        _ if kind == "rest" => 5.0,
                        _ => 40.0,
                    };
                    csv.push_str(&format!(",{}", (amp * noise(&mut rng)).round()));
                }
                csv.push_str(&format!(",{angle}\n"));
                n += 1;
            }
        }
    }
    let (samples, table) = (dir.join("emg.csv"), dir.join("labels.csv"));
    std::fs::write(&samples, csv).unwrap();
    std::fs::write(&table, labels).unwrap();
    (samples, table)
}

/// Import, train and decode one synthetic front end; returns import's output.
fn front_end(channels: usize, rate: f64, window_len: usize, step_len: usize) -> String {
    let dir = tmp(&format!("{channels}ch-{rate}hz"));
    let (samples, labels) = synthesise(&dir, channels, rate);
    let (session, model, decoded) = (dir.join("s"), dir.join("m.hsm"), dir.join("d.csv"));
    let (session, model, decoded) = (s(&session), s(&model), s(&decoded));
    let imported = ok(run(&format!(
        "import --samples {} --labels {} --channels {channels} --rate {rate} \
         --reference angle --ignore-columns time_s -o {session}",
        s(&samples),
        s(&labels)
    )));
    // A synthetic research recording: flexion and an angle, no extension trial of every
    // finger, so the one-direction refusal is overridden as for a research recording.
    ok(run(&format!(
        "train {session} -o {model} --model ln --epochs 30 --validation none --seed 2 \
         --allow-one-direction"
    )));
    let json = ok(run(&format!(
        "decode {session} --model {model} -o {decoded} --finger 1 --json"
    )));
    let numpy = numpy_agreement(
        Path::new(decoded),
        &samples,
        "angle",
        rate,
        window_len,
        "index",
    );
    assert_same_figures(&json, &numpy);
    let n = (16.0 * rate) as usize;
    let windows = (n - window_len) / step_len + 1;
    assert_eq!(
        numpy["windows"], windows,
        "{channels} ch at {rate} Hz: {numpy}"
    );
    let r = numpy["pearson_r"].as_f64().unwrap();
    assert!(
        r > 0.8,
        "{channels} ch at {rate} Hz: index follows the angle at r = {r}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
    imported
}

#[test]
fn an_8_channel_armband_at_200_hz_imports_trains_and_decodes() {
    let out = front_end(8, 200.0, 40, 10);
    assert!(
        out.contains("chose band-pass upper edge 90 Hz") && out.contains("8 channels at 200 Hz"),
        "{out}"
    );
}

#[test]
fn four_and_sixteen_channels_at_other_rates() {
    // 250 Hz: 50 ms is 12.5 samples, the step is rounded to 13 samples (52 ms), and said.
    let out = front_end(4, 250.0, 50, 13);
    assert!(out.contains("chose step 52 ms (13 samples"), "{out}");
    let out = front_end(16, 1000.0, 200, 50);
    assert!(
        !out.contains("chose"),
        "the 1 kHz defaults need no choice: {out}"
    );
}

#[test]
fn configurations_that_cannot_work_are_clear_errors() {
    let dir = tmp("import-errors");
    let (samples, labels) = synthesise(&dir, 4, 200.0);
    let base = format!(
        "import --samples {} --labels {} --channels 4 --rate 200 --ignore-columns time_s",
        s(&samples),
        s(&labels)
    );
    let refused = dir.join("refused");
    let import = |extra: &str| run(&format!("{base} -o {} {extra}", s(&refused)));
    let e = fails(import("--reference angle --band-high 100"));
    assert!(
        e.contains("band_high_hz = 100") && e.contains("Nyquist"),
        "{e}"
    );
    let e = fails(import("--reference angle --band-low 95"));
    assert!(e.contains("band_low_hz = 95") && e.contains("90 Hz"), "{e}");
    let e = fails(import("--reference angel"));
    assert!(e.contains("\"angel\"") && e.contains("time_s, ch0"), "{e}");
    // Without the reference named, the angle column counts as a fifth channel.
    let e = fails(import(""));
    assert!(e.contains("leave 5 EMG channels"), "{e}");
    assert!(!refused.join("session.toml").exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A session without a reference: decoding works (the session or its bare samples file alike),
/// comparing with a reference does not; a model of another chain is refused naming the
/// difference.
#[test]
fn decode_without_a_reference_and_the_errors() {
    let dir = tmp("decode-errors");
    let (samples, labels) = synthesise(&dir, 4, 200.0);
    let plain = dir.join("plain.csv");
    let text = std::fs::read_to_string(&samples).unwrap();
    let lines: Vec<&str> = text.lines().map(|l| &l[..l.rfind(',').unwrap()]).collect();
    std::fs::write(&plain, lines.join("\n")).unwrap();
    let base = format!(
        "import --samples {} --labels {} --channels 4 --rate 200 --ignore-columns time_s",
        s(&plain),
        s(&labels)
    );
    let (session, other) = (dir.join("s"), dir.join("other"));
    let (session, other) = (s(&session), s(&other));
    let (model, decoded) = (dir.join("m.hsm"), dir.join("d.csv"));
    let (model, decoded) = (s(&model), s(&decoded));
    ok(run(&format!("{base} -o {session}")));
    ok(run(&format!("{base} -o {other} --band-high 80")));
    // Two epochs make a model fast, not a monotonic one: this test is about decode's errors, so
    // the verification's refusal is overridden (and the file records it as forced).
    ok(run(&format!(
        "train {session} -o {model} --model ln --epochs 2 --validation none --force \
         --allow-one-direction"
    )));
    let decode = |extra: &str| run(&format!("decode {session} --model {model} {extra}"));
    let out = ok(decode(&format!("-o {decoded}")));
    assert!(out.contains("wrote") && !out.contains("R²"), "{out}");
    let csv = std::fs::read_to_string(decoded).unwrap();
    assert!(
        csv.starts_with("time_s,thumb,index,middle,ring,pinky\n"),
        "{csv}"
    );
    // The session's bare samples file, read with the model's chain, decodes the same; the
    // source CSV, whose time column would be a fifth channel, is refused.
    let bare = dir.join("bare.csv");
    let npy = format!("{session}/samples.npy");
    ok(run(&format!(
        "decode {npy} --model {model} -o {}",
        s(&bare)
    )));
    assert_eq!(std::fs::read_to_string(&bare).unwrap(), csv);
    let e = fails(run(&format!(
        "decode {} --model {model} -o {}",
        s(&plain),
        s(&bare)
    )));
    assert!(e.contains("leave 5 EMG channels"), "{e}");
    let e = fails(decode(&format!("-o {decoded} --finger index")));
    assert!(e.contains("has none") && e.contains("--reference"), "{e}");
    let e = fails(decode(&format!("-o {decoded} --finger wrist")));
    assert!(e.contains("wrist") && e.contains("thumb"), "{e}");
    let e = fails(run(&format!("decode {other} --model {model} -o {decoded}")));
    assert!(
        e.contains("signal chain") && e.contains("band_high_hz: 90"),
        "{e}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
