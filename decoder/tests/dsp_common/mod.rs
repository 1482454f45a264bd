//! Helpers shared by the dsp test binaries: paths to the real data and the Python reference.
#![allow(dead_code)]

use std::path::PathBuf;
use std::process::Command;

/// `../shared/data/<rel>` relative to the repository root; fails loudly when missing.
pub fn data_path(rel: &str) -> PathBuf {
    let p = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../shared/data")).join(rel);
    assert!(
        p.exists(),
        "{} is missing: the dsp tests read the real recordings from ../shared/data next to the repository",
        p.display()
    );
    p
}

/// The Python with numpy and scipy: HANDSTACK_PYTHON, else `<workspace>/.venv/bin/python`.
pub fn python() -> PathBuf {
    if let Some(p) = std::env::var_os("HANDSTACK_PYTHON") {
        return PathBuf::from(p);
    }
    let venv = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../.venv/bin/python"));
    assert!(
        venv.exists(),
        "no Python reference interpreter: run ./scripts/test (it creates .venv) or set HANDSTACK_PYTHON to a python with numpy, scipy, cantools"
    );
    venv
}

/// Runs `decoder/ref/<script>` with `args`; panics with its output when it fails.
pub fn run_reference(script: &str, args: &[&str]) {
    let script = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/ref")).join(script);
    let py = python();
    let out = Command::new(&py)
        .arg(&script)
        .args(args)
        .output()
        .unwrap_or_else(|e| {
            panic!(
                "could not start {} ({e}): run ./scripts/test (it creates .venv) or set HANDSTACK_PYTHON to a python with numpy, scipy, cantools",
                py.display()
            )
        });
    assert!(
        out.status.success(),
        "{} {} failed:\n{}\n{}",
        py.display(),
        script.display(),
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    eprint!("{}", String::from_utf8_lossy(&out.stdout));
}

/// A fresh empty temporary directory for this test process.
pub fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("handstack-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create temp dir");
    dir
}

/// max |a - b| / max |b| (the relative error used throughout the dsp checks).
pub fn rel_err(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len(), "length mismatch");
    let num = a
        .iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max);
    let den = b.iter().map(|y| y.abs()).fold(0.0, f64::max);
    if den == 0.0 {
        num
    } else {
        num / den
    }
}
