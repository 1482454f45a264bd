//! Model files: round trip, atomic save, and every refusal on load.

mod model_support;

use std::path::PathBuf;

use decoder::dsp::ChainConfig;
use decoder::model::verify::{Method, VerificationRecord, WorstRay};
use decoder::model::{
    train, FileError, ModelKind, ModelSpec, TrainConfig, TrainedModel, ValidationSplit, HEADER_LEN,
    MAGIC,
};
use model_support::{calibration, chain};

fn trained(kind: ModelKind) -> TrainedModel {
    let mut spec = ModelSpec::default();
    spec.resdd.hidden = 8;
    spec.ln.hidden = [8, 8];
    spec.mlp.hidden = [8, 8];
    spec.cnn.filters = [3, 3];
    spec.cnn.dense = 8;
    // Trials of 4 windows: too short for the default trial-tail split.
    let cfg = TrainConfig {
        max_epochs: 3,
        split: ValidationSplit::Trial { fraction: 0.2 },
        ..TrainConfig::default()
    };
    train(kind, &spec, &calibration(2, 2, 4, 11), &cfg, &mut |_| {}).expect("trains")
}

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!(
        "handstack-model-test-{}-{name}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("temp dir");
    d
}

/// The body split into metadata JSON and raw values, and a way to put it back together
/// with a correct header (so only the intended defect is left in the file).
struct Parts {
    meta: serde_json::Value,
    data: Vec<u8>,
}

fn split(bytes: &[u8]) -> Parts {
    let body = &bytes[HEADER_LEN..];
    let meta_len = u64::from_le_bytes(body[..8].try_into().unwrap()) as usize;
    Parts {
        meta: serde_json::from_slice(&body[8..8 + meta_len]).expect("metadata is JSON"),
        data: body[8 + meta_len..].to_vec(),
    }
}

fn join(p: &Parts) -> Vec<u8> {
    join_version(p, decoder::model::FORMAT_VERSION)
}

fn join_version(p: &Parts, version: u32) -> Vec<u8> {
    let meta = serde_json::to_vec(&p.meta).unwrap();
    let mut body = (meta.len() as u64).to_le_bytes().to_vec();
    body.extend_from_slice(&meta);
    body.extend_from_slice(&p.data);
    let mut out = MAGIC.to_vec();
    out.extend_from_slice(&version.to_le_bytes());
    out.extend_from_slice(&crc32fast::hash(&body).to_le_bytes());
    out.extend_from_slice(&(body.len() as u64).to_le_bytes());
    out.extend_from_slice(&body);
    out
}

#[test]
fn save_load_round_trip_is_bit_exact_for_every_kind() {
    let dir = temp_dir("roundtrip");
    for kind in ModelKind::ALL {
        let m = trained(kind);
        let path = dir.join(format!("{kind}.hsm"));
        m.save(&path).expect("saves");
        // Saving again replaces the file in one step.
        m.save(&path).expect("saves over an existing file");
        let back = TrainedModel::load(&path, Some(&chain(2))).expect("loads");
        assert_eq!(back, m, "{kind}");
        let x: Vec<f64> = (0..16).map(|i| 10.0 * i as f64).collect();
        let (a, b) = (m.predict(&x), back.predict(&x));
        assert_eq!(a.map(f64::to_bits), b.map(f64::to_bits));
        // The batch path and the daemon's path give the very same numbers.
        let rows: Vec<f64> = x.iter().chain(x.iter().rev()).copied().collect();
        let batch = back.predict_rows(&rows);
        assert_eq!(batch.len(), 2);
        assert_eq!(batch[0].map(f64::to_bits), a.map(f64::to_bits));
        assert_eq!(
            back.predictor().run(&rows[16..]).map(f64::to_bits),
            batch[1].map(f64::to_bits)
        );
        assert_eq!(back.sample_rate_hz(), 1000.0);
        assert_eq!(back.n_channels(), 2);
        // Also loads without a chain to compare against (e.g. for `handctl info`).
        assert!(TrainedModel::load(&path, None).is_ok());
    }
    let leftovers: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.contains(".tmp"))
        .collect();
    assert!(leftovers.is_empty(), "temporary files left: {leftovers:?}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn file_is_self_describing() {
    let bytes = trained(ModelKind::ResDd).to_bytes().unwrap();
    let p = split(&bytes);
    let m = &p.meta;
    assert_eq!(m["format"], "handstack-model");
    assert_eq!(m["kind"], "resdd");
    assert_eq!(m["n_inputs"], 16);
    assert_eq!(m["n_outputs"], 5);
    assert_eq!(m["n_channels"], 2);
    assert_eq!(m["sample_rate_hz"], 1000.0);
    assert_eq!(m["feature_names"][9], "ch1.MAV");
    assert_eq!(m["tensors"][0]["name"], "w_in");
    assert_eq!(m["tensors"][0]["shape"], serde_json::json!([8, 16]));
    assert_eq!(m["normalizer"]["shape"], serde_json::json!([16]));
    assert_eq!(m["summary"]["epochs_run"], 3);
    assert_eq!(m["chain"]["channels"], 2);
    // w_in + 2 modules + w_out, then 16 scales.
    assert_eq!(p.data.len(), 8 * (8 * 16 + 2 * 64 + 5 * 8 + 16));
}

#[test]
fn load_rejects_each_defect_with_a_named_error() {
    let good = trained(ModelKind::ResDd).to_bytes().unwrap();
    let load = |b: &[u8]| TrainedModel::from_bytes(b, Some(&chain(2))).unwrap_err();
    assert!(
        TrainedModel::from_bytes(&join(&split(&good)), Some(&chain(2))).is_ok(),
        "helper round trip"
    );

    assert!(matches!(
        load(b"not a model at all, just text"),
        FileError::NotAModelFile
    ));

    let mut v = good.clone();
    v[8..12].copy_from_slice(&7u32.to_le_bytes());
    assert!(matches!(
        load(&v),
        FileError::UnknownVersion {
            found: 7,
            supported: 2
        }
    ));

    let e = load(&good[..good.len() - 1]);
    assert!(matches!(e, FileError::Length { .. }), "{e}");

    let mut v = good.clone();
    let last = v.len() - 20;
    v[last] ^= 0x40;
    let e = load(&v);
    assert!(matches!(e, FileError::BadChecksum { .. }), "{e}");
    assert!(e.to_string().contains("checksum"));

    // A tensor of the wrong shape (checksum recomputed, so only the shape is wrong).
    let mut p = split(&good);
    p.meta["tensors"][1]["shape"] = serde_json::json!([8, 9]);
    match load(&join(&p)) {
        FileError::WrongShape {
            tensor,
            expected,
            found,
        } => {
            assert_eq!(
                (tensor.as_str(), expected, found),
                ("w_mod.1", vec![8, 8], vec![8, 9])
            );
        }
        e => panic!("expected WrongShape, got {e}"),
    }
    // The spec says more modules than the file has tensors for.
    let mut p = split(&good);
    p.meta["spec"]["resdd"]["modules"] = serde_json::json!(3);
    let e = load(&join(&p));
    assert!(
        matches!(e, FileError::WrongShape { ref tensor, .. } if tensor == "w_mod.3"),
        "{e}"
    );
    // A corrupt spec asking for a huge model is refused from the shapes alone (no allocation
    // of the claimed 1e9 parameters happens before the check).
    let mut p = split(&good);
    p.meta["spec"]["resdd"]["hidden"] = serde_json::json!(4096);
    p.meta["spec"]["resdd"]["modules"] = serde_json::json!(64);
    let e = load(&join(&p));
    assert!(
        matches!(e, FileError::WrongShape { ref tensor, .. } if tensor == "w_in"),
        "{e}"
    );
    let mut p = split(&good);
    p.meta["spec"]["resdd"]["hidden"] = serde_json::json!(0);
    let e = load(&join(&p));
    assert!(e.to_string().contains("hidden width"), "{e}");
    // Normalizer of the wrong length.
    let mut p = split(&good);
    p.meta["normalizer"]["shape"] = serde_json::json!([15]);
    let e = load(&join(&p));
    assert!(
        matches!(e, FileError::WrongShape { ref tensor, .. } if tensor == "normalizer.scale"),
        "{e}"
    );
    // Input size that does not match the chain's channel count.
    let mut p = split(&good);
    p.meta["n_inputs"] = serde_json::json!(96);
    assert!(matches!(load(&join(&p)), FileError::WrongShape { .. }));

    // Non-finite weights: NaN in w_mod.1, infinity in the normalizer.
    let mut p = split(&good);
    let at = 8 * (8 * 16 + 5);
    p.data[at..at + 8].copy_from_slice(&f64::NAN.to_le_bytes());
    match load(&join(&p)) {
        FileError::NonFiniteWeight { tensor, index } => {
            assert_eq!((tensor.as_str(), index), ("w_mod.1", 5))
        }
        e => panic!("expected NonFiniteWeight, got {e}"),
    }
    let mut p = split(&good);
    let n = p.data.len();
    p.data[n - 8..].copy_from_slice(&f64::INFINITY.to_le_bytes());
    let e = load(&join(&p));
    assert!(
        matches!(e, FileError::NonFiniteWeight { ref tensor, index: 15 } if tensor == "normalizer.scale"),
        "{e}"
    );

    // Weight data of the wrong length.
    let mut p = split(&good);
    p.data.truncate(p.data.len() - 8);
    assert!(matches!(load(&join(&p)), FileError::Malformed(_)));
    // Metadata that is not JSON.
    let mut v = MAGIC.to_vec();
    let body = [&4u64.to_le_bytes()[..], b"{{{{"].concat();
    v.extend_from_slice(&1u32.to_le_bytes());
    v.extend_from_slice(&crc32fast::hash(&body).to_le_bytes());
    v.extend_from_slice(&(body.len() as u64).to_le_bytes());
    v.extend_from_slice(&body);
    assert!(matches!(load(&v), FileError::Malformed(_)));

    // A model trained on another chain configuration.
    let running = ChainConfig {
        mains_hz: 60,
        window_ms: 100.0,
        ..chain(2)
    };
    match TrainedModel::from_bytes(&good, Some(&running)).unwrap_err() {
        FileError::ChainMismatch { fields } => assert_eq!(fields, ["mains_hz", "window_ms"]),
        e => panic!("expected ChainMismatch, got {e}"),
    }
    let e = TrainedModel::from_bytes(&good, Some(&chain(12))).unwrap_err();
    assert!(e.to_string().contains("channels"), "{e}");
}

#[test]
fn io_errors_name_the_path() {
    let e = TrainedModel::load("/nonexistent/dir/model.hsm", None).unwrap_err();
    assert!(matches!(e, FileError::Io { op: "read", .. }));
    assert!(e.to_string().contains("/nonexistent/dir/model.hsm"), "{e}");
    let e = trained(ModelKind::Ln)
        .save("/nonexistent/dir/model.hsm")
        .unwrap_err();
    assert!(matches!(e, FileError::Io { op: "create", .. }), "{e}");
}

/// A record as `handctl train --force` writes it for a model that reverses.
fn forced_record() -> VerificationRecord {
    VerificationRecord {
        method: Method::Exact,
        tolerance: 0.01,
        rays: 3375,
        reversing: 12,
        worst: Some(WorstRay {
            trial: "trial 3 (index flexion, repetition 1)".into(),
            finger: 1,
            amount: 0.0312,
            from_k: 0.4,
            to_k: 0.9,
        }),
        forced: true,
    }
}

#[test]
fn verification_and_rest_level_round_trip_and_old_files_load() {
    let plain = trained(ModelKind::ResDd);
    assert_eq!(plain.verification(), None);
    assert_eq!(plain.rest_rms_uv(), None);
    // Without the sections the metadata has neither key: the file is what the writer before
    // them wrote, and it loads as "not verified".
    let old = plain.to_bytes().unwrap();
    let meta = split(&old).meta;
    assert!(meta.get("verification").is_none() && meta.get("rest_rms_uv").is_none());
    // The calibration has rest windows, so training fitted a rest stage and the file keeps it.
    let stage = *plain
        .rest_stage()
        .expect("a rest stage from the rest windows");
    assert!(meta.get("rest_stage").is_some());
    let back = TrainedModel::from_bytes(&old, Some(&chain(2))).unwrap();
    assert_eq!((back.verification(), back.rest_rms_uv()), (None, None));
    assert!(
        decoder::model::verify::describe_verification(back.verification())
            .starts_with("NOT verified")
    );

    let full = plain
        .clone()
        .with_verification(forced_record())
        .unwrap()
        .with_rest_rms_uv(vec![3.25, 4.5])
        .unwrap();
    let bytes = full.to_bytes().unwrap();
    let back = TrainedModel::from_bytes(&bytes, Some(&chain(2))).unwrap();
    assert_eq!(back, full);
    assert_eq!(back.verification(), Some(&forced_record()));
    assert_eq!(back.rest_rms_uv(), Some(&[3.25, 4.5][..]));
    let line = back.verification().unwrap().to_string();
    assert!(
        line.starts_with("FORCED: 12 of 3375 rays reverse beyond 0.01 (exact)")
            && line.contains("index in trial 3 (index flexion, repetition 1) by 0.0312"),
        "{line}"
    );
    // The same file with the sections removed from its metadata is the older file.
    let mut p = split(&bytes);
    let obj = p.meta.as_object_mut().unwrap();
    obj.remove("verification");
    obj.remove("rest_rms_uv");
    assert_eq!(
        TrainedModel::from_bytes(&join(&p), Some(&chain(2))).unwrap(),
        plain
    );
    // A file from before the rest stage (no `rest_stage` key) loads, with raw outputs.
    p.meta.as_object_mut().unwrap().remove("rest_stage");
    let raw = TrainedModel::from_bytes(&join(&p), Some(&chain(2))).unwrap();
    assert_eq!(raw.rest_stage(), None);
    assert_eq!(raw, plain.clone().with_rest_stage(None));
    let x = vec![20.0; 16];
    let (staged, unstaged) = (plain.predict(&x), raw.predict(&x));
    for f in 0..5 {
        assert_eq!(staged[f], stage.map(f, unstaged[f]), "finger {f}");
    }
}

#[test]
fn the_checksum_covers_the_new_sections_and_bad_ones_are_refused() {
    let full = trained(ModelKind::Ln)
        .with_verification(forced_record())
        .unwrap()
        .with_rest_rms_uv(vec![3.25, 4.5])
        .unwrap();
    let good = full.to_bytes().unwrap();
    let load = |b: &[u8]| TrainedModel::from_bytes(b, Some(&chain(2))).unwrap_err();
    // One value inside each section changed, the checksum left as it was.
    let find = |hay: &[u8], needle: &str| {
        hay.windows(needle.len())
            .position(|w| w == needle.as_bytes())
            .unwrap_or_else(|| panic!("{needle} is in the file"))
    };
    for (key, from, to) in [
        ("\"verification\"", "\"reversing\": 12", "\"reversing\": 13"),
        ("\"rest_rms_uv\"", "3.25", "3.75"),
    ] {
        let at = find(&good, key);
        let at = at + find(&good[at..], from);
        let mut v = good.clone();
        v[at..at + from.len()].copy_from_slice(to.as_bytes());
        let e = load(&v);
        assert!(matches!(e, FileError::BadChecksum { .. }), "{key}: {e}");
    }
    // With the checksum made right, contradictions are still refused, named.
    let bad = [
        (
            "verification",
            serde_json::json!({"forced": true, "reversing": 0}),
        ),
        ("verification", serde_json::json!({"reversing": 4000})),
        ("verification", serde_json::json!({"tolerance": -1.0})),
        ("rest_rms_uv", serde_json::json!([1.0])),
        ("rest_rms_uv", serde_json::json!([1.0, -2.0])),
        (
            "rest_stage",
            serde_json::json!({"up": [0.1, 0.1, -0.3, 0.1, 0.1]}),
        ),
        ("rest_stage", serde_json::json!({"sharpness": 0.0})),
    ];
    for (key, patch) in bad {
        let mut p = split(&good);
        match (&mut p.meta[key], &patch) {
            (serde_json::Value::Object(o), serde_json::Value::Object(q)) => {
                o.extend(q.iter().map(|(k, v)| (k.clone(), v.clone())))
            }
            (slot, _) => *slot = patch.clone(),
        }
        let e = load(&join(&p));
        assert!(
            matches!(e, FileError::Malformed(ref m) if m.contains(key)),
            "{key} {patch}: {e}"
        );
    }
}

/// Issue 32 item 7: a section that changes the outputs is required, and a reader that does not
/// know a required section refuses the file; version 1 files still load.
#[test]
fn required_sections_are_listed_and_an_unknown_one_is_refused() {
    use decoder::model::RestStage;
    let with_stage = trained(ModelKind::ResDd)
        .with_rest_stage(Some(RestStage::try_new([0.1; 5], [0.05; 5], 4.0).unwrap()));
    let bytes = with_stage.to_bytes().unwrap();
    assert_eq!(u32::from_le_bytes(bytes[8..12].try_into().unwrap()), 2);
    let mut p = split(&bytes);
    assert_eq!(
        p.meta["required"],
        serde_json::json!([
            "rest_stage",
            "envelope",
            "envelope_alone",
            "envelope_patterns"
        ])
    );
    let load = |b: &[u8]| TrainedModel::from_bytes(b, Some(&chain(2)));
    let back = load(&join(&p)).expect("loads");
    let alone = with_stage.envelope().and_then(|e| e.alone());
    assert!(alone.is_some_and(|a| a >= 1.0), "{alone:?}");
    assert_eq!(back.envelope().and_then(|e| e.alone()), alone);
    let cone = with_stage.envelope().and_then(|e| e.cone()).cloned();
    assert!(cone.is_some(), "training records the channel patterns");
    assert_eq!(back.envelope().and_then(|e| e.cone()), cone.as_ref());
    // So do the channel patterns: listed, and an older file without them loads with the
    // pattern test off.
    p.meta["required"] = serde_json::json!(["rest_stage", "envelope", "envelope_alone"]);
    let e = load(&join(&p)).unwrap_err();
    assert!(e.to_string().contains("envelope_patterns"), "{e}");
    let patterns = p.meta.as_object_mut().unwrap().remove("envelope_patterns");
    let older = load(&join(&p)).expect("an envelope without the patterns loads");
    assert_eq!(older.envelope().and_then(|e| e.cone()), None);
    p.meta["envelope_patterns"] = patterns.unwrap();
    p.meta["envelope_patterns"]["worst"] = serde_json::json!(2.0);
    p.meta["required"] = serde_json::json!([
        "rest_stage",
        "envelope",
        "envelope_alone",
        "envelope_patterns"
    ]);
    let e = load(&join(&p)).unwrap_err();
    assert!(e.to_string().contains("worst misfit"), "{e}");
    p.meta.as_object_mut().unwrap().remove("envelope_patterns");
    // The calibration's channel ratio changes the outputs: it must be listed, and it needs
    // the envelope it belongs to.
    p.meta["required"] = serde_json::json!(["rest_stage", "envelope"]);
    let e = load(&join(&p)).unwrap_err();
    assert!(e.to_string().contains("envelope_alone"), "{e}");
    p.meta["required"] = serde_json::json!(["rest_stage", "envelope_alone"]);
    let envelope = p.meta.as_object_mut().unwrap().remove("envelope").unwrap();
    let e = load(&join(&p)).unwrap_err();
    assert!(e.to_string().contains("without an envelope"), "{e}");
    p.meta["envelope"] = envelope;
    // An older file (an envelope, no ratio) loads with the alone test off.
    p.meta.as_object_mut().unwrap().remove("envelope_alone");
    p.meta["required"] = serde_json::json!(["rest_stage", "envelope"]);
    let older = load(&join(&p)).expect("an envelope without the ratio loads");
    assert_eq!(older.envelope().and_then(|e| e.alone()), None);
    // A newer writer's section this build does not know.
    p.meta["required"] = serde_json::json!(["rest_stage", "envelope", "grip_limiter"]);
    let e = load(&join(&p)).unwrap_err();
    assert!(
        matches!(&e, FileError::UnknownRequired { sections } if sections == &["grip_limiter"]),
        "{e}"
    );
    // A version 2 file with a rest stage it does not mark required is malformed.
    p.meta["required"] = serde_json::json!(["envelope"]);
    let e = load(&join(&p)).unwrap_err();
    assert!(e.to_string().contains("rest_stage"), "{e}");
    // Version 1 (no `required`): loads, its rest stage applied as before.
    p.meta.as_object_mut().unwrap().remove("required");
    p.meta.as_object_mut().unwrap().remove("envelope");
    let old = load(&join_version(&p, 1)).expect("a version 1 file loads");
    assert_eq!(old.rest_stage(), with_stage.rest_stage());
}

/// Issue 32 item 4: the file records which patient and session, when, and the quality gates
/// bypassed; the section is descriptive (not required), and a file without it (older, or a
/// version 1 file) loads as "unknown patient". A bad record is refused, named.
#[test]
fn provenance_round_trips_and_older_files_load_as_unknown_patient() {
    use decoder::model::provenance::describe_provenance;
    use decoder::model::Provenance;
    let record = Provenance {
        patient: Some("P-017".into()),
        session: "fitting-2026-12-02".into(),
        calibrated_utc: "2026-12-02T13:15:28Z".into(),
        ignore_gates: true,
        gates_bypassed: vec!["trial 3 (index flexion, repetition 1): channel 4 is flat".into()],
    };
    let plain = trained(ModelKind::ResDd);
    let with = plain.clone().with_provenance(record.clone()).unwrap();
    let bytes = with.to_bytes().unwrap();
    let back = TrainedModel::from_bytes(&bytes, Some(&chain(2))).unwrap();
    assert_eq!(back, with);
    assert_eq!(back.provenance(), Some(&record));
    let line = describe_provenance(back.provenance());
    assert!(
        line.starts_with(
            "patient P-017, session fitting-2026-12-02, calibrated 2026-12-02T13:15:28Z; \
             QUALITY GATES BYPASSED (--ignore-gates): 1 finding(s): trial 3"
        ),
        "{line}"
    );
    let mut p = split(&bytes);
    assert_eq!(p.meta["provenance"]["patient"], "P-017");
    let required = p.meta["required"].as_array().unwrap();
    assert!(
        required.iter().all(|r| r != "provenance"),
        "descriptive, not required: {required:?}"
    );
    // The checksum covers it.
    let at = bytes.windows(5).position(|w| w == b"P-017").unwrap();
    let mut v = bytes.clone();
    v[at + 4] = b'8';
    assert!(matches!(
        TrainedModel::from_bytes(&v, None),
        Err(FileError::BadChecksum { .. })
    ));
    // A bad record with a right checksum is malformed, named.
    p.meta["provenance"]["patient"] = serde_json::json!("P 017; rm");
    let e = TrainedModel::from_bytes(&join(&p), None).unwrap_err();
    assert!(
        matches!(&e, FileError::Malformed(m) if m.contains("provenance") && m.contains("patient id")),
        "{e}"
    );
    // The older file: no `provenance` key, in version 2 and in version 1.
    p.meta.as_object_mut().unwrap().remove("provenance");
    let old = TrainedModel::from_bytes(&join(&p), Some(&chain(2))).unwrap();
    assert_eq!(old, plain);
    assert_eq!(old.provenance(), None);
    assert!(describe_provenance(old.provenance()).starts_with("unknown patient"));
    p.meta.as_object_mut().unwrap().remove("required");
    let v1 = TrainedModel::from_bytes(&join_version(&p, 1), Some(&chain(2))).unwrap();
    assert_eq!(v1.provenance(), None);
    // A program cannot put a malformed record into a model either.
    let e = plain
        .with_provenance(Provenance {
            calibrated_utc: "yesterday".into(),
            ..record
        })
        .unwrap_err();
    assert!(e.to_string().contains("calibration date"), "{e}");
}

/// Issue 25 item 4: the directions the calibration taught are a required section, written only
/// when some direction was not taught, covered by the checksum; a file without it (older, or a
/// full calibration) loads as "both taught" and outputs what it did.
#[test]
fn taught_directions_round_trip_and_older_files_load_as_both_taught() {
    use decoder::model::Taught;
    let load = |b: &[u8]| TrainedModel::from_bytes(b, Some(&chain(2)));
    let full = trained(ModelKind::ResDd);
    assert!(full.taught().is_both(), "{:?}", full.taught());
    let full_bytes = full.to_bytes().unwrap();
    let p = split(&full_bytes);
    assert!(
        p.meta.get("taught").is_none(),
        "nothing to hold, nothing written"
    );
    assert_eq!(load(&full_bytes).unwrap().taught(), &Taught::BOTH);

    let mut taught = Taught::BOTH;
    taught.extension = [false; 5];
    taught.flexion[3] = false;
    let held = full.clone().with_taught(taught);
    let bytes = held.to_bytes().unwrap();
    let back = load(&bytes).unwrap();
    assert_eq!(back, held);
    assert_eq!(back.taught(), &taught);
    let mut p = split(&bytes);
    assert!(p.meta["required"]
        .as_array()
        .unwrap()
        .iter()
        .any(|r| r == "taught"));
    // The outputs: the held directions are 0, the others those of the full model.
    let x = vec![0.3; back.normalizer().len()];
    let (y, y_full) = (back.predict(&x), full.predict(&x));
    for f in 0..5 {
        assert_eq!(y[f], taught.hold(f, y_full[f]), "finger {f}");
    }
    // Covered by the checksum: one byte of the section changed and the file is refused.
    let at = find(&bytes, b"\"taught\"");
    let mut bad = bytes.clone();
    bad[at + 1] ^= 0x20;
    assert!(matches!(load(&bad), Err(FileError::BadChecksum { .. })));
    // Present but not required: malformed (a reader must not drop it unknowingly).
    let required: Vec<serde_json::Value> = p.meta["required"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|r| *r != "taught")
        .cloned()
        .collect();
    p.meta["required"] = serde_json::Value::Array(required);
    let e = load(&join(&p)).unwrap_err();
    assert!(e.to_string().contains("taught"), "{e}");
    // The older file: no section; both taught, the full model's outputs.
    p.meta.as_object_mut().unwrap().remove("taught");
    let old = load(&join(&p)).unwrap();
    assert_eq!(old.taught(), &Taught::BOTH);
    assert_eq!(old, full);
}

fn find(hay: &[u8], needle: &[u8]) -> usize {
    hay.windows(needle.len())
        .position(|w| w == needle)
        .expect("present")
}
