//! The embedded demo end to end on a virtual clock: simulated calibration, ResDD training, the
//! real daemon loop, and the simulated patient tracking a sine with the index finger.

use driver::demo::{run_demo, track_model, DemoEvent, DemoOptions, DriveProfile};
use driver::drive_config::DriveMode;

#[test]
fn demo_calibrates_trains_and_tracks_a_sine() {
    let dir = std::env::temp_dir().join(format!("handstack-demo-test-{}", std::process::id()));
    let opts = DemoOptions {
        fast: true,
        work_dir: dir.clone(),
        ..DemoOptions::default()
    };
    let mut phases = 0;
    let mut live = 0;
    let demo = run_demo(&opts, |e| match e {
        DemoEvent::Phase(_) => phases += 1,
        DemoEvent::Live { .. } => live += 1,
        DemoEvent::Epoch(_) => {}
    })
    .unwrap();
    let r = &demo.tracking;
    println!(
        "trials {} epochs {} train {} ms; tracking over {} samples: RMSE {:.3} MAPE {:?} R² {:.3}; latency {:?}",
        demo.trials, demo.epochs, demo.train_ms, r.samples, r.rmse, r.mape, r.r2, r.end.latency
    );
    assert_eq!(phases, 3);
    assert!(live >= 90, "live updates every 250 ms: {live}");
    assert!(demo.trials >= 30, "{}", demo.trials);
    assert!(r.samples >= 900, "20 s of 50 Hz status: {}", r.samples);
    println!(
        "selectivity: mean |label| per finger {:?}",
        r.mean_abs_label
    );
    assert!(r.r2 >= 0.9, "tracking R² {:.3} (RMSE {:.3})", r.r2, r.rmse);
    // Selectivity (issue 12): the fingers the patient does not move stay near 0.
    for f in [0, 2, 3, 4] {
        assert!(
            r.mean_abs_label[f] <= 0.15,
            "finger {f} follows the index: mean |label| {:.3} (all {:?})",
            r.mean_abs_label[f],
            r.mean_abs_label
        );
    }
    assert!(
        r.mean_abs_label[1] > 0.3,
        "the index itself moves: mean |label| {:.3}",
        r.mean_abs_label[1]
    );
    assert_eq!(r.end.counters.deadline_misses, 0);
    assert!(std::fs::metadata(&demo.model_path).unwrap().len() > 1000);
    // The model proved itself before it drove the hand, and its file says so.
    assert!(
        demo.verification.passed() && !demo.verification.forced,
        "{}",
        demo.verification
    );
    let saved = decoder::model::TrainedModel::load(&demo.model_path, None).unwrap();
    assert_eq!(saved.verification(), Some(&demo.verification));
    assert_eq!(saved.rest_rms_uv().map(<[f64]>::len), Some(12));
    assert_eq!(r.drives.drives, 0, "native fingers: no CiA 402 drive");

    // Issue 26 item 6: the same model, every finger on a simulated CiA 402 drive that the
    // daemon starts over the bus and drives in torque mode: it tracks as natively (R² >= 0.8).
    let cia402 = DemoOptions {
        drives: DriveProfile::Cia402(DriveMode::Cst),
        ..opts.clone()
    };
    let d = track_model(&saved, &cia402, |_| {}).unwrap();
    println!(
        "native:  R² {:.3} RMSE {:.3} MAPE {:?}, off-target mean |label| {:?}\n\
         cia402:  R² {:.3} RMSE {:.3} MAPE {:?}, off-target mean |label| {:?}; drives {:?}, \
         deadline misses {}",
        r.r2,
        r.rmse,
        r.mape,
        r.mean_abs_label,
        d.r2,
        d.rmse,
        d.mape,
        d.mean_abs_label,
        d.drives,
        d.end.counters.deadline_misses
    );
    assert_eq!(d.drives.drives, 5, "a drive per finger: {:?}", d.drives);
    assert!(
        d.drives.all_enabled_s.is_some_and(|t| t < opts.settle_s),
        "every drive follows its target before the score starts: {:?}",
        d.drives
    );
    assert_eq!(d.drives.enabled_at_end, 5, "{:?}", d.drives);
    assert!(d.samples >= 900, "20 s of 50 Hz readings: {}", d.samples);
    assert!(
        d.r2 >= 0.8,
        "tracking R² through the drives {:.3} (RMSE {:.3})",
        d.r2,
        d.rmse
    );
    for f in [0, 2, 3, 4] {
        assert!(
            d.mean_abs_label[f] <= 0.15,
            "finger {f} follows the index: mean |label| {:.3} (all {:?})",
            d.mean_abs_label[f],
            d.mean_abs_label
        );
    }
    assert_eq!(d.end.counters.deadline_misses, 0);

    // The same drives in csv with the force as torque limit (0x6072): the joint's speed is
    // the velocity setpoint again, so the index hits its stops no faster than natively (the
    // README's table: 1.71 rad/s native, 6.00 in cst, 1.73 in csv).
    let csv = DemoOptions {
        drives: DriveProfile::Cia402(DriveMode::Csv),
        ..opts.clone()
    };
    let v = track_model(&saved, &csv, |_| {}).unwrap();
    println!(
        "csv:     R² {:.3} RMSE {:.3}, index at a stop {:.1} s, impacts {:?}; native impacts {:?}",
        v.r2, v.rmse, v.at_stop_s[1], v.impacts[1], r.impacts[1]
    );
    assert_eq!(v.drives.enabled_at_end, 5, "{:?}", v.drives);
    assert!(
        v.impacts[1].1 <= 1.8,
        "csv bounds the index's impacts as natively: {:?} (native {:?})",
        v.impacts[1],
        r.impacts[1]
    );
    assert_eq!(v.end.counters.deadline_misses, 0);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Issue 32 item 3: the quality gates refuse none of the simulator's calibration sessions (the
/// demo's full protocol and the quick one, two seeds each), and they do refuse a full session
/// whose index flexion and extension are swapped, or made the same movement, or one of whose
/// index flexions is an extension. Prints the pattern figures of each session.
#[test]
fn the_simulated_calibrations_pass_the_gates_and_a_swapped_finger_does_not() {
    use decoder::session::{check_gates, GateConfig, GateKind, Session, TrialKind};
    use driver::demo::record_scenario;
    use hand_model::Scenario;

    let root = std::env::temp_dir().join(format!("handstack-demo-gates-{}", std::process::id()));
    let mut full = None;
    for (scenario, seed) in [
        (Scenario::Calibration, 1),
        (Scenario::Calibration, 2),
        (Scenario::CalibrationQuick, 1),
        (Scenario::CalibrationQuick, 3),
    ] {
        let dir = root.join(format!("{}-{seed}", scenario.name()));
        record_scenario(&dir, seed, scenario).expect("simulated calibration");
        let s = Session::open(&dir).expect("the session opens");
        let r = check_gates(&s, &GateConfig::default()).expect("gates run");
        println!("{} seed {seed}:\n{r}", scenario.name());
        assert!(r.passed(), "{} seed {seed} refused:\n{r}", scenario.name());
        assert!(!r.patterns.is_empty(), "the pattern gates ran");
        if full.is_none() {
            full = Some(s);
        }
    }
    let s = full.expect("the full session");
    let index = |t: &decoder::session::Trial, kind| t.finger == Some(1) && t.kind == kind;
    let refused = |meta: decoder::session::SessionMeta, what: &str| {
        let bad = Session::from_parts("edited".into(), meta, s.recording.clone()).expect("parts");
        let r = check_gates(&bad, &GateConfig::default()).expect("gates run");
        println!("{what}:\n{r}");
        assert!(!r.passed(), "{what} passed the gates:\n{r}");
        r
    };

    // Every index flexion labelled extension and the reverse: consistent, distinct, inverted.
    let mut meta = s.meta.clone();
    for t in &mut meta.trials {
        if t.finger == Some(1) && t.kind != TrialKind::Rest {
            t.kind = if t.kind == TrialKind::Flexion {
                TrialKind::Extension
            } else {
                TrialKind::Flexion
            };
        }
    }
    let r = refused(meta, "index swapped");
    assert!(
        r.issues
            .iter()
            .any(|i| i.kind == GateKind::SwappedDirections { finger: Some(1) }),
        "{r}"
    );
    assert!(
        r.issues
            .iter()
            .all(|i| matches!(i.kind, GateKind::SwappedDirections { .. })),
        "only the swap: {r}"
    );

    // The patient extends at every flexion cue: the extensions' samples over the flexions'.
    let ch = s.recording.channels;
    let range = |t: &decoder::session::Trial| s.recording.range_of(t.start_us, t.end_us);
    let flex: Vec<_> = s
        .meta
        .trials
        .iter()
        .filter(|t| index(t, TrialKind::Flexion))
        .collect();
    let ext: Vec<_> = s
        .meta
        .trials
        .iter()
        .filter(|t| index(t, TrialKind::Extension))
        .collect();
    let mut rec = s.recording.clone();
    for (f, e) in flex.iter().zip(&ext) {
        let (f, e) = (range(f), range(e));
        let n = f.len().min(e.len()) * ch;
        rec.samples[f.start * ch..f.start * ch + n]
            .copy_from_slice(&s.recording.samples[e.start * ch..e.start * ch + n]);
    }
    let same = Session::from_parts("edited".into(), s.meta.clone(), rec).expect("parts");
    let r = check_gates(&same, &GateConfig::default()).expect("gates run");
    println!("index extends at every flexion cue:\n{r}");
    assert!(
        r.issues
            .iter()
            .any(|i| i.kind == GateKind::FlexionLikeExtension { finger: Some(1) }),
        "{r}"
    );

    // Once: the second index flexion holds an extension (its samples).
    let mut rec = s.recording.clone();
    let (f, e) = (range(flex[1]), range(ext[1]));
    let n = f.len().min(e.len()) * ch;
    rec.samples[f.start * ch..f.start * ch + n]
        .copy_from_slice(&s.recording.samples[e.start * ch..e.start * ch + n]);
    let id = flex[1].id;
    let once = Session::from_parts("edited".into(), s.meta.clone(), rec).expect("parts");
    let r = check_gates(&once, &GateConfig::default()).expect("gates run");
    println!("index extends at one flexion cue:\n{r}");
    assert!(
        r.issues
            .iter()
            .any(|i| i.trial_id == id && i.kind == GateKind::InconsistentPattern),
        "{r}"
    );
    std::fs::remove_dir_all(&root).unwrap();
}
