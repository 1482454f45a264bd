//! Sessions on disk: loading, labelling, the error messages, the importers.

mod session_support;

use decoder::session::{
    check_gates, import_table, GateConfig, SamplesSource, Session, SessionError, SessionMeta,
    TableImport, TrialKind, WindowOptions,
};
use session_support::*;

#[test]
fn windows_carry_targets_and_masks() {
    let dir = temp_dir("load");
    let meta = write_session(&dir, &clean_protocol(), 1);
    let s = Session::open(&dir).unwrap();
    assert_eq!(s.recording.len(), meta.trials.len() * TRIAL_SAMPLES);
    let w = s.windows(&WindowOptions::default()).unwrap();
    assert_eq!(w.n_features, 8 * CHANNELS);
    // The chain's first window ends at 200 samples, then one every 50: a trial of 2000
    // samples starting on a multiple of 50 holds (2000 - 200) / 50 + 1 = 37 windows.
    for ti in 0..meta.trials.len() {
        let n = w.labels.iter().filter(|l| l.trial == ti).count();
        assert_eq!(n, 37, "trial {ti}");
    }
    for l in &w.labels {
        let t = &meta.trials[l.trial];
        match (t.kind, t.finger) {
            (TrialKind::Rest, _) => {
                assert_eq!(l.targets, [0.0; 5]);
                assert_eq!(l.mask, [true; 5]);
            }
            (k, Some(f)) => {
                let want = if k == TrialKind::Flexion { 1.0 } else { -1.0 };
                assert_eq!(l.targets[f], want);
                // Selective labels: the other fingers are trained toward 0.
                assert_eq!(l.mask, [true; 5]);
                assert!((0..5).filter(|&o| o != f).all(|o| l.targets[o] == 0.0));
            }
            (_, None) => unreachable!("the protocol has no whole-hand contraction"),
        }
        let start = (t.start_us / 1000) as usize;
        let end = (t.end_us / 1000) as usize;
        assert!(l.end_sample - 200 >= start && l.end_sample <= end);
    }
    // The paper's masks: a single-finger trial counts for its finger alone.
    let paper = s
        .windows(&WindowOptions {
            mask_others: true,
            ..WindowOptions::default()
        })
        .unwrap();
    assert_eq!(paper.len(), w.len());
    for (l, p) in w.labels.iter().zip(&paper.labels) {
        assert_eq!(l.targets, p.targets);
        let t = &meta.trials[l.trial];
        let counted = p.mask.iter().filter(|&&m| m).count();
        match t.finger {
            Some(f) if t.kind != TrialKind::Rest => assert!(counted == 1 && p.mask[f]),
            _ => assert_eq!(counted, 5),
        }
    }
    // Two-point mode leaves rest out.
    let w2 = s
        .windows(&WindowOptions {
            two_point: true,
            ..WindowOptions::default()
        })
        .unwrap();
    assert_eq!(w2.len(), w.len() - 2 * 37);
    assert!(w2
        .labels
        .iter()
        .all(|l| meta.trials[l.trial].kind != TrialKind::Rest));
    // The active channel's RMS dominates in a flexion window of finger 0.
    let i = w
        .labels
        .iter()
        .position(|l| meta.trials[l.trial].kind == TrialKind::Flexion)
        .unwrap();
    let row = w.row(i);
    assert!(row[0] > 5.0 * row[2 * 8], "{row:?}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn onset_skip_drops_early_windows() {
    let dir = temp_dir("skip");
    let mut meta = write_session(&dir, &clean_protocol(), 2);
    meta.onset_skip_ms = 500.0;
    meta.write(&dir).unwrap();
    let w = Session::open(&dir)
        .unwrap()
        .windows(&WindowOptions::default())
        .unwrap();
    // (2000 - 500 - 200) / 50 + 1 = 27 per trial.
    assert_eq!(w.len(), 27 * meta.trials.len());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn metadata_round_trips() {
    let (_, meta) = synth(&clean_protocol(), 3);
    let text = meta.to_toml();
    let back = SessionMeta::parse(&text, std::path::Path::new("x/session.toml")).unwrap();
    assert_eq!(back, meta);
    // With the date the recorder writes: 1.7e9 s after the epoch.
    let dated = meta.recorded_at(1_700_000_000);
    let text = dated.to_toml();
    assert!(
        text.contains("recorded_utc = \"2023-11-14T22:13:20Z\""),
        "{text}"
    );
    let back = SessionMeta::parse(&text, std::path::Path::new("x/session.toml")).unwrap();
    assert_eq!(back, dated);
}

fn parse(text: &str) -> Result<SessionMeta, SessionError> {
    SessionMeta::parse(text, std::path::Path::new("s/session.toml"))
}

const HEAD: &str =
    "format_version = 1\n[chain]\nchannels = 4\n[recording]\nformat = \"npy\"\nfile = \"x.npy\"\n";

#[test]
fn bad_metadata_is_refused_with_a_clear_message() {
    // Bad TOML: the message carries the line.
    let e = parse("format_version = 1\n[chain\n")
        .unwrap_err()
        .to_string();
    assert!(e.contains("line 2"), "{e}");
    // Unknown field, named.
    let e = parse(&format!("{HEAD}[[trial]]\nid = 1\nfinger = 1\nkind = \"flexion\"\nrepetition = 1\nstart_us = 0\nend_us = 9\ncolour = 3\n")).unwrap_err().to_string();
    assert!(e.contains("colour"), "{e}");
    // Finger out of range.
    let e = parse(&format!("{HEAD}[[trial]]\nid = 1\nfinger = 7\nkind = \"flexion\"\nrepetition = 1\nstart_us = 0\nend_us = 9\n")).unwrap_err().to_string();
    assert!(e.contains("finger 7"), "{e}");
    // Bad kind.
    let e = parse(&format!("{HEAD}[[trial]]\nid = 1\nfinger = 1\nkind = \"wave\"\nrepetition = 1\nstart_us = 0\nend_us = 9\n")).unwrap_err().to_string();
    assert!(e.contains("wave"), "{e}");
    // End before start.
    let e = parse(&format!("{HEAD}[[trial]]\nid = 1\nfinger = \"all\"\nkind = \"rest\"\nrepetition = 1\nstart_us = 10\nend_us = 9\n")).unwrap_err().to_string();
    assert!(e.contains("not after start"), "{e}");
    // A date that is not a UTC time.
    let t = "[[trial]]\nid = 1\nfinger = 1\nkind = \"flexion\"\nrepetition = 1\nstart_us = 0\nend_us = 9\n";
    let e = parse(&format!(
        "recorded_utc = \"2026-13-01T00:00:00Z\"\n{HEAD}{t}"
    ))
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("recorded_utc") && e.contains("2026-13-01"),
        "{e}"
    );
    // Duplicate ids.
    let t = "[[trial]]\nid = 1\nfinger = \"index\"\nkind = \"flexion\"\nrepetition = 1\nstart_sample = 0\nend_sample = 900\n";
    let e = parse(&format!("{HEAD}{t}{t}")).unwrap_err().to_string();
    assert!(e.contains("appears twice"), "{e}");
    // No trials, wrong version, bad chain.
    assert!(parse(HEAD)
        .unwrap_err()
        .to_string()
        .contains("no [[trial]]"));
    let e = parse(&HEAD.replace("format_version = 1", "format_version = 9"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("format_version 9"), "{e}");
    assert!(matches!(
        parse(&format!(
            "{}{t}",
            HEAD.replace("channels = 4", "channels = 0")
        )),
        Err(SessionError::Chain(_))
    ));
    // Finger names and samples are accepted.
    let m = parse(&format!("{HEAD}{t}")).unwrap();
    assert_eq!(m.trials[0].finger, Some(1));
    assert_eq!(m.trials[0].end_us, 900_000);
}

#[test]
fn missing_files_are_named() {
    let dir = temp_dir("missing");
    let e = Session::open(&dir.join("nope")).unwrap_err().to_string();
    assert!(e.contains("nope"), "{e}");
    let e = Session::open(&dir).unwrap_err().to_string();
    assert!(e.contains("session.toml"), "{e}");
    write_session(&dir, &clean_protocol(), 4);
    std::fs::remove_file(dir.join("samples.npy")).unwrap();
    let e = Session::open(&dir).unwrap_err().to_string();
    assert!(e.contains("samples.npy"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn wrong_channel_count_in_the_recording_is_refused() {
    let dir = temp_dir("channels");
    let mut meta = write_session(&dir, &clean_protocol(), 5);
    meta.chain.channels = 6;
    meta.write(&dir).unwrap();
    let e = Session::open(&dir).unwrap_err().to_string();
    assert!(e.contains("channels"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn csv_and_label_table_import() {
    let dir = temp_dir("import");
    let (samples, meta) = synth(&clean_protocol(), 6);
    let mut csv = String::from("c0,c1,c2,c3\n");
    for s in samples.chunks(CHANNELS) {
        csv.push_str(&format!("{},{},{},{}\n", s[0], s[1], s[2], s[3]));
    }
    std::fs::write(dir.join("emg.csv"), csv).unwrap();
    let mut labels = String::from("finger,kind,repetition,start_sample,end_sample\n");
    for t in &meta.trials {
        let f = t.finger.map_or("all".to_string(), |f| f.to_string());
        labels.push_str(&format!(
            "{f},{},{},{},{}\n",
            t.kind.name(),
            t.repetition,
            t.start_us / 1000,
            t.end_us / 1000
        ));
    }
    std::fs::write(dir.join("labels.csv"), &labels).unwrap();
    let spec = TableImport {
        samples: SamplesSource::Csv(dir.join("emg.csv")),
        labels: dir.join("labels.csv"),
        chain: meta.chain.clone(),
        rows_are_recordings: false,
        full_scale: Some(2047.0),
        onset_skip_ms: 0.0,
        reference: None,
        ignore_columns: Vec::new(),
    };
    let out = dir.join("session");
    import_table(&spec, &out).unwrap();
    let s = Session::open(&out).unwrap();
    assert_eq!(s.meta.trials, meta.trials);
    assert_eq!(s.recording.samples, samples);
    assert!(check_gates(&s, &GateConfig::default()).unwrap().passed());
    // A label table with a bad kind names the line.
    std::fs::write(
        dir.join("bad.csv"),
        "finger,kind,repetition,start_sample,end_sample\n1,flexion,1,0,10\n1,wiggle,1,0,10\n",
    )
    .unwrap();
    let e = import_table(
        &TableImport {
            labels: dir.join("bad.csv"),
            ..spec
        },
        &dir.join("s2"),
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("line 3") && e.contains("wiggle"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn the_last_repetition_of_each_kind_is_held_out() {
    let (samples, meta) = synth(&clean_protocol(), 8);
    let rec = decoder::session::Recording::from_samples(CHANNELS, samples, RATE).unwrap();
    let s = Session::from_parts("synthetic".into(), meta, rec).unwrap();
    let held = s.holdout_last_repetition();
    for (t, h) in s.meta.trials.iter().zip(&held) {
        assert_eq!(*h, t.repetition == 2, "{t}");
    }
}

#[test]
fn interpolation_scales_the_chain_s_var_column_by_k_squared() {
    // The interpolation analysis assumes the chain's feature order; keep the two in step.
    use decoder::dsp::FEATURES_PER_CHANNEL;
    use decoder::eval::VAR_INDEX;
    assert_eq!(FEATURES_PER_CHANNEL, decoder::dsp::FEATURE_NAMES.len());
    assert_eq!(decoder::dsp::FEATURE_NAMES[VAR_INDEX], "VAR");
}
