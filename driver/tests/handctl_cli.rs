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

    let model = session.join("resdd.model");
    let out = handctl(&[
        "train",
        s(&session),
        "-o",
        s(&model),
        "--epochs",
        "5",
        "--seed",
        "3",
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(text(&out.stdout).contains("wrote"), "{}", text(&out.stdout));
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
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let o = text(&out.stdout);
    assert!(o.contains("Table 3") && o.contains("Table 4"), "{o}");
    assert!(
        o.lines().any(|l| l.starts_with("resdd ")) && o.lines().any(|l| l.starts_with("ln ")),
        "{o}"
    );
    for f in [
        "roc_resdd.png",
        "interpolation_resdd.png",
        "roc_ln.png",
        "interpolation_ln.png",
    ] {
        let bytes = std::fs::read(plots.join(f)).unwrap_or_else(|e| panic!("{f}: {e}"));
        assert_eq!(&bytes[..4], b"\x89PNG", "{f}");
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

#[test]
fn errors_are_clear() {
    let out = handctl(&["train", "/nonexistent/session", "-o", "/tmp/x.model"]);
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

    let out = handctl(&["train", "3dc:/nowhere:validation", "-o", "/tmp/x.model"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(
        text(&out.stderr).contains("validation"),
        "{}",
        text(&out.stderr)
    );
}
