//! Issue 25 item 4: the sign a calibration never taught. The 3DC train recordings teach every
//! finger both directions (Power Grip +1, Open Hand -1), so a one-direction calibration is made
//! from them by leaving one gesture out: each participant without Open Hand (no extension
//! taught), then without Power Grip (no flexion taught). The default ResDD trained on that must not output
//! the untaught direction beyond [`TOLERANCE`] on any window of the test recording (rest, the
//! taught gesture and the gesture it never saw), and still output the taught one. The same
//! weights without the hold ([`Taught::BOTH`]) show what the network alone does.

mod data_3dc;
use data_3dc::data_dir;

use decoder::model::{train, ModelKind, ModelSpec, Taught, TrainConfig, TrainedModel, N_FINGERS};
use decoder::session::{load_3dc, LabelledWindows, Split, TrialKind, WindowOptions};

/// Largest output accepted in an untaught direction, label units (full effort is 1).
const TOLERANCE: f64 = 0.05;

/// The largest output in the direction `sign` (+1 flexion, -1 extension) over every finger and
/// window, and the share of the `taught` gesture's finger-windows beyond 0.2 its way.
fn measure(model: &TrainedModel, test: &LabelledWindows, sign: f64) -> (f64, f64) {
    let mut p = model.predictor();
    let (mut worst, mut hit, mut total) = (0.0f64, 0usize, 0usize);
    for (i, l) in test.labels.iter().enumerate() {
        let y = p.run(test.row(i));
        worst = y.iter().fold(worst, |m, v| m.max(sign * v));
        let s = l.targets[0];
        if s == -sign && l.targets.iter().all(|t| *t == s) {
            total += N_FINGERS;
            hit += y.iter().filter(|v| s * **v > 0.2).count();
        }
    }
    (worst, hit as f64 / total.max(1) as f64)
}

/// Trains the default ResDD on `participant`'s train recording without `left_out`'s trials and
/// checks the untaught direction on the test recording.
fn check(participant: u32, left_out: TrialKind) {
    let train_s = load_3dc(&data_dir(participant), Split::Train).unwrap();
    let test_s = load_3dc(&data_dir(participant), Split::Test).unwrap();
    let opts = WindowOptions::default();
    let trials = &train_s.meta.trials;
    let train_w = train_s
        .windows(&opts)
        .unwrap()
        .filter_trials(|t| trials[t].kind != left_out);
    assert!(train_w.len() > 500, "{} training windows", train_w.len());
    let data = train_w.to_dataset(&train_s.meta.chain).unwrap();
    let model = train(
        ModelKind::ResDd,
        &ModelSpec::default(),
        &data,
        &TrainConfig::default(),
        &mut |_| {},
    )
    .unwrap();
    let untaught = left_out.target();
    let t = model.taught();
    for f in 0..N_FINGERS {
        assert_eq!(
            (t.flexion[f], t.extension[f]),
            (untaught < 0.0, untaught > 0.0),
            "finger {f}: {t:?}"
        );
    }
    // The stage is part of the model file: it comes back from it.
    let back = TrainedModel::from_bytes(&model.to_bytes().unwrap(), None).unwrap();
    assert_eq!(back.taught(), t);

    let test = test_s.windows(&opts).unwrap();
    let (held, taught_rate) = measure(&model, &test, untaught);
    let raw = model.clone().with_taught(Taught::BOTH);
    let (unheld, raw_rate) = measure(&raw, &test, untaught);
    println!(
        "P{participant} without {}: largest output the untaught way {:.3} without the hold, \
         {held:.3} with it; the taught gesture's finger-windows beyond 0.2: {:.2}% ({:.2}% \
         without the hold)",
        left_out.name(),
        untaught * unheld,
        100.0 * taught_rate,
        100.0 * raw_rate
    );
    assert!(
        held <= TOLERANCE,
        "P{participant}: output {held:.3} in the untaught direction"
    );
    // The hold never touches the taught direction.
    assert_eq!(taught_rate, raw_rate);
    assert!(
        taught_rate >= 0.9,
        "P{participant}: the taught gesture reached only {:.2}%",
        100.0 * taught_rate
    );
}

#[test]
fn p4_never_moves_a_way_it_was_not_taught() {
    check(4, TrialKind::Extension);
    check(4, TrialKind::Flexion);
}

#[test]
fn p6_never_moves_a_way_it_was_not_taught() {
    check(6, TrialKind::Extension);
    check(6, TrialKind::Flexion);
}

#[test]
fn p7_never_moves_a_way_it_was_not_taught() {
    check(7, TrialKind::Extension);
    check(7, TrialKind::Flexion);
}
