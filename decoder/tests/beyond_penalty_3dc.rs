//! Issue 25 item 3, the training side: the default effort-ray penalty, extended past full
//! effort to each ray's envelope edge (`EffortPenalty::beyond` = 3, the default since session
//! 32, charged on the label the hand gets), against the same penalty stopped at full effort
//! (`beyond` = 0, the default before), on P4, P6 and P7 (train -> test, seed 0). Measures the
//! rays reversing beyond full effort (exact, `verify_beyond`) and the interpolation figures the
//! default must keep (correct >= 99%, asserted; against LN trained with the defaults, printed).
//! Figures in docs/EVALUATION.md ("Beyond full effort").

mod data_3dc;
use data_3dc::data_dir;

use decoder::eval::{evaluate_model, InterpolationConfig};
use decoder::model::verify::{
    verify_beyond, verify_windows, RayVerifier, BEYOND_EFFORT, DEFAULT_TOLERANCE,
};
use decoder::model::{train, EffortPenalty, ModelKind, ModelSpec, TrainConfig};
use decoder::session::{load_3dc, Split, WindowOptions};

#[test]
// A measurement against the option the default replaced (six trainings): kept out of the test
// command's time budget. Run it with
// `cargo test --release -p decoder --test beyond_penalty_3dc -- --ignored --nocapture`.
#[ignore = "measures the option the default replaced; about 60 s: run with --ignored"]
fn the_penalty_past_full_effort_against_the_default() {
    let beyond = 3;
    for participant in [4, 6, 7] {
        let train_s = load_3dc(&data_dir(participant), Split::Train).unwrap();
        let test_s = load_3dc(&data_dir(participant), Split::Test).unwrap();
        let opts = WindowOptions::default();
        let train_w = train_s.windows(&opts).unwrap();
        let data = train_w.to_dataset(&train_s.meta.chain).unwrap();
        let test = test_s.windows(&opts).unwrap();
        let icfg = InterpolationConfig::default();
        let default = TrainConfig::default();
        assert_eq!(default.effort.map(|e| e.beyond), Some(beyond));
        let to_full = TrainConfig {
            effort: Some(EffortPenalty {
                beyond: 0,
                ..EffortPenalty::default()
            }),
            ..default
        };
        let ln = train(
            ModelKind::Ln,
            &ModelSpec::default(),
            &data,
            &default,
            &mut |_| {},
        )
        .unwrap();
        let ln_e = evaluate_model(&ln, &test, &icfg).unwrap();
        let mut reversing = Vec::new();
        for (name, cfg) in [("to full effort only", to_full), ("default", default)] {
            let m = train(
                ModelKind::ResDd,
                &ModelSpec::default(),
                &data,
                &cfg,
                &mut |_| {},
            )
            .unwrap();
            let e = evaluate_model(&m, &test, &icfg).unwrap();
            let acc = e
                .direction
                .iter()
                .flatten()
                .map(|d| d.accuracy)
                .fold(1.0f64, f64::min);
            let mut v = RayVerifier::exact(&m).unwrap();
            let trials = &train_s.meta.trials;
            let unit = verify_windows(&mut v, &train_w, trials, DEFAULT_TOLERANCE).unwrap();
            let b =
                verify_beyond(&mut v, &train_w, trials, DEFAULT_TOLERANCE, BEYOND_EFFORT).unwrap();
            println!(
                "P{participant} {name}: correct {:.2}% (LN {:.2}%), min accuracy {:.2}%, rest \
                 |y| {:.3}; [0,1] {} of {} reverse; [0,10] {} reverse (worst {:.3}), {} \
                 overshoot; epochs {}",
                100.0 * e.interpolation_total.correct_rate(),
                100.0 * ln_e.interpolation_total.correct_rate(),
                100.0 * acc,
                e.rest_mean_abs.unwrap_or(f64::NAN),
                unit.reversing(),
                unit.rays(),
                b.reversing(),
                b.worst().map_or(0.0, |w| w.worst.amount),
                b.overshooting(),
                m.summary().epochs_run
            );
            assert!(b.rays() > 3000 && b.not_held() == 0);
            assert_eq!(unit.reversing(), 0, "P{participant} {name}: [0, 1]");
            let correct = e.interpolation_total.correct_rate();
            assert!(correct >= 0.99, "P{participant} {name}: correct {correct}");
            // Not asserted: ResDD >= LN. LN trained with the default gains from the penalty
            // past full effort too, and on P4 at seed 0 it reaches 3345 of 3345 correct curves
            // against ResDD's 3342 (a miss, docs/EVALUATION.md), printed above.
            reversing.push(b.reversing());
        }
        assert!(
            reversing[1] < reversing[0],
            "P{participant}: the default leaves {} reversing rays, the penalty to full \
             effort only {}",
            reversing[1],
            reversing[0]
        );
    }
}
