//! Cross-check of the evaluation statistics against scipy/numpy (decoder/ref/eval_reference.py).

use std::io::Write;
use std::path::PathBuf;
use std::process::{Command, Stdio};

use decoder::eval::{auc, linear_fit, spearman};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn python() -> PathBuf {
    if let Some(p) = std::env::var_os("HANDSTACK_PYTHON") {
        return PathBuf::from(p);
    }
    let p = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../.venv/bin/python"));
    assert!(
        p.exists(),
        "run ./scripts/test (it creates .venv) or set HANDSTACK_PYTHON to a python with numpy, scipy, cantools"
    );
    p
}

struct Case {
    scores: Vec<f64>,
    positive: Vec<bool>,
    x: Vec<f64>,
    y: Vec<f64>,
}

fn cases() -> Vec<Case> {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let mut out = Vec::new();
    for i in 0..12 {
        let n = 20 + 37 * i;
        // Coarse rounding in half the cases makes many ties, the part most easily got wrong.
        let q: f64 = if i % 2 == 0 { 10.0 } else { 1e6 };
        let positive: Vec<bool> = (0..n).map(|j| j % 3 != 0 || rng.gen_bool(0.3)).collect();
        let scores: Vec<f64> = positive
            .iter()
            .map(|&p| ((if p { 0.4 } else { -0.4 } + rng.gen_range(-1.0..1.0)) * q).round() / q)
            .collect();
        let x: Vec<f64> = (0..n)
            .map(|_| (rng.gen_range(-1.0..1.0f64) * q).round() / q)
            .collect();
        let y: Vec<f64> = x
            .iter()
            .map(|v| ((0.7 * v + rng.gen_range(-0.5..0.5)) * q).round() / q)
            .collect();
        out.push(Case {
            scores,
            positive,
            x,
            y,
        });
    }
    out
}

fn to_json(cases: &[Case]) -> String {
    let arr: Vec<serde_json::Value> = cases
        .iter()
        .map(
            |c| serde_json::json!({"scores": c.scores, "positive": c.positive, "x": c.x, "y": c.y}),
        )
        .collect();
    serde_json::json!({ "cases": arr }).to_string()
}

#[test]
fn auc_spearman_and_fit_match_scipy() {
    let cases = cases();
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/ref/eval_reference.py");
    let py = python();
    let mut child = Command::new(&py)
        .arg(script)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::inherit())
        .spawn()
        .unwrap_or_else(|e| panic!("cannot start {}: {e}", py.display()));
    child
        .stdin
        .take()
        .unwrap()
        .write_all(to_json(&cases).as_bytes())
        .unwrap();
    let out = child.wait_with_output().unwrap();
    assert!(out.status.success(), "eval_reference.py failed");
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let results = v["results"].as_array().unwrap();
    assert_eq!(results.len(), cases.len());
    for (c, r) in cases.iter().zip(results) {
        let a = auc(&c.scores, &c.positive).unwrap();
        let rho = spearman(&c.x, &c.y).unwrap();
        let fit = linear_fit(&c.x, &c.y).unwrap();
        let close = |ours: f64, theirs: &serde_json::Value, what: &str| {
            let t = theirs.as_f64().unwrap();
            assert!(
                (ours - t).abs() <= 1e-10 * t.abs().max(1.0),
                "{what}: ours {ours}, scipy {t}"
            );
        };
        close(a, &r["auc"], "auc");
        close(rho, &r["spearman"], "spearman");
        close(fit.slope, &r["slope"], "slope");
        close(fit.intercept, &r["intercept"], "intercept");
        close(fit.r2, &r["r2"], "r2");
    }
}
