//! `handd`'s startup as a new user (or systemd) meets it: a bad config is reported once, and a
//! log that does not go to a terminal carries no ANSI colour escapes.

use std::path::PathBuf;
use std::process::{Command, Output};

/// A scratch directory holding a config that does not parse.
fn bad_config(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("handd-startup-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("scratch directory");
    let path = dir.join("bad.toml");
    std::fs::write(&path, "interface = [\n").expect("write the bad config");
    path
}

/// `handd --check --config <bad>` with stderr piped, plus `extra` arguments and `env`.
fn check(name: &str, extra: &[&str], env: &[(&str, &str)]) -> (Output, String) {
    let config = bad_config(name);
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_handd"));
    cmd.arg("--check").arg("--config").arg(&config).args(extra);
    for var in ["NO_COLOR", "JOURNAL_STREAM", "RUST_LOG"] {
        cmd.env_remove(var);
    }
    cmd.envs(env.iter().copied());
    let out = cmd.output().expect("handd runs");
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    std::fs::remove_dir_all(config.parent().expect("scratch directory")).expect("clean up");
    (out, stderr)
}

fn assert_refused_once(out: &Output, stderr: &str) {
    assert_eq!(out.status.code(), Some(2), "exit status; stderr:\n{stderr}");
    assert_eq!(
        stderr.matches("refusing to start").count(),
        1,
        "the refusal is printed once:\n{stderr}"
    );
    assert_eq!(
        stderr.matches("bad.toml").count(),
        1,
        "the config error is printed once:\n{stderr}"
    );
    assert!(
        stderr.contains("TOML parse error"),
        "the error says what is wrong:\n{stderr}"
    );
}

#[test]
fn a_bad_config_is_reported_once_without_colour_on_a_pipe() {
    let (out, stderr) = check("pipe", &[], &[]);
    assert_refused_once(&out, &stderr);
    assert!(
        !stderr.contains("\x1b["),
        "no ANSI escapes when stderr is not a terminal:\n{stderr:?}"
    );
}

#[test]
fn under_systemd_the_journal_gets_no_colour() {
    let (out, stderr) = check("journal", &[], &[("JOURNAL_STREAM", "8:1234")]);
    assert_refused_once(&out, &stderr);
    assert!(
        !stderr.contains("\x1b["),
        "no ANSI escapes in the journal:\n{stderr:?}"
    );
}

#[test]
fn json_logs_carry_the_error_once_and_no_colour() {
    let (out, stderr) = check("json", &["--json-logs"], &[]);
    assert_refused_once(&out, &stderr);
    assert!(!stderr.contains("\x1b["), "no ANSI escapes:\n{stderr:?}");
    assert!(
        stderr.lines().all(|l| l.starts_with('{')),
        "every line is a JSON object:\n{stderr}"
    );
}
