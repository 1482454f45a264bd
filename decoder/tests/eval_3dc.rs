//! ResDD trained on the 3DC train recordings (Power Grip = all fingers +1, Open Hand = -1,
//! Neutral = rest) of each participant, P4, P6 and P7, tells grip from open hand on the test
//! recordings, keeps a relaxed hand still, and, trained with the effort-ray penalty (the
//! default), is proven monotonic on every training ray by the exact verifier (issue 12).

use std::path::PathBuf;

use decoder::eval::{direction_table, evaluate_model, interpolation_table, InterpolationConfig};
use decoder::model::verify::{verify_windows, RayVerifier, DEFAULT_TOLERANCE};
use decoder::model::{train, ModelKind, ModelSpec, TrainConfig};
use decoder::session::{load_3dc, Split, WindowOptions};

fn data_dir(participant: u32) -> PathBuf {
    let d = PathBuf::from(format!(
        "{}/../../shared/data/3dc-armband-p{participant}",
        env!("CARGO_MANIFEST_DIR")
    ));
    assert!(
        d.join(format!("P{participant}_train_emg.npy")).exists(),
        "{} is missing: the tests read the real recordings from ../shared/data",
        d.display()
    );
    d
}

#[test]
fn resdd_on_3dc_separates_grip_from_open_hand_on_p4_p6_and_p7() {
    for participant in [4, 6, 7] {
        println!("P{participant}");
        check_participant(participant);
    }
}

/// The defaults' figures on one participant (seed 0, as `handctl train` trains).
fn check_participant(participant: u32) {
    let train_s = load_3dc(&data_dir(participant), Split::Train).unwrap();
    let test_s = load_3dc(&data_dir(participant), Split::Test).unwrap();
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
        assert!(d.auc >= 0.98, "finger {f}: AUC {:.3} < 0.98", d.auc);
        // The defaults reach 99.8-100% on every finger (docs/EVALUATION.md); the 99.3% that the
        // whole-trial split gave on P7 (lower than the paper's training there) fails here.
        assert!(
            d.accuracy >= 0.995,
            "finger {f}: accuracy {:.4} < 0.995",
            d.accuracy
        );
    }
    // A relaxed hand stays still: the rest windows' mean |y| (the rest stage's job).
    let rest = e
        .rest_mean_abs
        .expect("the test recording has rest windows");
    assert!(rest <= 0.05, "rest |y| {rest:.3} > 0.05");
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
