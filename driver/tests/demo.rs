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
    assert!(r.r2 >= 0.8, "tracking R² {:.3} (RMSE {:.3})", r.r2, r.rmse);
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
