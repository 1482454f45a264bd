//! Forward passes of every architecture against an independent numpy implementation
//! (decoder/ref/model_reference.py), written from the architecture definitions in PyTorch's
//! conventions, on random weights and inputs.

use std::io::Write;
use std::path::PathBuf;
use std::process::{Command, Stdio};

use decoder::model::{AnyModel, CnnSpec, Model, ModelKind, ModelSpec, ResDdVariant, Trainable};

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

fn reference(model: &AnyModel, spec: &serde_json::Value, inputs: &[Vec<f64>]) -> Vec<Vec<f64>> {
    let tensors: Vec<serde_json::Value> = model
        .tensors()
        .iter()
        .map(|t| serde_json::json!({"name": t.name, "shape": t.shape, "offset": t.offset}))
        .collect();
    let req = serde_json::json!({
        "kind": model.kind().name(),
        "spec": spec,
        "tensors": tensors,
        "params": model.params(),
        "inputs": inputs,
    });
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/ref/model_reference.py");
    let mut child = Command::new(python())
        .arg(script)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .spawn()
        .expect("python starts");
    child
        .stdin
        .take()
        .expect("stdin")
        .write_all(req.to_string().as_bytes())
        .expect("request written");
    let out = child.wait_with_output().expect("python runs");
    assert!(
        out.status.success(),
        "model_reference.py failed: {}",
        out.status
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON answer");
    serde_json::from_value(v["outputs"].clone()).expect("outputs")
}

fn compare(model: &AnyModel, spec: serde_json::Value, seed: u64) {
    let mut s = seed;
    let mut next = move || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((s >> 11) as f64 / (1u64 << 53) as f64) * 4.0 - 1.0
    };
    let inputs: Vec<Vec<f64>> = (0..6)
        .map(|_| (0..model.n_inputs()).map(|_| next()).collect())
        .collect();
    let want = reference(model, &spec, &inputs);
    for (x, w) in inputs.iter().zip(&want) {
        let mut y = vec![0.0; model.n_outputs()];
        model.predict(x, &mut y);
        for (a, b) in y.iter().zip(w) {
            assert!(
                (a - b).abs() <= 1e-12 * (1.0 + b.abs()),
                "{}: rust {y:?} numpy {w:?}",
                model.kind()
            );
        }
    }
}

#[test]
fn all_models_match_numpy() {
    let mut spec = ModelSpec::default();
    spec.resdd.hidden = 12;
    spec.ln.hidden = [10, 7];
    spec.mlp.hidden = [10, 7];
    spec.cnn = CnnSpec {
        filters: [5, 4],
        dense: 9,
        ..CnnSpec::default()
    };
    for variant in [ResDdVariant::InputGated, ResDdVariant::Chained] {
        for modules in [0, 1, 2, 3] {
            spec.resdd.modules = modules;
            spec.resdd.variant = variant;
            let m =
                AnyModel::random(ModelKind::ResDd, &spec, 24, 5, modules as u64).expect("model");
            compare(&m, serde_json::to_value(spec.resdd).unwrap(), 1);
        }
    }
    let m = AnyModel::random(ModelKind::Ln, &spec, 24, 5, 2).expect("model");
    compare(&m, serde_json::to_value(spec.ln).unwrap(), 2);
    let m = AnyModel::random(ModelKind::Mlp, &spec, 24, 5, 3).expect("model");
    compare(&m, serde_json::to_value(spec.mlp).unwrap(), 3);
    for (electrodes, kernel) in [(12, 3), (5, 5), (10, 3)] {
        spec.cnn.kernel = kernel;
        let m = AnyModel::random(ModelKind::Cnn, &spec, 8 * electrodes, 5, 4).expect("model");
        compare(&m, serde_json::to_value(spec.cnn).unwrap(), 4);
    }
}
