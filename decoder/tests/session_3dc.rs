//! The 3DC armband recordings as a proxy calibration session.

use std::path::{Path, PathBuf};

use decoder::session::{
    check_gates, import_3dc, load_3dc, GateConfig, Session, Split, TrialKind, WindowOptions,
};

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

#[test]
fn both_splits_load_as_sessions() {
    for split in [Split::Train, Split::Test] {
        let s = load_3dc(&data_dir(), split).unwrap();
        assert_eq!(s.recording.channels, 10);
        assert_eq!(
            s.meta.trials.len(),
            12,
            "4 repetitions of rest, power grip, open hand"
        );
        for kind in [TrialKind::Rest, TrialKind::Flexion, TrialKind::Extension] {
            assert_eq!(s.meta.trials.iter().filter(|t| t.kind == kind).count(), 4);
        }
        assert!(s.meta.trials.iter().all(|t| t.finger.is_none()));
        let w = s.windows(&WindowOptions::default()).unwrap();
        // About 5 s per recording, less the 0.5 s onset skip and one window: ~85 windows each.
        assert!(
            w.len() > 12 * 60 && w.len() < 12 * 100,
            "{} windows",
            w.len()
        );
        let flex = w
            .labels
            .iter()
            .find(|l| s.meta.trials[l.trial].kind == TrialKind::Flexion)
            .unwrap();
        assert_eq!(flex.targets, [1.0; 5]);
        assert_eq!(flex.mask, [true; 5]);
        let r = check_gates(&s, &GateConfig::default()).unwrap();
        println!("3dc {}: {} windows; gates:\n{r}", split.name(), w.len());
    }
}

#[test]
fn any_participant_loads() {
    let shared = data_dir().join("..");
    for who in ["P6", "P7"] {
        let dir = shared.join(format!("3dc-armband-{}", who.to_lowercase()));
        let s = load_3dc(&dir, Split::Train).unwrap();
        assert_eq!(s.recording.channels, 10, "{who}");
        assert_eq!(s.meta.trials.len(), 12, "{who}");
        assert!(
            s.meta.recording.file.to_string_lossy().contains(who),
            "{who}: {}",
            s.meta.recording.file.display()
        );
    }
    // A directory without 3DC recordings names what it looked for.
    let err = load_3dc(Path::new(env!("CARGO_MANIFEST_DIR")), Split::Test).unwrap_err();
    assert!(err.to_string().contains("P<n>_test_emg.npy"), "{err}");
}

#[test]
fn import_writes_a_session_that_opens_the_same() {
    let out = std::env::temp_dir().join(format!("handstack-3dc-import-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let meta = import_3dc(&data_dir(), Split::Test, &out).unwrap();
    let opened = Session::open(&out).unwrap();
    assert_eq!(opened.meta, meta);
    let direct = Session::open_spec(&format!("3dc:{}:test", data_dir().display())).unwrap();
    assert_eq!(direct.recording, opened.recording);
    assert!(Path::new(&opened.meta.recording.file).is_absolute());
    let e = Session::open_spec("3dc:/nonexistent:test")
        .unwrap_err()
        .to_string();
    assert!(e.contains("/nonexistent"), "{e}");
    let e = Session::open_spec("3dc:/x:validation")
        .unwrap_err()
        .to_string();
    assert!(e.contains("validation"), "{e}");
    std::fs::remove_dir_all(&out).unwrap();
}

fn rec_range(s: &Session, t: &decoder::session::Trial) -> std::ops::Range<usize> {
    s.recording.range_of(t.start_us, t.end_us)
}

/// Issue 32 item 3: no false refusals. The gates (the pattern gates included) pass all six 3DC
/// sessions (P4, P6, P7, train and test); their pattern figures are printed. With the flexions'
/// samples copied over the extensions' (the participant made a fist at every cue), each session
/// is refused.
#[test]
fn the_gates_pass_all_six_sessions_and_refuse_them_with_flexion_at_every_cue() {
    let shared = data_dir().join("..");
    for who in ["p4", "p6", "p7"] {
        for split in [Split::Train, Split::Test] {
            let s = load_3dc(&shared.join(format!("3dc-armband-{who}")), split).unwrap();
            let r = check_gates(&s, &GateConfig::default()).unwrap();
            println!("3dc {who} {}:\n{r}", split.name());
            assert!(r.passed(), "{who} {} refused:\n{r}", split.name());
            assert_eq!(r.patterns.len(), 1, "the whole hand: {r}");
            // The flexions' samples copied over the extensions' (4 recordings of each).
            let mut rec = s.recording.clone();
            let ranges = |kind| -> Vec<std::ops::Range<usize>> {
                s.meta
                    .trials
                    .iter()
                    .filter(|t| t.kind == kind)
                    .map(|t| rec_range(&s, t))
                    .collect()
            };
            let ch = rec.channels;
            for (f, e) in ranges(TrialKind::Flexion)
                .into_iter()
                .zip(ranges(TrialKind::Extension))
            {
                let n = f.len().min(e.len()) * ch;
                let from = s.recording.samples[f.start * ch..f.start * ch + n].to_vec();
                rec.samples[e.start * ch..e.start * ch + n].copy_from_slice(&from);
            }
            let same = Session::from_parts(s.name.clone(), s.meta.clone(), rec).unwrap();
            let r = check_gates(&same, &GateConfig::default()).unwrap();
            println!("{who} {}, a fist at every cue:\n{r}", split.name());
            assert!(
                r.issues
                    .iter()
                    .any(|i| i.kind
                        == decoder::session::GateKind::FlexionLikeExtension { finger: None }),
                "{who} {}: {r}",
                split.name()
            );
        }
    }
}
