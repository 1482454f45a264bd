//! Issue 25 item 3, the training side: the effort-ray penalty extended past full effort to each
//! ray's envelope edge (`EffortPenalty::beyond` = 3, not the default) against today's default,
//! on P4, P6 and P7 (train -> test, seed 0). Measures the rays reversing beyond full effort
//! (exact, `verify_beyond`) and the interpolation figures the default must keep (correct >= 99%
//! and >= today's LN). Measured: reversing rays P4 890 -> 21 (worst 0.756 -> 0.038), P6 134
//! -> 0, P7 229 -> 14 (0.149 -> 0.034); correct P4 99.73 -> 100.00%, P6 99.88 -> 99.69%, P7
//! 99.28 -> 99.28% (LN 99.64, 99.45, 99.28). Not the default: trained this way, P7 with channel
//! 4 at ten times its level points 39.4% of its movement finger-windows the wrong way (26.8%
//! with today's default; eval_3dc's bar is 30%), and LN trained the same way beats it on P6.

mod data_3dc;
use data_3dc::data_dir;

use decoder::eval::{evaluate_model, InterpolationConfig};
use decoder::model::verify::{
    verify_beyond, verify_windows, RayVerifier, BEYOND_EFFORT, DEFAULT_TOLERANCE,
};
use decoder::model::{train, EffortPenalty, ModelKind, ModelSpec, TrainConfig};
use decoder::session::{load_3dc, Split, WindowOptions};

#[test]
// A measurement of an option that is off (about 50 s: six trainings): kept out of the test
// command's time budget. Run it with
// `cargo test --release -p decoder --test beyond_penalty_3dc -- --ignored --nocapture`.
#[ignore = "measures an option that is off; about 50 s: run with --ignored"]
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
        let extended = TrainConfig {
            effort: Some(EffortPenalty {
                beyond,
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
        for (name, cfg) in [("default", default), ("beyond", extended)] {
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
            assert!(
                correct >= ln_e.interpolation_total.correct_rate(),
                "P{participant} {name}: below LN"
            );
            reversing.push(b.reversing());
        }
        assert!(
            reversing[1] < reversing[0],
            "P{participant}: the penalty past full effort leaves {} reversing rays, the \
             default {}",
            reversing[1],
            reversing[0]
        );
    }
}
