//! The embedded demo end to end on a virtual clock: simulated calibration, ResDD training, the
//! real daemon loop, and the simulated patient tracking a sine with the index finger.

use driver::demo::{run_demo, DemoEvent, DemoOptions};

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
    let r = run_demo(&opts, |e| match e {
        DemoEvent::Phase(_) => phases += 1,
        DemoEvent::Live { .. } => live += 1,
        DemoEvent::Epoch(_) => {}
    })
    .unwrap();
    println!(
        "trials {} epochs {} train {} ms; tracking over {} samples: RMSE {:.3} MAPE {:?} R² {:.3}; latency {:?}",
        r.trials, r.epochs, r.train_ms, r.samples, r.rmse, r.mape, r.r2, r.end.latency
    );
    assert_eq!(phases, 3);
    assert!(live >= 90, "live updates every 250 ms: {live}");
    assert!(r.trials >= 30, "{}", r.trials);
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
    assert!(std::fs::metadata(&r.model_path).unwrap().len() > 1000);
    // The model proved itself before it drove the hand, and its file says so.
    assert!(
        r.verification.passed() && !r.verification.forced,
        "{}",
        r.verification
    );
    let saved = decoder::model::TrainedModel::load(&r.model_path, None).unwrap();
    assert_eq!(saved.verification(), Some(&r.verification));
    assert_eq!(saved.rest_rms_uv().map(<[f64]>::len), Some(12));
    std::fs::remove_dir_all(&dir).unwrap();
}
