//! `handctl` end to end: import the 3DC proxy, train, evaluate with figures, and the errors a
//! technician sees.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn data_dir() -> PathBuf {
    let d = PathBuf::from(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../shared/data/3dc-armband-p4"
    ));
    assert!(
        d.join("P4_train_emg.npy").exists(),
        "{} is missing: the tests read the real recordings from ../shared/data",
        d.display()
    );
    d
}

fn handctl(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_handctl"))
        .args(args)
        .output()
        .expect("run handctl")
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("handctl-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn import_train_and_eval_on_the_3dc_proxy() {
    let data = data_dir();
    let session = tmp("session");
    let out = handctl(&["import-3dc", s(&data), "--split", "test", "-o", s(&session)]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(session.join("session.toml").exists());

    let model = session.join("resdd.hsm");
    let out = handctl(&[
        "train",
        s(&session),
        "-o",
        s(&model),
        "--epochs",
        "2",
        "--seed",
        "3",
        // Two epochs keep this pipeline test fast, not the model monotonic (8 of 3345 rays
        // reverse): the verification's refusal is overridden, and the file and the output say
        // so.
        "--force",
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let said = format!("{}{}", text(&out.stdout), text(&out.stderr));
    assert!(said.contains("wrote") && said.contains("FORCED"), "{said}");
    assert!(std::fs::metadata(&model).unwrap().len() > 1000);
    // stderr is a pipe here: no live progress lines.
    assert!(
        !text(&out.stderr).contains("epoch"),
        "{}",
        text(&out.stderr)
    );

    let plots = session.join("plots");
    let train_spec = format!("3dc:{}:train", data.display());
    let out = handctl(&[
        "eval",
        &train_spec,
        "--test",
        s(&session),
        "--models",
        "resdd,ln",
        "--epochs",
        "5",
        "--plots",
        s(&plots),
        "--stress",
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let o = text(&out.stdout);
    assert!(o.contains("Table 3") && o.contains("Table 4"), "{o}");
    // Issue 25: the envelope's count and the output range per model, and the stress table.
    for name in ["resdd", "ln"] {
        assert!(
            o.lines().any(|l| l.starts_with(&format!("  {name}: "))
                && l.contains("windows beyond the calibration's envelope")
                && l.contains("raw output in [")),
            "{o}"
        );
    }
    assert!(o.contains("Transients in the signal"), "{o}");
    for name in ["resdd", "ln"] {
        assert!(
            o.lines().any(|l| l.starts_with(&format!("  {name}: "))
                && l.contains("movement finger-windows the wrong way")
                && l.contains("for 200 ms")),
            "{o}"
        );
    }
    for condition in ["x1.5 ", "x2 ", "x3 ", "x5 ", "worst channel at x10"] {
        assert!(
            o.lines().any(|l| l.starts_with(condition)),
            "{condition}: {o}"
        );
    }
    assert!(
        o.lines().any(|l| l.starts_with("resdd ")) && o.lines().any(|l| l.starts_with("ln ")),
        "{o}"
    );
    for name in ["resdd", "ln"] {
        let roc = std::fs::read_to_string(plots.join(format!("roc_{name}.csv"))).unwrap();
        assert!(roc.starts_with("finger,auc,fpr,tpr\n") && roc.lines().count() > 10);
        let f = format!("interpolation_{name}.csv");
        let curves = std::fs::read_to_string(plots.join(&f)).unwrap();
        assert!(curves.starts_with("curve,finger,sign,"), "{f}");
    }
    // PNG figures only from a handctl built with the plotting stack.
    for f in [
        "roc_resdd.png",
        "interpolation_resdd.png",
        "roc_ln.png",
        "interpolation_ln.png",
    ] {
        let png = std::fs::read(plots.join(f));
        if cfg!(feature = "plots") {
            let bytes = png.unwrap_or_else(|e| panic!("{f}: {e}"));
            assert_eq!(&bytes[..4], b"\x89PNG", "{f}");
        } else {
            assert!(png.is_err(), "{f} written without the plots feature");
            assert!(o.contains("--features plots"), "{o}");
        }
    }
    // Without --test, the last repetitions are held out.
    let out = handctl(&["eval", s(&session), "--models", "ln", "--epochs", "3"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(
        text(&out.stdout).contains("tested on the last"),
        "{}",
        text(&out.stdout)
    );
    std::fs::remove_dir_all(&session).unwrap();
}

/// "REVERSES: N of M rays" / "verified: N of M rays" from a verification line: (N, M).
fn counts(line: &str) -> (usize, usize) {
    let words: Vec<&str> = line.split_whitespace().collect();
    let at = words.iter().position(|w| *w == "of").expect("N of M");
    (
        words[at - 1].parse().unwrap(),
        words[at + 1].parse().unwrap(),
    )
}

#[test]
fn train_and_verify_agree_on_the_effort_rays() {
    // Another participant's recordings, named directly: the loader reads the P6_ prefix.
    let spec = format!("3dc:{}/../3dc-armband-p6:test", data_dir().display());
    let dir = tmp("verify");
    std::fs::create_dir_all(&dir).unwrap();
    let model = dir.join("ln.hsm");
    let train = |extra: &[&str]| {
        let mut args = vec!["train", &spec, "--model", "ln", "-o", s(&model)];
        args.extend_from_slice(&["--epochs", "3"]);
        args.extend_from_slice(extra);
        handctl(&args)
    };
    // Three epochs leave an LN that goes back on some rays (its VAR weights make it a
    // quadratic in the effort): train refuses it and writes nothing.
    let out = train(&[]);
    let o = text(&out.stdout);
    assert_eq!(out.status.code(), Some(4), "{o}{}", text(&out.stderr));
    assert!(
        text(&out.stderr).contains("no --patient: the model file records no patient id"),
        "{}",
        text(&out.stderr)
    );
    assert!(!model.exists());
    let line = o
        .lines()
        .find_map(|l| l.strip_prefix("effort rays of the calibration: REVERSES: "))
        .unwrap_or_else(|| panic!("the verdict: {o}"));
    let refused = counts(line);
    assert!(refused.0 > 0 && refused.1 > refused.0, "{line}");
    // Written with --force, `handctl verify` on the same session finds the very same rays.
    let out = train(&["--force", "--patient", "P-006"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let o = text(&out.stdout);
    assert!(
        o.contains(&format!("patient P-006, session {spec}, calibrated 20")),
        "the provenance line: {o}"
    );
    let out = train(&["--patient", "P 006"]);
    assert_eq!(
        out.status.code(),
        Some(2),
        "a bad patient id is a usage error"
    );
    assert!(text(&out.stderr).contains("' ' is not allowed"));
    let out = handctl(&["verify", "--model", s(&model), &spec]);
    let o = text(&out.stdout);
    assert!(o.contains("ln effort-ray check, exact"), "{o}");
    assert!(o.contains(": FORCED: "), "the file's own record first: {o}");
    let summary = o
        .lines()
        .find(|l| l.contains("rays checked"))
        .unwrap_or_else(|| panic!("{o}"));
    assert!(
        summary.starts_with(&format!(
            "{} rays checked, {} reverse",
            refused.1, refused.0
        )),
        "train said {refused:?}; verify: {summary}"
    );
    assert_eq!(out.status.code(), Some(1), "{o}");
    assert!(text(&out.stderr).contains("reverse beyond the tolerance"));
    // Then the same rays out to effort 10 (issue 25).
    assert!(
        o.lines()
            .any(|l| l.starts_with(&format!("{} rays checked to effort 10", refused.1))),
        "{o}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn errors_are_clear() {
    let out = handctl(&["train", "/nonexistent/session", "-o", "/tmp/x.hsm"]);
    assert_eq!(out.status.code(), Some(1));
    let e = text(&out.stderr);
    assert!(
        e.contains("/nonexistent/session") && e.contains("handctl: error"),
        "{e}"
    );

    let dir = tmp("badtoml");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(
        dir.join("session.toml"),
        "format_version = 1\n[chain]\nchannels = \n",
    )
    .unwrap();
    let out = handctl(&["check", s(&dir)]);
    assert_eq!(out.status.code(), Some(1));
    let e = text(&out.stderr);
    assert!(e.contains("session.toml") && e.contains("line 3"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();

    let out = handctl(&["eval", "x", "--models", "resdd,transformer"]);
    assert_eq!(out.status.code(), Some(2), "clap usage error");
    assert!(text(&out.stderr).contains("transformer"));

    let out = handctl(&["train", "3dc:/nowhere:validation", "-o", "/tmp/x.hsm"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(
        text(&out.stderr).contains("validation"),
        "{}",
        text(&out.stderr)
    );
}

/// Pseudo-random noise in [-1, 1) without a dependency: a 64-bit LCG.
fn noise(state: &mut u64) -> f64 {
    *state = state
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    ((*state >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
}

#[test]
fn import_an_npy_recording_with_a_label_table_and_train_on_it() {
    let dir = tmp("table");
    std::fs::create_dir_all(&dir).unwrap();
    // Four channels; rest, then flexion and extension of the index finger (channels 0 and 1)
    // and the whole hand (all channels), two repetitions each, 2 s per trial.
    let plan: [(&str, &str, [f64; 4]); 5] = [
        ("all", "rest", [5.0; 4]),
        ("index", "flexion", [120.0, 30.0, 5.0, 5.0]),
        ("1", "extension", [30.0, 120.0, 5.0, 5.0]),
        ("all", "flexion", [120.0, 30.0, 120.0, 30.0]),
        ("all", "extension", [30.0, 120.0, 30.0, 120.0]),
    ];
    let mut samples = Vec::new();
    let mut labels = String::from("finger,kind,repetition,start_sample,end_sample\n");
    // The same recording labelled without the whole hand's extensions.
    let mut flexion_only = labels.clone();
    let mut rng = 7u64;
    for rep in 1..=2 {
        for (finger, kind, amps) in plan {
            let start = samples.len() / 4;
            for _ in 0..2000 {
                for a in amps {
                    samples.push((a * noise(&mut rng)).round());
                }
            }
            let row = format!("{finger},{kind},{rep},{start},{}\n", start + 2000);
            if (finger, kind) != ("all", "extension") {
                flexion_only.push_str(&row);
            }
            labels.push_str(&row);
        }
    }
    let npy = dir.join("emg.npy");
    decoder::session::write_npy_f64(&npy, samples.len() / 4, 4, &samples).unwrap();
    std::fs::write(dir.join("labels.csv"), labels).unwrap();
    std::fs::write(dir.join("flexion_only.csv"), flexion_only).unwrap();
    let import = |labels: &str, session: &Path| {
        let out = handctl(&[
            "import",
            "--samples",
            s(&npy),
            "--labels",
            s(&dir.join(labels)),
            "--channels",
            "4",
            "--rows-are-recordings",
            "-o",
            s(session),
        ]);
        assert!(out.status.success(), "{}", text(&out.stderr));
        text(&out.stdout)
    };
    // Issue 32 item 3: thumb, middle, ring and pinky would only ever be flexed (by the whole
    // hand): check refuses the session, and train refuses it even with --ignore-gates.
    let partial = dir.join("partial");
    assert!(import("flexion_only.csv", &partial).contains("8 trials"));
    let out = handctl(&["check", s(&partial)]);
    assert_eq!(out.status.code(), Some(3), "{}", text(&out.stdout));
    let o = text(&out.stdout);
    assert!(
        o.contains("thumb: the session has flexion trials") && o.contains("one anchor"),
        "{o}"
    );
    let out = handctl(&[
        "train",
        s(&partial),
        "-o",
        s(&dir.join("no.hsm")),
        "--ignore-gates",
    ]);
    assert_eq!(out.status.code(), Some(3), "{}", text(&out.stderr));
    let e = text(&out.stderr);
    assert!(
        e.contains("moves 4 finger(s) in one direction only")
            && e.contains("--allow-one-direction"),
        "{e}"
    );
    assert!(!dir.join("no.hsm").exists());
    let session = dir.join("session");
    let o = import("labels.csv", &session);
    assert!(o.contains("10 trials"), "{o}");
    let out = handctl(&["check", s(&session)]);
    assert!(
        out.status.success(),
        "{}{}",
        text(&out.stdout),
        text(&out.stderr)
    );
    let model = dir.join("m.hsm");
    // Trained to convergence (an LN of a few epochs still goes back against the effort on
    // some rays, and train refuses it): it verifies.
    let out = handctl(&["train", s(&session), "-o", s(&model), "--model", "ln"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(
        text(&out.stdout).contains("effort rays of the calibration: verified: 0 of "),
        "{}",
        text(&out.stdout)
    );
    assert!(model.exists());
    // A channel count that does not match the file is refused, naming the shape.
    let out = handctl(&[
        "import",
        "--samples",
        s(&npy),
        "--labels",
        s(&dir.join("labels.csv")),
        "--channels",
        "6",
        "-o",
        s(&dir.join("bad")),
    ]);
    assert_eq!(out.status.code(), Some(1));
    assert!(
        text(&out.stderr).contains("channels"),
        "{}",
        text(&out.stderr)
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn the_demo_says_how_to_build_it_and_socket_failures_are_not_usage_errors() {
    if !cfg!(feature = "sim") {
        let out = handctl(&["demo", "--fast"]);
        assert_eq!(out.status.code(), Some(1));
        let e = text(&out.stderr);
        assert!(
            e.contains("cargo run --release -p handctl --features sim -- demo"),
            "{e}"
        );
    }
    let dir = tmp("nosocket");
    let out = handctl(&["status", "--socket", s(&dir.join("handctl.sock"))]);
    assert_eq!(out.status.code(), Some(1));
    let e = text(&out.stderr);
    assert!(
        e.contains("cannot talk to handd") && e.contains("handctl.sock"),
        "{e}"
    );
}

/// A session no model can fit without going back against the effort: the index finger's
/// extension is its flexion's very pattern at half the amplitude, so along a flexion ray the
/// label must pass -1 (at half effort) on its way from 0 to +1. Two channels, rest included.
fn contradictory_session(dir: &Path) -> PathBuf {
    std::fs::create_dir_all(dir).unwrap();
    let plan: [(&str, [f64; 2]); 3] = [
        ("rest", [5.0, 5.0]),
        ("flexion", [100.0, 40.0]),
        ("extension", [50.0, 20.0]),
    ];
    let mut samples = Vec::new();
    let mut labels = String::from("finger,kind,repetition,start_sample,end_sample\n");
    let mut rng = 11u64;
    for rep in 1..=2 {
        for (kind, amps) in plan {
            let start = samples.len() / 2;
            for _ in 0..2000 {
                for a in amps {
                    samples.push((a * noise(&mut rng)).round());
                }
            }
            let finger = if kind == "rest" { "all" } else { "index" };
            labels.push_str(&format!("{finger},{kind},{rep},{start},{}\n", start + 2000));
        }
    }
    let npy = dir.join("emg.npy");
    decoder::session::write_npy_f64(&npy, samples.len() / 2, 2, &samples).unwrap();
    std::fs::write(dir.join("labels.csv"), labels).unwrap();
    let session = dir.join("session");
    let out = handctl(&[
        "import",
        "--samples",
        s(&npy),
        "--labels",
        s(&dir.join("labels.csv")),
        "--channels",
        "2",
        "--rows-are-recordings",
        "-o",
        s(&session),
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    session
}

/// The lines of `handctl eval`'s output from Table 3 to the end of Table 4.
fn tables(stdout: &str) -> String {
    let from = stdout.find("Table 3").expect("Table 3 printed");
    let rest = &stdout[from..];
    let end = rest.find("\nEffort rays").unwrap_or(rest.len());
    rest[..end].trim_end().to_string()
}

#[test]
fn train_refuses_a_reversing_model_force_records_it_and_eval_scores_the_file() {
    let dir = tmp("refuse");
    let session = contradictory_session(&dir);
    let model = dir.join("ln.hsm");
    let train = |extra: &[&str]| {
        let mut args = vec!["train", s(&session), "-o", s(&model), "--model", "ln"];
        args.extend_from_slice(&["--epochs", "40", "--seed", "2"]);
        args.extend_from_slice(extra);
        handctl(&args)
    };
    let out = train(&[]);
    let e = text(&out.stderr);
    assert_eq!(out.status.code(), Some(4), "{}{e}", text(&out.stdout));
    assert!(
        e.contains("model NOT written: the ln model REVERSES:")
            && e.contains("worst index in trial")
            && e.contains("--force"),
        "{e}"
    );
    let left: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.contains("ln.hsm"))
        .collect();
    assert!(
        left.is_empty(),
        "nothing written, no partial file: {left:?}"
    );

    let out = train(&["--force", "--patient", "P-006"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    // An imported session has no date: the calibration date is the training's, and train
    // says so.
    assert!(
        text(&out.stderr).contains("the session records no date"),
        "{}",
        text(&out.stderr)
    );
    let m = decoder::model::TrainedModel::load(&model, None).unwrap();
    // The session's id is its directory's name.
    let origin = m.provenance().expect("train records the provenance");
    let name = session.file_name().unwrap().to_string_lossy();
    assert_eq!(
        (origin.patient.as_deref(), origin.session.as_str()),
        (Some("P-006"), name.as_ref())
    );
    let v = m.verification().expect("the file records its verification");
    assert!(v.forced && v.reversing > 0 && v.rays > 0, "{v:?}");
    assert_eq!(v.method, decoder::model::verify::Method::Exact);
    let rest = m.rest_rms_uv().expect("the session has rest trials");
    assert_eq!(rest.len(), 2);
    // Rest is white noise uniform in ±5 (RMS 5/√3 = 2.89) on both channels; the 10-450 Hz
    // band keeps 440/500 of its power at 1 kHz: 2.89·√0.88 = 2.71, within 10%.
    let expected = 5.0 / 3f64.sqrt() * 0.88f64.sqrt();
    assert!(
        rest.iter().all(|&r| (r / expected - 1.0).abs() < 0.1),
        "{rest:?}, expected about {expected:.2}"
    );

    // A session that records when it was recorded gives that as the calibration date.
    let toml = session.join("session.toml");
    let t = std::fs::read_to_string(&toml).unwrap().replacen(
        "format_version = 1\n",
        "format_version = 1\nrecorded_utc = \"2026-11-30T09:12:55Z\"\n",
        1,
    );
    std::fs::write(&toml, t).unwrap();
    let out = train(&["--force", "--patient", "P-006"]);
    let e = text(&out.stderr);
    assert!(
        out.status.success() && !e.contains("records no date"),
        "{e}"
    );
    let m = decoder::model::TrainedModel::load(&model, None).unwrap();
    assert_eq!(
        m.provenance().expect("provenance").calibrated_utc,
        "2026-11-30T09:12:55Z"
    );

    let out = handctl(&["eval", "--model", s(&model), s(&session)]);
    let o = text(&out.stdout);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(
        o.contains("its file records: FORCED:") && o.contains("nothing trained"),
        "{o}"
    );
    assert!(
        o.contains("ln effort-ray check, exact") && o.contains("REVERSES"),
        "{o}"
    );
    // One path: the tables of the saved model equal those of `handctl eval` training the
    // same model (same session, seed and epochs) and testing on the same windows.
    let trained = handctl(&[
        "eval",
        s(&session),
        "--test",
        s(&session),
        "--models",
        "ln",
        "--epochs",
        "40",
        "--seed",
        "2",
    ]);
    assert!(trained.status.success(), "{}", text(&trained.stderr));
    assert_eq!(tables(&o), tables(&text(&trained.stdout)));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Issue 28: the completions and the manual pages come from the clap definitions: every
/// subcommand is in the bash completion and has its own page, and handd prints its page.
#[test]
fn completions_and_manual_pages_cover_every_subcommand() {
    let subcommands = [
        "train",
        "eval",
        "import-3dc",
        "check",
        "verify",
        "import",
        "decode",
        "status",
        "tune",
        "arm",
        "stop",
        "deploy",
        "rollback",
        "monitor",
        "record",
        "replay",
        "calibrate",
        "demo",
        "completions",
    ];
    let out = handctl(&["completions", "bash"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let bash = text(&out.stdout);
    for sub in subcommands {
        assert!(bash.contains(sub), "the bash completion lacks {sub}");
    }
    for shell in ["zsh", "fish"] {
        let out = handctl(&["completions", shell]);
        assert!(out.status.success() && out.stdout.len() > 1000, "{shell}");
    }
    // `handctl completions bash | head -0`: the reader gone before handctl writes ends it
    // quietly with 141 (as SIGPIPE would), not with a panic's backtrace.
    let (reader, writer) = std::io::pipe().expect("pipe");
    drop(reader);
    let closed = Command::new(env!("CARGO_BIN_EXE_handctl"))
        .args(["completions", "bash"])
        .stdout(writer)
        .output()
        .expect("run handctl");
    assert!(
        closed.status.code() == Some(141) && closed.stderr.is_empty(),
        "{:?}: {}",
        closed.status,
        text(&closed.stderr)
    );
    let bad = handctl(&["completions", "tcsh"]);
    assert_eq!(
        bad.status.code(),
        Some(2),
        "an unknown shell is a usage error"
    );
    let dir = tmp("man");
    let out = handctl(&["man", s(&dir)]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let page = std::fs::read_to_string(dir.join("handctl.1")).expect("handctl.1");
    assert!(page.contains(".TH handctl 1"), "{page}");
    for sub in subcommands {
        let page = std::fs::read_to_string(dir.join(format!("handctl-{sub}.1")))
            .unwrap_or_else(|e| panic!("handctl-{sub}.1: {e}"));
        assert!(
            page.contains(&format!(".TH handctl-{sub} 1")),
            "{sub}: {page}"
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
