//! The exact effort-ray verifier (issue 12): it finds a reversal the 21-point metric misses,
//! calls linear models monotonic, its polynomials are the model, and it never reports less than
//! any sampling.

use decoder::dsp::{ChainConfig, FEATURES_PER_CHANNEL};
use decoder::eval::{judge_curve, InterpolationConfig};
use decoder::model::verify::{
    eval_polynomial, verify_windows, Method, RayCurves, RayVerifier, VerificationRecord,
    DEFAULT_TOLERANCE, SAMPLED_POINTS,
};
use decoder::model::{
    AnyModel, LnSpec, Model, ModelKind, ModelSpec, Normalizer, ResDdSpec, ResDdVariant, RestStage,
    Trainable, TrainedModel, TrainingSummary, N_FINGERS,
};
use decoder::session::{LabelledWindows, Trial, TrialKind, WindowLabel};
use proptest::prelude::*;
use proptest::test_runner::RngSeed;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn bundle(model: AnyModel, spec: ModelSpec, normalizer: Normalizer) -> TrainedModel {
    let channels = Model::n_inputs(&model) / FEATURES_PER_CHANNEL;
    let chain = ChainConfig {
        channels,
        ..ChainConfig::default()
    };
    let kind = Model::kind(&model);
    TrainedModel::new(
        model,
        spec,
        normalizer,
        chain,
        TrainingSummary::untrained(kind),
    )
    .unwrap()
}

fn resdd_spec(hidden: usize, modules: usize, variant: ResDdVariant) -> ModelSpec {
    ModelSpec {
        resdd: ResDdSpec {
            hidden,
            modules,
            variant,
        },
        ..ModelSpec::default()
    }
}

/// One channel, H = 2, one module. With RMS = VAR = 1, `X = (k, k²)` and every finger's output
/// is `S·[((k-m)³ + m³)/3 - r²k]`, whose slope `S·((k-m)² - r²)` is negative only on
/// `(m - r, m + r) = (0.515, 0.535)`, strictly between the samples 0.5 and 0.55; over that
/// dip the output falls by `4Sr³/3 = 0.02`, twice the tolerance, yet every 0.05 step rises.
fn dipping_resdd() -> (TrainedModel, Vec<f64>) {
    dipping_resdd_at(15_000.0, 0.525, 0.01)
}

/// The same shape with scale `s`, dip centre `m` and half-width `r`: the dip falls by
/// `4·s·r³/3`, from about `s·m³/3` (so a dip below full scale needs `r/m` large).
fn dipping_resdd_at(s: f64, m: f64, r: f64) -> (TrainedModel, Vec<f64>) {
    let (c1, c2, c3) = (s * (m * m - r * r), -s * m, s / 3.0);
    let q = (c2 + c3 - c1) / 2.0;
    let (p, v) = (c2 - q, c3 - q);
    let mut w_in = vec![0.0; 2 * 8];
    w_in[0] = 1.0; // X1 = RMS
    w_in[8 + 2] = 1.0; // X2 = VAR
    let w_mod = vec![p, q, 1.0, 0.0];
    let w_out: Vec<f64> = (0..N_FINGERS).flat_map(|_| [1.0, v]).collect();
    let params = [w_in, w_mod, w_out].concat();
    let spec = resdd_spec(2, 1, ResDdVariant::InputGated);
    let model = AnyModel::from_params(ModelKind::ResDd, &spec, 8, N_FINGERS, params).unwrap();
    let mut features = vec![0.0; 8];
    features[0] = 1.0;
    features[2] = 1.0;
    (bundle(model, spec, Normalizer::identity(8)), features)
}

#[test]
fn a_dip_between_samples_is_missed_by_21_points_and_found_exactly() {
    let (model, features) = dipping_resdd();
    let mut v = RayVerifier::exact(&model).unwrap();
    let levels = InterpolationConfig::default().levels().unwrap();
    let outputs: Vec<f64> = levels
        .iter()
        .map(|&k| v.output_at(&features, k)[0])
        .collect();
    let judged = judge_curve(0, 1.0, &levels, outputs, DEFAULT_TOLERANCE).unwrap();
    assert!(
        !judged.failed && judged.correct,
        "the 21-point metric: {judged:?}"
    );
    let r = v.curves(&features).reversal(0, 1.0);
    assert_eq!(r.method, Method::Exact);
    assert!((r.amount - 0.02).abs() < 1e-9, "{r:?}");
    assert!(
        (r.from_k - 0.515).abs() < 1e-9 && (r.to_k - 0.535).abs() < 1e-9,
        "{r:?}"
    );
    assert!(r.bound < 1e-12, "{r:?}");

    let windows = LabelledWindows {
        n_features: 8,
        features: features.clone(),
        labels: vec![WindowLabel {
            trial: 0,
            targets: [1.0; N_FINGERS],
            mask: [true; N_FINGERS],
            end_sample: 0,
        }],
    };
    let trials = [Trial {
        id: 7,
        finger: None,
        kind: TrialKind::Flexion,
        repetition: 2,
        start_us: 0,
        end_us: 1,
    }];
    let report = verify_windows(&mut v, &windows, &trials, DEFAULT_TOLERANCE).unwrap();
    assert_eq!((report.rays(), report.reversing()), (5, 5));
    assert_eq!(
        (report.sampled_failed(), report.sampled_not_correct()),
        (0, 0)
    );
    assert!(!report.passed());
    let text = report.to_string();
    assert!(
        text.contains("REVERSES trial 7 (all flexion, repetition 2) thumb"),
        "{text}"
    );
}

/// One flexion window of all five fingers (trial 7) with `features`.
fn one_window(features: Vec<f64>) -> (LabelledWindows, [Trial; 1]) {
    let windows = LabelledWindows {
        n_features: features.len(),
        features,
        labels: vec![WindowLabel {
            trial: 0,
            targets: [1.0; N_FINGERS],
            mask: [true; N_FINGERS],
            end_sample: 0,
        }],
    };
    let trial = Trial {
        id: 7,
        finger: None,
        kind: TrialKind::Flexion,
        repetition: 2,
        start_us: 0,
        end_us: 1,
    };
    (windows, [trial])
}

/// An LN is linear in the features, but VAR grows as `k²`: with RMS weight -5 and VAR weight
/// 6, every finger's output along the ray through RMS = VAR = 1 is `y = 6k² - 5k`, which
/// falls to `y(5/12) = -25/24` before it rises to 1. The exact check finds that dip, so an
/// LN is verified, not assumed monotonic (trained LNs do reverse: see the report).
#[test]
fn an_ln_is_exactly_verified_and_can_reverse_through_its_var_weight() {
    let spec = ModelSpec {
        ln: LnSpec { hidden: [1, 1] },
        ..ModelSpec::default()
    };
    let mut w1 = vec![0.0; 8];
    w1[0] = -5.0; // RMS
    w1[2] = 6.0; // VAR
    let params = [w1, vec![1.0], vec![1.0; N_FINGERS]].concat();
    let ln = AnyModel::from_params(ModelKind::Ln, &spec, 8, N_FINGERS, params).unwrap();
    let model = bundle(ln, spec, Normalizer::identity(8));
    let mut v = RayVerifier::new(&model);
    assert_eq!(v.method(), Method::Exact);
    let mut features = vec![0.0; 8];
    features[0] = 1.0;
    features[2] = 1.0;
    let r = v.curves(&features).reversal(0, 1.0);
    assert!((r.amount - 25.0 / 24.0).abs() < 1e-12, "{r:?}");
    assert!(
        (r.to_k - 5.0 / 12.0).abs() < 1e-12 && r.from_k == 0.0,
        "{r:?}"
    );
    let (windows, trials) = one_window(features);
    let report = verify_windows(&mut v, &windows, &trials, DEFAULT_TOLERANCE).unwrap();
    let record = VerificationRecord::from_report(&report, false);
    assert_eq!(
        (record.rays, record.reversing, record.forced),
        (5, 5, false)
    );
    let text = record.to_string();
    assert!(
        text.starts_with(
            "REVERSES: 5 of 5 rays reverse beyond 0.01 (exact); worst thumb in \
             trial 7 (all flexion, repetition 2) by 1.0417 (effort 0.000 to 0.417)"
        ),
        "{text}"
    );
    let forced = VerificationRecord::from_report(&report, true);
    assert!(forced.forced && forced.to_string().starts_with("FORCED: 5 of 5"));
    assert_eq!(forced.check(), Ok(()));
}

/// MLP and CNN (ReLU) are not polynomials along a ray: they are checked at
/// [`SAMPLED_POINTS`] efforts and their record says so; a pass is never called exact.
#[test]
fn mlp_and_cnn_are_verified_by_dense_sampling_and_say_so() {
    let n_in = 2 * FEATURES_PER_CHANNEL;
    let mut rng = ChaCha8Rng::seed_from_u64(4);
    for kind in [ModelKind::Mlp, ModelKind::Cnn] {
        let spec = ModelSpec::default();
        let model = AnyModel::random(kind, &spec, n_in, N_FINGERS, 8).unwrap();
        let model = bundle(model, spec, Normalizer::identity(n_in));
        let mut v = RayVerifier::new(&model);
        assert_eq!(v.method(), Method::Sampled(SAMPLED_POINTS), "{kind}");
        assert!(RayVerifier::exact(&model).is_err(), "{kind}");
        let (windows, trials) = one_window(random_features(&mut rng, n_in, false));
        let report = verify_windows(&mut v, &windows, &trials, DEFAULT_TOLERANCE).unwrap();
        let record = VerificationRecord::from_report(&report, false);
        assert_eq!(record.method, Method::Sampled(SAMPLED_POINTS));
        let text = record.to_string();
        assert!(
            text.contains(&format!(
                "(sampled at {SAMPLED_POINTS} efforts, not a proof)"
            )),
            "{kind}: {text}"
        );
        // Beyond full effort too: sampled over [0, 10], said so; with an envelope at the
        // window itself the output past effort 1 is the predictor's at 1.
        let features = windows.features.clone();
        let held = model
            .clone()
            .with_envelope(Some(decoder::model::Envelope::try_new(features).unwrap()))
            .unwrap();
        let mut v = RayVerifier::new(&held);
        let b = decoder::model::verify::verify_beyond(
            &mut v,
            &windows,
            &trials,
            DEFAULT_TOLERANCE,
            decoder::model::verify::BEYOND_EFFORT,
        )
        .unwrap();
        assert_eq!(b.method, Method::Sampled(SAMPLED_POINTS), "{kind}");
        assert_eq!((b.rays(), b.not_held()), (report.rays(), 0), "{kind}: {b}");
        assert!(b.to_string().contains("SAMPLED"), "{kind}: {b}");
        assert!(b
            .entries
            .iter()
            .all(|e| (e.lowest_edge - 1.0).abs() < 1e-12));
        assert_eq!(
            b.reversing(),
            report.reversing(),
            "{kind}: nothing new past 1"
        );
    }
}

fn random_features(rng: &mut ChaCha8Rng, n: usize, var_zero: bool) -> Vec<f64> {
    (0..n)
        .map(|j| {
            if var_zero && j % FEATURES_PER_CHANNEL == 2 {
                0.0
            } else {
                rng.gen_range(0.0..3.0)
            }
        })
        .collect()
}

#[test]
fn linear_models_never_reverse() {
    let mut rng = ChaCha8Rng::seed_from_u64(12);
    let n_in = 3 * FEATURES_PER_CHANNEL;
    let spec = resdd_spec(16, 0, ResDdVariant::InputGated);
    let mut ln = AnyModel::random(ModelKind::Ln, &spec, n_in, N_FINGERS, 5).unwrap();
    // No VAR weights: the LN is linear in k on every ray.
    let hidden = spec.ln.hidden[0];
    let w1 = &mut ln.params_mut()[..hidden * n_in];
    for (j, w) in w1.iter_mut().enumerate() {
        if j % n_in % FEATURES_PER_CHANNEL == 2 {
            *w = 0.0;
        }
    }
    let resdd0 = AnyModel::random(ModelKind::ResDd, &spec, n_in, N_FINGERS, 6).unwrap();
    let scales: Vec<f64> = (0..n_in).map(|_| rng.gen_range(0.1..2.0)).collect();
    for (model, var_zero) in [(ln, false), (resdd0, true)] {
        let model = bundle(
            model,
            spec,
            Normalizer::from_scales(scales.clone()).unwrap(),
        );
        let mut v = RayVerifier::exact(&model).unwrap();
        for _ in 0..200 {
            let f = random_features(&mut rng, n_in, var_zero);
            let c = v.curves(&f);
            for finger in 0..N_FINGERS {
                let end = c.value(finger, 1.0);
                let dir = if end >= 0.0 { 1.0 } else { -1.0 };
                let with = c.reversal(finger, dir);
                assert!(with.amount <= 1e-12, "{with:?}");
                let against = c.reversal(finger, -dir);
                assert!((against.amount - end.abs()).abs() <= 1e-12 * end.abs().max(1.0));
            }
        }
    }
}

#[test]
fn the_polynomials_are_the_model() {
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let n_in = 10 * FEATURES_PER_CHANNEL;
    for (kind, variant) in [
        (ModelKind::ResDd, ResDdVariant::InputGated),
        (ModelKind::ResDd, ResDdVariant::Chained),
        (ModelKind::Ln, ResDdVariant::InputGated),
    ] {
        let spec = resdd_spec(96, 2, variant);
        let model = AnyModel::random(kind, &spec, n_in, N_FINGERS, 9).unwrap();
        let scales: Vec<f64> = (0..n_in).map(|_| rng.gen_range(0.1..2.0)).collect();
        let model = bundle(model, spec, Normalizer::from_scales(scales).unwrap());
        let mut v = RayVerifier::exact(&model).unwrap();
        for _ in 0..20 {
            let f = random_features(&mut rng, n_in, false);
            let RayCurves::Polynomials(p, stage) = v.curves(&f) else {
                panic!("a {kind} model verifies exactly");
            };
            assert!(stage.is_identity(), "no rest stage, every direction taught");
            for _ in 0..10 {
                let k: f64 = rng.gen_range(0.0..=1.0);
                let y = v.output_at(&f, k);
                for (finger, yf) in y.iter().enumerate() {
                    let e = eval_polynomial(&p[finger], k);
                    assert!(
                        (e - yf).abs() <= 1e-9 * yf.abs().max(1.0),
                        "{kind} {variant:?} k {k}: polynomial {e}, forward {yf}"
                    );
                }
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 300,
        rng_seed: RngSeed::Fixed(12),
        failure_persistence: None,
        ..ProptestConfig::default()
    })]

    #[test]
    fn exact_is_never_below_dense_sampling(
        seed in any::<u64>(),
        chained in any::<bool>(),
        features in proptest::collection::vec(0.0f64..3.0, 8),
        dir in prop_oneof![Just(1.0f64), Just(-1.0f64)],
        finger in 0..N_FINGERS,
        width in prop_oneof![Just(0.0f64), 0.0f64..0.5],
    ) {
        let variant = if chained { ResDdVariant::Chained } else { ResDdVariant::InputGated };
        let spec = resdd_spec(4, 2, variant);
        let model = AnyModel::random(ModelKind::ResDd, &spec, 8, N_FINGERS, seed).unwrap();
        // With a rest stage (width > 0) the exact reading goes through it, like the forward pass.
        let stage = (width > 0.0).then(|| {
            RestStage::try_new([width; N_FINGERS], [0.5 * width; N_FINGERS], 4.0).unwrap()
        });
        let model = bundle(model, spec, Normalizer::identity(8)).with_rest_stage(stage);
        let mut v = RayVerifier::exact(&model).unwrap();
        let exact = v.curves(&features).reversal(finger, dir);
        let n = 2001;
        let mut peak = f64::NEG_INFINITY;
        let mut sampled: f64 = 0.0;
        let mut scale: f64 = 1.0;
        for i in 0..n {
            let z = dir * v.output_at(&features, i as f64 / (n - 1) as f64)[finger];
            peak = peak.max(z);
            sampled = sampled.max(peak - z);
            scale = scale.max(z.abs());
        }
        prop_assert!(exact.amount >= sampled - 1e-12 * scale, "exact {exact:?}, sampled {sampled}");
        prop_assert!(exact.bound <= 1e-12 * scale, "{exact:?}");
    }
}

/// A one-channel window at half its level: RMS-like features halved, VAR (index 2) quartered.
fn at_half(full: &[f64]) -> Vec<f64> {
    full.iter()
        .enumerate()
        .map(|(j, v)| v * if j == 2 { 0.25 } else { 0.5 })
        .collect()
}

/// Issue 25 item 3: beyond full effort. A dipping ResDD (dip on `(0.502, 0.718)` of its full
/// window, from 0.826 down to 0.806: below full scale, where the hand sees it) with its window
/// at half its level (RMS 0.5, VAR 0.25) puts the dip at efforts 1.004 to 1.436: [0, 1] passes,
/// [0, 10] does not, unless the envelope holds the input at the edge before it. The exact
/// result agrees with the hand's label from the predictor sampled densely over [0, 10], and the
/// hold is confirmed on the predictor. The same dip above full scale (the first model of this
/// file, whose outputs there are in the hundreds) is no reversal of the hand's label.
#[test]
fn beyond_full_effort_the_dip_is_found_unless_the_envelope_holds_the_ray_before_it() {
    use decoder::model::verify::{verify_beyond, BEYOND_EFFORT};
    use decoder::model::{hand_label, Envelope};
    let r: f64 = 0.108;
    let (model, full) = dipping_resdd_at(0.015 / r.powi(3), 0.61, r);
    let half = at_half(&full);
    let (windows, trials) = one_window(half.clone());
    let tol = DEFAULT_TOLERANCE;
    let check = |m: &TrainedModel| {
        let mut v = RayVerifier::exact(m).unwrap();
        let unit = verify_windows(&mut v, &windows, &trials, tol).unwrap();
        let beyond = verify_beyond(&mut v, &windows, &trials, tol, BEYOND_EFFORT).unwrap();
        assert!(unit.passed(), "{unit}");
        assert_eq!(beyond.rays(), unit.rays());
        assert_eq!(beyond.not_held(), 0, "{beyond}");
        assert_eq!(beyond.resting(), 0, "one channel is never implausible");
        // Dense sampling of the real predictor over [0, 10] never finds more than the proof.
        let n = 100_001;
        let points: Vec<(f64, f64)> = (0..n)
            .map(|i| {
                let k = BEYOND_EFFORT * i as f64 / (n - 1) as f64;
                (k, hand_label(v.output_at(&half, k)[0]))
            })
            .collect();
        let sampled = decoder::model::verify::largest_drop(&points, 1.0, Method::Sampled(n));
        let exact = beyond.worst().unwrap().worst;
        assert!(
            sampled.amount <= exact.amount + exact.bound + 1e-9,
            "sampled {sampled:?} exact {exact:?}"
        );
        assert!(
            exact.amount - sampled.amount < 1e-4,
            "{sampled:?} {exact:?}"
        );
        beyond
    };
    // No envelope (an older file): the raw polynomial on [0, 10] dips at 1.05.
    let b = check(&model);
    // Counted per finger and ray, as `verify_windows` counts: 5 fingers, one ray.
    assert_eq!(
        (b.rays(), b.reversing(), b.reversing_beyond_only()),
        (5, 5, 5),
        "{b}"
    );
    let w = b.worst().unwrap().worst;
    assert!((w.amount - 0.02).abs() < 1e-6, "{w:?}");
    assert!(w.from_k > 1.0 && w.to_k < 1.5, "{w:?}");
    assert!(b.to_string().contains("NO envelope"));
    // An envelope at the full window: the edge is at effort 2, past the dip: still found.
    let wide = model
        .clone()
        .with_envelope(Some(Envelope::try_new(full.clone()).unwrap()))
        .unwrap();
    let b = check(&wide);
    assert_eq!(b.reversing(), 5, "{b}");
    assert!((b.entries[0].lowest_edge - 2.0).abs() < 1e-12, "{b}");
    // An envelope at the half window: the edge is effort 1, the input held there: no dip.
    let tight = model
        .with_envelope(Some(Envelope::try_new(half.clone()).unwrap()))
        .unwrap();
    let b = check(&tight);
    assert!(b.passed(), "{b}");
    assert!((b.entries[0].lowest_edge - 1.0).abs() < 1e-12, "{b}");
    assert!(b.to_string().contains("holds its direction"));
    // The first dipping model: the same dip at efforts 1.03-1.07, but at outputs near 700,
    // clamped to full scale for the hand: no reversal beyond full effort.
    let (above, full) = dipping_resdd();
    let half = at_half(&full);
    let (windows, trials) = one_window(half.clone());
    let mut v = RayVerifier::exact(&above).unwrap();
    assert!(v.output_at(&half, 1.05)[0] > 100.0);
    let b = verify_beyond(&mut v, &windows, &trials, tol, BEYOND_EFFORT).unwrap();
    assert!(b.passed(), "{b}");
}
