//! ResDD against values computed independently (numpy, in the issue): one input-gated module
//! applied straight to X (identity input projection).

use decoder::model::{Model, ResDd, ResDdSpec, ResDdVariant};

#[test]
fn one_module_matches_numpy_values() {
    let spec = ResDdSpec {
        hidden: 3,
        modules: 1,
        variant: ResDdVariant::InputGated,
    };
    let w_in = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0];
    let w1 = [0.1, 0.2, -0.3, 0.0, 0.5, 0.4, -0.2, 0.1, 0.3];
    let w2 = [0.3, -0.6, 0.9, 1.0, 0.2, -0.4];
    let params: Vec<f64> = w_in.iter().chain(&w1).chain(&w2).copied().collect();
    let m = ResDd::from_params(spec, 3, 2, params).expect("valid shapes");
    let x = [1.0, 0.5, -0.25];
    let mut y = [0.0; 2];
    let mut s = m.new_scratch();
    m.predict_with(&x, &mut y, &mut s);
    let want_y = [-0.121875, 0.6625];
    for (a, b) in y.iter().zip(want_y) {
        assert!((a - b).abs() <= 1e-12, "Y = {y:?}, want {want_y:?}");
    }
    let act = m.activations(&s);
    let checks: [(&str, &[f64], [f64; 3]); 3] = [
        ("X", act.x(), x),
        ("G", act.g(1), [0.275, 0.15, -0.225]),
        ("A1", act.a(1), [0.55, 0.225, -0.16875]),
    ];
    for (name, got, want) in checks {
        for (a, b) in got.iter().zip(want) {
            assert!((a - b).abs() <= 1e-12, "{name} = {got:?}, want {want:?}");
        }
    }
}

#[test]
fn zero_input_gives_zero_output_for_bias_free_models() {
    use decoder::model::{AnyModel, ModelKind, ModelSpec};
    for kind in [ModelKind::ResDd, ModelKind::Ln] {
        let m = AnyModel::random(kind, &ModelSpec::default(), 96, 5, 7).expect("model");
        let mut y = [1.0; 5];
        m.predict(&[0.0; 96], &mut y);
        assert_eq!(y, [0.0; 5], "{kind}");
    }
}
