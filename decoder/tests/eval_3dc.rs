//! ResDD trained on the 3DC train recordings (Power Grip = all fingers +1, Open Hand = -1,
//! Neutral = rest) tells grip from open hand on the test recordings, and, trained with the
//! effort-ray penalty (the default), is proven monotonic on every training ray by the exact
//! verifier (issue 12).

use std::path::PathBuf;

use decoder::eval::{direction_table, evaluate_model, interpolation_table, InterpolationConfig};
use decoder::model::verify::{verify_windows, RayVerifier, DEFAULT_TOLERANCE};
use decoder::model::{train, ModelKind, ModelSpec, TrainConfig};
use decoder::session::{load_3dc, Split, WindowOptions};

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
fn resdd_on_3dc_separates_grip_from_open_hand() {
    let train_s = load_3dc(&data_dir(), Split::Train).unwrap();
    let test_s = load_3dc(&data_dir(), Split::Test).unwrap();
    let opts = WindowOptions::default();
    let train_w = train_s.windows(&opts).unwrap();
    let data = train_w.to_dataset(&train_s.meta.chain).unwrap();
    // The CLI's defaults (`handctl train`): the penalty needs the full patience to leave no
    // training ray reversing.
    let cfg = TrainConfig::default();
    let model = train(
        ModelKind::ResDd,
        &ModelSpec::default(),
        &data,
        &cfg,
        &mut |_| {},
    )
    .unwrap();
    let test = test_s.windows(&opts).unwrap();
    let icfg = InterpolationConfig::default();
    let e = evaluate_model(&model, &test, &icfg).unwrap();
    println!("{}", direction_table(std::slice::from_ref(&e)));
    println!(
        "{}",
        interpolation_table(std::slice::from_ref(&e), icfg.tolerance)
    );
    for (f, d) in e.direction.iter().enumerate() {
        let d = d
            .as_ref()
            .unwrap_or_else(|| panic!("finger {f} has no direction data"));
        assert!(d.auc >= 0.9, "finger {f}: AUC {:.3} < 0.9", d.auc);
        assert!(
            d.accuracy >= 0.8,
            "finger {f}: accuracy {:.3} < 0.8",
            d.accuracy
        );
    }
    assert!(e.interpolation_total.curves > 500);
    assert!(
        e.interpolation_total.correct_rate() >= 0.99,
        "{:?}",
        e.interpolation_total
    );
    // The exact verifier: no training ray reverses beyond the tolerance.
    let mut v = RayVerifier::exact(&model).unwrap();
    let report = verify_windows(&mut v, &train_w, &train_s.meta.trials, DEFAULT_TOLERANCE).unwrap();
    println!(
        "training rays: {} of {} reverse (worst {:?})",
        report.reversing(),
        report.rays(),
        report.worst().map(|w| w.worst.amount)
    );
    assert!(report.rays() > 3000, "{} rays", report.rays());
    assert_eq!(report.reversing(), 0, "{:?}", report.worst());
}
