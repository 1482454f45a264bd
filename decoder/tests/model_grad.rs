//! Analytic gradients of every architecture against central finite differences.

use decoder::model::{
    ray_penalty, AnyModel, CnnSpec, EffortPenalty, LnSpec, MlpSpec, Model, ModelKind, ModelSpec,
    RayWork, ResDdSpec, ResDdVariant, Trainable, N_FINGERS,
};

/// Small deterministic generator (SplitMix64) so the test needs no RNG crate.
struct Gen(u64);
impl Gen {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    }
}

/// Loss `L = c · f(x)`; asserts analytic `∂L/∂θ` equals central differences.
fn check(mut m: AnyModel, seed: u64) {
    let mut g = Gen(seed);
    let x: Vec<f64> = (0..m.n_inputs()).map(|_| g.next()).collect();
    let c: Vec<f64> = (0..m.n_outputs()).map(|_| g.next()).collect();
    let mut s = m.new_scratch();
    let mut y = vec![0.0; m.n_outputs()];
    m.predict_with(&x, &mut y, &mut s);
    let mut grad = vec![0.0; m.params().len()];
    m.backward(&x, &c, &mut s, &mut grad);
    // The gradient accumulates: a second backward doubles it.
    let mut twice = grad.clone();
    m.backward(&x, &c, &mut s, &mut twice);
    for (a, b) in grad.iter().zip(&twice) {
        assert!(
            (2.0 * a - b).abs() <= 1e-12 * (1.0 + b.abs()),
            "backward must accumulate"
        );
    }
    let loss = |m: &AnyModel, s: &mut decoder::model::Scratch| {
        let mut y = vec![0.0; m.n_outputs()];
        m.predict_with(&x, &mut y, s);
        y.iter().zip(&c).map(|(a, b)| a * b).sum::<f64>()
    };
    let n = m.params().len();
    // Every parameter for small models; a strided subset beyond 3000 keeps the test quick.
    let stride = (n / 3000).max(1);
    for i in (0..n).step_by(stride) {
        let p0 = m.params()[i];
        let h = 1e-6 * (1.0 + p0.abs());
        m.params_mut()[i] = p0 + h;
        let lp = loss(&m, &mut s);
        m.params_mut()[i] = p0 - h;
        let lm = loss(&m, &mut s);
        m.params_mut()[i] = p0;
        let num = (lp - lm) / (2.0 * h);
        // Central differences carry ~1e-10 of round-off here: relative 1e-5 above that floor.
        let diff = (num - grad[i]).abs();
        assert!(
            diff <= 1e-8 + 1e-5 * num.abs().max(grad[i].abs()),
            "param {i}: analytic {} numeric {num}",
            grad[i]
        );
    }
}

fn spec() -> ModelSpec {
    ModelSpec {
        resdd: ResDdSpec {
            hidden: 7,
            modules: 2,
            variant: ResDdVariant::InputGated,
        },
        ln: LnSpec { hidden: [6, 5] },
        mlp: MlpSpec { hidden: [9, 6] },
        cnn: CnnSpec {
            features_per_channel: 8,
            filters: [4, 3],
            kernel: 3,
            dense: 6,
        },
    }
}

#[test]
fn resdd_gradients_all_depths_and_variants() {
    for variant in [ResDdVariant::InputGated, ResDdVariant::Chained] {
        for modules in 0..=3 {
            let mut sp = spec();
            sp.resdd.modules = modules;
            sp.resdd.variant = variant;
            // Larger input gain than training's init, so the multiplicative terms matter.
            let mut m = AnyModel::random(ModelKind::ResDd, &sp, 11, 5, 3).expect("model");
            for p in m.params_mut() {
                *p *= 2.0;
            }
            check(m, 100 + modules as u64);
        }
    }
}

#[test]
fn ln_gradients() {
    check(
        AnyModel::random(ModelKind::Ln, &spec(), 13, 5, 4).expect("model"),
        5,
    );
}

#[test]
fn mlp_gradients() {
    for seed in 0..3 {
        check(
            AnyModel::random(ModelKind::Mlp, &spec(), 13, 5, seed).expect("model"),
            10 + seed,
        );
    }
}

#[test]
fn cnn_gradients_even_and_odd_electrode_counts() {
    for (electrodes, kernel) in [(4, 3), (5, 3), (6, 5), (2, 1)] {
        let mut sp = spec();
        sp.cnn.kernel = kernel;
        for seed in 0..2 {
            let m = AnyModel::random(ModelKind::Cnn, &sp, 8 * electrodes, 5, seed).expect("model");
            check(m, 20 + seed);
        }
    }
}

#[test]
fn default_sized_models_gradients() {
    // The shapes the daemon runs (96 features, 5 fingers), strided over parameters.
    for kind in ModelKind::ALL {
        let m = AnyModel::random(kind, &ModelSpec::default(), 96, 5, 1).expect("model");
        check(m, 42);
    }
}

/// The effort-ray penalty's analytic gradient against central differences, for every kind:
/// a window of non-negative features, three fingers with a direction, jittered efforts, and a
/// slope margin high enough that most intervals are charged.
fn check_effort_penalty(mut m: AnyModel, seed: u64) {
    let mut g = Gen(seed);
    let x: Vec<f64> = (0..m.n_inputs()).map(|_| g.next().abs()).collect();
    let dirs: [f64; N_FINGERS] = [1.0, -1.0, 0.0, 1.0, 0.0];
    let cfg = EffortPenalty {
        points: 5,
        min_slope: 1.0,
        ..EffortPenalty::default()
    };
    let jitter: Vec<f64> = (0..cfg.points).map(|_| 0.5 * (g.next() + 1.0)).collect();
    let mut ks = vec![0.0; cfg.points + 2];
    cfg.efforts(&jitter, &mut ks);
    assert!(
        ks.windows(2).all(|w| w[0] < w[1]),
        "ascending efforts {ks:?}"
    );
    let mut work = RayWork::new(m.n_inputs(), ks.len());
    let mut s = m.new_scratch();
    let mut grad = vec![0.0; m.params().len()];
    let scale = 0.7;
    let p = ray_penalty(
        &m,
        &x,
        &dirs,
        &ks,
        cfg.min_slope,
        &mut work,
        &mut s,
        Some((&mut grad, scale)),
    );
    assert!(p > 0.0, "the margin charges some interval: {p}");
    let mut penalty =
        |m: &AnyModel| ray_penalty(m, &x, &dirs, &ks, cfg.min_slope, &mut work, &mut s, None);
    assert_eq!(
        penalty(&m),
        p,
        "with or without the gradient, the same penalty"
    );
    let n = m.params().len();
    let stride = (n / 500).max(1);
    for i in (0..n).step_by(stride) {
        let p0 = m.params()[i];
        let h = 1e-6 * (1.0 + p0.abs());
        m.params_mut()[i] = p0 + h;
        let lp = penalty(&m);
        m.params_mut()[i] = p0 - h;
        let lm = penalty(&m);
        m.params_mut()[i] = p0;
        let num = scale * (lp - lm) / (2.0 * h);
        let diff = (num - grad[i]).abs();
        assert!(
            diff <= 1e-7 + 1e-5 * num.abs().max(grad[i].abs()),
            "{} param {i}: analytic {} numeric {num}",
            m.kind(),
            grad[i]
        );
    }
}

#[test]
fn effort_penalty_gradients() {
    for kind in ModelKind::ALL {
        let mut m = AnyModel::random(kind, &spec(), 16, 5, 7).expect("model");
        // Larger ResDD weights so the multiplicative terms matter; non-zero biases so no ReLU
        // sits on its kink at k = 0 (where finite differences see a one-sided slope).
        let mut g = Gen(61);
        for p in m.params_mut() {
            *p = 2.0 * *p + 0.1 * g.next();
        }
        check_effort_penalty(m, 60);
    }
}

/// The batched passes training uses against the per-sample passes (whose gradients the tests
/// above check): outputs row by row and the gradient summed over the rows agree to round-off
/// (the matrix products sum in another order). Small and default shapes, every kind, ResDD at
/// every depth and both variants, a batch of one and a ragged batch.
fn check_batch(m: &AnyModel, rows: usize, seed: u64) {
    let mut g = Gen(seed);
    let (n_in, n_out) = (m.n_inputs(), m.n_outputs());
    let x: Vec<f64> = (0..rows * n_in).map(|_| g.next()).collect();
    let dy: Vec<f64> = (0..rows * n_out).map(|_| g.next()).collect();
    let mut work = m.new_batch_work(rows);
    let mut y = vec![f64::NAN; rows * n_out];
    m.forward_batch(&x, &mut y, &mut work);
    let mut grad = vec![0.0; m.params().len()];
    m.backward_batch(&x, &dy, &mut work, &mut grad);
    let (mut s, mut want_grad) = (m.new_scratch(), vec![0.0; m.params().len()]);
    let mut yi = vec![0.0; n_out];
    for r in 0..rows {
        let xr = &x[r * n_in..(r + 1) * n_in];
        m.predict_with(xr, &mut yi, &mut s);
        for (a, b) in y[r * n_out..(r + 1) * n_out].iter().zip(&yi) {
            assert!(
                (a - b).abs() <= 1e-12 * (1.0 + b.abs()),
                "{} row {r}: {a} vs {b}",
                m.kind()
            );
        }
        m.backward(xr, &dy[r * n_out..(r + 1) * n_out], &mut s, &mut want_grad);
    }
    let scale = want_grad.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    for (i, (a, b)) in grad.iter().zip(&want_grad).enumerate() {
        assert!(
            (a - b).abs() <= 1e-12 * scale,
            "{} grad {i}: {a} vs {b}",
            m.kind()
        );
    }
}

#[test]
fn batched_passes_equal_per_sample_passes() {
    for variant in [ResDdVariant::InputGated, ResDdVariant::Chained] {
        for modules in 0..=2 {
            let mut sp = spec();
            sp.resdd.modules = modules;
            sp.resdd.variant = variant;
            let m = AnyModel::random(ModelKind::ResDd, &sp, 11, 5, 3).expect("model");
            check_batch(&m, 7, 200 + modules as u64);
        }
    }
    for kind in ModelKind::ALL {
        let m = AnyModel::random(kind, &spec(), 16, 5, 2).expect("model");
        check_batch(&m, 1, 300);
        check_batch(&m, 9, 301);
        let m = AnyModel::random(kind, &ModelSpec::default(), 96, 5, 1).expect("model");
        check_batch(&m, 32, 302);
    }
    // An odd electrode count (the pool drops the last) and a wider kernel.
    let mut sp = spec();
    sp.cnn.kernel = 5;
    let m = AnyModel::random(ModelKind::Cnn, &sp, 40, 5, 3).expect("model");
    check_batch(&m, 6, 303);
}
