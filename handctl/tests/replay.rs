//! `handctl replay`: a tape handd recorded replays bit for bit (exit 0); a tape whose inputs
//! were changed does not (exit 1, the differing rounds listed); a tape of another model is
//! refused.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use decoder::dsp::ChainConfig;
use decoder::model::{AnyModel, ModelKind, ModelSpec, Normalizer, TrainedModel, TrainingSummary};
use driver::engine::Engine;

fn handctl(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_handctl"))
        .args(args)
        .output()
        .expect("run handctl")
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

fn s(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

/// A model file with random weights (seed), a config naming it, in `dir`.
fn model_and_config(dir: &Path, seed: u64) -> (PathBuf, PathBuf) {
    let chain = ChainConfig::default();
    let n_in = 8 * chain.channels;
    let spec = ModelSpec::default();
    let model = AnyModel::random(ModelKind::ResDd, &spec, n_in, 5, seed).expect("model");
    let norm = Normalizer::from_scales(vec![100.0; n_in]).expect("normalizer");
    let trained = TrainedModel::new(
        model,
        spec,
        norm,
        chain,
        TrainingSummary::untrained(ModelKind::ResDd),
    )
    .expect("trained");
    let path = dir.join(format!("m{seed}.hsm"));
    trained.save(&path).expect("save");
    let config = dir.join(format!("handd{seed}.toml"));
    std::fs::write(
        &config,
        format!(
            "interface = \"vcan0\"\nmodel = \"{}\"\nstate_dir = \"{}\"\n",
            s(&path),
            s(dir)
        ),
    )
    .expect("config");
    (path, config)
}

/// A tape of 60 ticks of handd with `config` on a silent bus (SAFE, safe stops, diagnostics).
fn tape(dir: &Path, config: &Path) -> PathBuf {
    let config = driver::Config::load(config).expect("config");
    let loaded = driver::startup::load_model(&config.model, config.mains_hz).expect("model");
    let settings = driver::startup::engine_settings(&config, loaded.model_id);
    let path = dir.join("handd.tape");
    let (recorder, writer) = driver::tape::start(&path).expect("tape");
    let mut engine = Engine::new(&loaded.chain, loaded.model.predictor(), settings, 1_000);
    engine.record_to(recorder);
    engine.validated(1_000);
    for k in 1..=60u64 {
        let deadline = 1_000 + k * 50_000;
        engine.tick(deadline, deadline + 120);
        engine.written(deadline + 300, 180);
    }
    drop(engine);
    assert!(writer.finish());
    path
}

#[test]
fn a_tape_replays_bit_for_bit_and_a_changed_one_is_listed() {
    let dir = std::env::temp_dir().join(format!("handctl-replay-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("dir");
    let (_, config) = model_and_config(&dir, 1);
    let tape = tape(&dir, &config);

    let out = handctl(&["replay", s(&tape), "--config", s(&config)]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let stdout = text(&out.stdout);
    assert!(
        stdout.contains("60 ticks; 60 rounds of frames bit for bit, 0 differ"),
        "{stdout}"
    );

    // One tick started 30 ms late instead of 120 us: a deadline miss, which its HAND_DIAG
    // counts, so its frames differ.
    let changed = dir.join("changed.tape");
    let original = std::fs::read_to_string(&tape).expect("tape");
    let mut moved = false;
    let lines: Vec<String> = original
        .lines()
        .map(|l| {
            if !moved && l == "T 1001000 1001120" {
                moved = true;
                "T 1001000 1031120".to_string()
            } else {
                l.to_string()
            }
        })
        .collect();
    assert!(moved, "tick 20 is on the tape");
    std::fs::write(&changed, lines.join("\n") + "\n").expect("write");
    let out = handctl(&["replay", s(&changed), "--config", s(&config)]);
    assert_eq!(out.status.code(), Some(1), "{}", text(&out.stdout));
    assert!(
        text(&out.stdout).contains("differs at 1001000 us:"),
        "{}",
        text(&out.stdout)
    );
    assert!(
        text(&out.stderr).contains("differ from the tape"),
        "{}",
        text(&out.stderr)
    );

    // Another model than the run's.
    let (other, _) = model_and_config(&dir, 2);
    let out = handctl(&[
        "replay",
        s(&tape),
        "--config",
        s(&config),
        "--model",
        s(&other),
    ]);
    assert_eq!(out.status.code(), Some(1));
    assert!(
        text(&out.stderr).contains("the tape ran model"),
        "{}",
        text(&out.stderr)
    );
    std::fs::remove_dir_all(&dir).expect("clean up");
}
