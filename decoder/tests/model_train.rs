//! Training: learning a known mapping, determinism, early stopping, splits, and every refusal.

mod model_support;

use decoder::model::{
    train, CnnSpec, Dataset, EffortPenalty, EpochReport, LnSpec, MlpSpec, Model, ModelKind,
    ModelSpec, Optimizer, ResDdSpec, RestFit, TrainConfig, TrainError, Trainable, ValidationSplit,
};
use model_support::{calibration, chain};

fn small_spec() -> ModelSpec {
    let d = ModelSpec::default();
    ModelSpec {
        resdd: ResDdSpec {
            hidden: 16,
            ..d.resdd
        },
        ln: LnSpec { hidden: [16, 16] },
        mlp: MlpSpec { hidden: [24, 16] },
        cnn: CnnSpec {
            filters: [6, 6],
            dense: 16,
            ..d.cnn
        },
    }
}

fn quick(epochs: usize) -> TrainConfig {
    TrainConfig {
        max_epochs: epochs,
        patience: 10,
        ..TrainConfig::default()
    }
}

/// Fraction of windows whose finger's output has the trial's sign.
fn sign_accuracy(m: &decoder::model::TrainedModel, d: &Dataset) -> f64 {
    let (mut ok, mut n) = (0, 0);
    for i in 0..d.len() {
        let y = m.predict(d.row(i));
        for (f, yf) in y.iter().enumerate() {
            let t = d.target(i)[f];
            if d.mask(i)[f] && t != 0.0 {
                n += 1;
                if yf.signum() == t.signum() {
                    ok += 1;
                }
            }
        }
    }
    ok as f64 / n as f64
}

#[test]
fn every_kind_learns_the_direction_of_each_finger() {
    let data = calibration(2, 2, 12, 1);
    let test = calibration(2, 1, 12, 1); // same mixing (same seed), fresh windows
    for kind in ModelKind::ALL {
        let mut reports = Vec::new();
        let m = train(kind, &small_spec(), &data, &quick(60), &mut |r| {
            reports.push(r)
        })
        .expect("trains");
        let first = reports.first().expect("one epoch at least");
        let best = m.summary().best_val_loss.expect("trial split");
        assert!(
            best < 0.5 * first.val_loss.unwrap(),
            "{kind}: val loss {best} vs first {:?}",
            first.val_loss
        );
        let acc = sign_accuracy(&m, &test);
        assert!(acc >= 0.95, "{kind}: sign accuracy {acc}");
        assert_eq!(m.model().kind(), kind);
    }
}

#[test]
fn same_seed_same_bits_other_seed_other_weights() {
    let data = calibration(2, 2, 6, 2);
    let cfg = quick(8);
    for kind in ModelKind::ALL {
        let a = train(kind, &small_spec(), &data, &cfg, &mut |_| {}).expect("trains");
        let b = train(kind, &small_spec(), &data, &cfg, &mut |_| {}).expect("trains");
        let bits = |m: &decoder::model::TrainedModel| -> Vec<u64> {
            m.model().params().iter().map(|p| p.to_bits()).collect()
        };
        assert_eq!(
            bits(&a),
            bits(&b),
            "{kind}: same seed must give identical weights"
        );
        assert_eq!(a.normalizer(), b.normalizer());
        let c = train(
            kind,
            &small_spec(),
            &data,
            &TrainConfig { seed: 9, ..cfg },
            &mut |_| {},
        )
        .expect("trains");
        assert_ne!(
            bits(&a),
            bits(&c),
            "{kind}: another seed must give other weights"
        );
    }
}

#[test]
fn progress_reports_every_epoch_and_early_stopping_keeps_the_best() {
    let data = calibration(2, 2, 6, 3);
    let cfg = TrainConfig {
        max_epochs: 400,
        patience: 5,
        optimizer: Optimizer::Adam {
            lr: 0.03,
            beta1: 0.9,
            beta2: 0.999,
            eps: 1e-8,
        },
        split: ValidationSplit::Trial { fraction: 0.2 },
        ..TrainConfig::default()
    };
    let mut reports: Vec<EpochReport> = Vec::new();
    let m = train(ModelKind::ResDd, &small_spec(), &data, &cfg, &mut |r| {
        reports.push(r)
    })
    .expect("trains");
    let s = m.summary();
    assert_eq!(reports.len(), s.epochs_run);
    for (i, r) in reports.iter().enumerate() {
        assert_eq!(r.epoch, i + 1);
        assert_eq!(r.max_epochs, 400);
        assert!(r.train_loss.is_finite() && r.val_loss.is_some());
    }
    assert!(
        s.stopped_early,
        "patience 5 must stop well before 400 epochs"
    );
    assert_eq!(s.epochs_run, s.best_epoch + 5);
    let best = reports
        .iter()
        .map(|r| r.val_loss.unwrap())
        .fold(f64::INFINITY, f64::min);
    assert_eq!(s.best_val_loss, Some(best));
    assert_eq!(reports[s.best_epoch - 1].val_loss, Some(best));
    // Whole trials are held out (22 trials, 2 repetitions of each label).
    assert_eq!(s.n_train_trials + s.n_val_trials, 22);
    assert!(s.n_val_trials >= 1 && s.n_val_windows == 6 * s.n_val_trials);
}

#[test]
fn sgd_window_split_and_no_split_train() {
    let data = calibration(2, 1, 10, 4);
    // SGD's step is not scale-free like Adam's: the penalty's default weight (tuned with Adam)
    // would multiply its step 30-fold, so SGD runs with weight 1.
    let sgd = TrainConfig {
        optimizer: Optimizer::sgd(),
        split: ValidationSplit::Window { fraction: 0.25 },
        effort: Some(EffortPenalty {
            weight: 1.0,
            ..EffortPenalty::default()
        }),
        ..quick(30)
    };
    let m = train(ModelKind::Ln, &small_spec(), &data, &sgd, &mut |_| {}).expect("sgd trains");
    assert_eq!(m.summary().n_val_windows, 28); // round(0.25 * 110)
    assert!(m.summary().best_val_loss.unwrap() < 0.3);
    let none = TrainConfig {
        split: ValidationSplit::None,
        ..quick(5)
    };
    let mut n = 0;
    let m = train(ModelKind::ResDd, &small_spec(), &data, &none, &mut |_| {
        n += 1
    })
    .expect("trains");
    assert_eq!(
        (n, m.summary().epochs_run, m.summary().best_val_loss),
        (5, 5, None)
    );
}

#[test]
fn trial_tail_split_holds_out_the_end_of_every_trial_without_overlap() {
    // One repetition per label: the whole-trial split is impossible, the tail split works.
    let data = calibration(2, 1, 20, 8);
    let cfg = TrainConfig {
        split: ValidationSplit::TrialTail { fraction: 0.2 },
        ..quick(40)
    };
    let m = train(ModelKind::ResDd, &small_spec(), &data, &cfg, &mut |_| {}).expect("trains");
    let s = m.summary();
    // 11 trials x 20 windows: 4 held out and 3 overlapping dropped per trial (200 ms / 50 ms).
    assert_eq!((s.n_val_windows, s.n_train_windows), (44, 143));
    assert_eq!((s.n_val_trials, s.n_train_trials), (11, 11));
    assert!(s.best_val_loss.unwrap() < 0.2, "{s:?}");
    // A trial too short to split trains whole; with no trial long enough, a clear refusal.
    let mut mixed = calibration(2, 1, 4, 8);
    for i in 0..data.len() {
        if data.trial(i) == 0 {
            mixed
                .push(data.row(i), *data.target(i), *data.mask(i), 1_000)
                .unwrap();
        }
    }
    let m = train(ModelKind::ResDd, &small_spec(), &mixed, &cfg, &mut |_| {}).expect("trains");
    let s = m.summary();
    assert_eq!(
        (s.n_val_windows, s.n_train_windows),
        (4, 11 * 4 + 13),
        "{s:?}"
    );
    assert_eq!((s.n_val_trials, s.n_train_trials), (1, 12));
    let too_short = calibration(2, 1, 4, 8);
    let e = train(
        ModelKind::ResDd,
        &small_spec(),
        &too_short,
        &cfg,
        &mut |_| {},
    )
    .unwrap_err();
    assert!(
        matches!(e, TrainError::Split(ref m) if m.contains("4 windows")),
        "{e}"
    );
}

#[test]
fn refusals_name_the_problem() {
    let spec = small_spec();
    let cfg = quick(3);
    let empty = Dataset::new(chain(2)).expect("chain");
    assert_eq!(
        train(ModelKind::ResDd, &spec, &empty, &cfg, &mut |_| {}).unwrap_err(),
        TrainError::EmptyDataset
    );

    let mut masked = Dataset::new(chain(2)).expect("chain");
    for t in 0..3 {
        masked
            .push(&[1.0; 16], [f64::NAN; 5], [false; 5], t)
            .expect("NaN allowed where masked");
    }
    assert_eq!(
        train(ModelKind::ResDd, &spec, &masked, &cfg, &mut |_| {}).unwrap_err(),
        TrainError::AllMasked
    );

    // One trial per label: no trial can be held out without losing that label.
    let single = calibration(2, 1, 4, 5);
    let whole_trials = TrainConfig {
        split: ValidationSplit::Trial { fraction: 0.2 },
        ..cfg
    };
    let e = train(ModelKind::ResDd, &spec, &single, &whole_trials, &mut |_| {}).unwrap_err();
    assert!(
        matches!(e, TrainError::Split(ref m) if m.contains("repetitions")),
        "{e}"
    );

    let data = calibration(2, 2, 4, 5);
    for bad in [
        TrainConfig {
            batch_size: 0,
            ..cfg
        },
        TrainConfig {
            max_epochs: 0,
            ..cfg
        },
        TrainConfig {
            optimizer: Optimizer::Sgd {
                lr: -1.0,
                momentum: 0.9,
            },
            ..cfg
        },
        TrainConfig {
            optimizer: Optimizer::Sgd {
                lr: 0.1,
                momentum: 1.0,
            },
            ..cfg
        },
        TrainConfig {
            split: ValidationSplit::Trial { fraction: 1.0 },
            ..cfg
        },
        TrainConfig {
            min_delta: f64::NAN,
            ..cfg
        },
    ] {
        let e = train(ModelKind::ResDd, &spec, &data, &bad, &mut |_| {}).unwrap_err();
        assert!(matches!(e, TrainError::Config(_)), "{bad:?} gave {e}");
    }
    let mut bad_spec = spec;
    bad_spec.resdd.hidden = 0;
    let e = train(
        ModelKind::ResDd,
        &bad_spec,
        &data,
        &whole_trials,
        &mut |_| {},
    )
    .unwrap_err();
    assert!(e.to_string().contains("hidden width"), "{e}");

    let diverge = TrainConfig {
        optimizer: Optimizer::Sgd {
            lr: 1e6,
            momentum: 0.0,
        },
        split: ValidationSplit::None,
        ..quick(50)
    };
    let e = train(ModelKind::Ln, &spec, &data, &diverge, &mut |_| {}).unwrap_err();
    assert!(matches!(e, TrainError::Diverged { .. }), "{e}");

    let mut d = Dataset::new(chain(2)).expect("chain");
    assert_eq!(
        d.push(&[1.0; 15], [0.0; 5], [true; 5], 0).unwrap_err(),
        TrainError::FeatureCount {
            expected: 16,
            found: 15
        }
    );
    let mut x = [1.0; 16];
    x[3] = f64::INFINITY;
    assert_eq!(
        d.push(&x, [0.0; 5], [true; 5], 0).unwrap_err(),
        TrainError::NonFiniteFeature { row: 0, col: 3 }
    );
    let mut t = [0.0; 5];
    t[2] = f64::NAN;
    assert_eq!(
        d.push(&[1.0; 16], t, [true; 5], 0).unwrap_err(),
        TrainError::NonFiniteTarget { row: 0, finger: 2 }
    );
    assert!(d.is_empty());
    let bad_chain = decoder::dsp::ChainConfig {
        channels: 0,
        ..chain(2)
    };
    assert!(matches!(
        Dataset::new(bad_chain).unwrap_err(),
        TrainError::Config(_)
    ));
}

#[test]
fn masked_fingers_do_not_influence_training() {
    // Changing the target of a masked finger must not change a single bit of the weights.
    let base = calibration(2, 2, 5, 6);
    let mut other = Dataset::new(chain(2)).expect("chain");
    for i in 0..base.len() {
        let mut t = *base.target(i);
        for (tf, m) in t.iter_mut().zip(base.mask(i)) {
            if !m {
                *tf = 123.0;
            }
        }
        other
            .push(base.row(i), t, *base.mask(i), base.trial(i))
            .expect("valid");
    }
    let a = train(ModelKind::Mlp, &small_spec(), &base, &quick(4), &mut |_| {}).expect("trains");
    let b = train(
        ModelKind::Mlp,
        &small_spec(),
        &other,
        &quick(4),
        &mut |_| {},
    )
    .expect("trains");
    assert_eq!(a.model().params(), b.model().params());
}

#[test]
fn names_parse() {
    use std::str::FromStr;
    assert_eq!(ModelKind::from_str(" ResDD ").unwrap(), ModelKind::ResDd);
    for k in ModelKind::ALL {
        assert_eq!(k.name().parse::<ModelKind>().unwrap(), k);
        assert_eq!(k.to_string(), k.name());
    }
    let e = "transformer".parse::<ModelKind>().unwrap_err();
    assert!(e.to_string().contains("resdd, ln, mlp, cnn"), "{e}");
    assert_eq!("sgd".parse::<Optimizer>().unwrap(), Optimizer::sgd());
    assert_eq!("Adam".parse::<Optimizer>().unwrap(), Optimizer::adam());
    assert!("rmsprop".parse::<Optimizer>().is_err());
    assert_eq!(
        "trial-tail".parse::<ValidationSplit>().unwrap(),
        ValidationSplit::TrialTail { fraction: 0.2 }
    );
    assert_eq!(
        "none".parse::<ValidationSplit>().unwrap(),
        ValidationSplit::None
    );
    assert_eq!(
        "window".parse::<ValidationSplit>().unwrap(),
        ValidationSplit::Window { fraction: 0.2 }
    );
    assert!(matches!(
        "by-magic".parse::<ValidationSplit>().unwrap_err(),
        TrainError::Config(ref m) if m.contains("trial-tail")
    ));
}

/// Mean |output| over the rest windows (every target 0) of `d` whose trial is at least
/// `from_trial`.
fn rest_level(m: &decoder::model::TrainedModel, d: &Dataset, from_trial: usize) -> f64 {
    let rows: Vec<usize> = (0..d.len())
        .filter(|&i| d.trial(i) >= from_trial && d.target(i).iter().all(|&t| t == 0.0))
        .collect();
    let sum: f64 = rows
        .iter()
        .map(|&i| m.predict(d.row(i)).iter().map(|v| v.abs()).sum::<f64>())
        .sum();
    sum / (5 * rows.len()) as f64
}

#[test]
fn the_rest_stage_lowers_the_rest_level_and_keeps_every_sign() {
    // Two repetitions to train on; the third (same mixing, fresh noise) is new data.
    let data = calibration(2, 2, 12, 3);
    let fresh = calibration(2, 3, 12, 3);
    let first_new_trial = data.trial_ids().len();
    let m = train(
        ModelKind::ResDd,
        &small_spec(),
        &data,
        &quick(30),
        &mut |_| {},
    )
    .unwrap();
    let stage = *m.rest_stage().expect("rest windows give a rest stage");
    let raw = m.clone().with_rest_stage(None);
    for (what, from) in [("calibration", 0), ("fresh windows", first_new_trial)] {
        let (before, after) = (rest_level(&raw, &fresh, from), rest_level(&m, &fresh, from));
        assert!(
            after < 0.7 * before,
            "{what}: rest level {before} -> {after} with {stage:?}"
        );
    }
    for i in 0..fresh.len() {
        let (y, r) = (m.predict(fresh.row(i)), raw.predict(fresh.row(i)));
        for f in 0..5 {
            assert!(y[f] == 0.0 || y[f].signum() == r[f].signum(), "window {i}");
        }
    }
    // Without rest windows (a two-point calibration) or with the stage off: raw outputs.
    let two_point = {
        let mut d = Dataset::new(chain(2)).unwrap();
        for i in (0..data.len()).filter(|&i| data.target(i).iter().any(|&t| t != 0.0)) {
            d.push(data.row(i), *data.target(i), *data.mask(i), data.trial(i))
                .unwrap();
        }
        d
    };
    let m2 = train(
        ModelKind::Ln,
        &small_spec(),
        &two_point,
        &quick(2),
        &mut |_| {},
    )
    .unwrap();
    assert_eq!(m2.rest_stage(), None);
    let off = TrainConfig {
        rest: None,
        ..quick(2)
    };
    let m3 = train(ModelKind::Ln, &small_spec(), &data, &off, &mut |_| {}).unwrap();
    assert_eq!(m3.rest_stage(), None);
    let bad = TrainConfig {
        rest: Some(RestFit {
            max_width: 2.0,
            ..RestFit::default()
        }),
        ..quick(2)
    };
    let e = train(ModelKind::Ln, &small_spec(), &data, &bad, &mut |_| {}).unwrap_err();
    assert!(e.to_string().contains("max_width"), "{e}");
}
