//! A bias-free polynomial model (ResDD, LN) along an effort ray, as one polynomial in `k` per
//! output: the normalized input is `k·a + k²·b` (`a` the amplitude features, `b` the VAR
//! features, both at full effort), and every layer maps polynomials to polynomials.

use super::error::VerifyError;
use super::poly::PolyVec;
use crate::dsp::{FEATURES_PER_CHANNEL, FEATURE_NAMES};
use crate::model::{AnyModel, Model, ModelKind, ResDdVariant, Trainable, TrainedModel};

/// Highest output degree handled (a chained ResDD doubles it per module).
pub const MAX_DEGREE: usize = 64;

/// Position of VAR, the one power-like feature, among a channel's features.
pub fn var_index() -> usize {
    FEATURE_NAMES
        .iter()
        .position(|n| *n == "VAR")
        .expect("VAR is one of the chain's features")
}

/// The degree of the output polynomials of a ResDD or LN; `None` for other kinds.
pub fn output_degree(model: &AnyModel) -> Option<usize> {
    match model {
        AnyModel::ResDd(m) => {
            let modules = m.spec().modules;
            Some(match m.spec().variant {
                ResDdVariant::InputGated => 2 * (modules + 1),
                ResDdVariant::Chained => 2usize.saturating_pow(modules as u32 + 1),
            })
        }
        AnyModel::Dense(m) if m.kind() == ModelKind::Ln => Some(2),
        _ => None,
    }
}

/// Checks that the model's outputs along a ray are polynomials this module can handle.
pub fn check_polynomial(model: &TrainedModel) -> Result<usize, VerifyError> {
    let kind = model.model().kind();
    let degree = output_degree(model.model()).ok_or(VerifyError::NotPolynomial(kind))?;
    if degree > MAX_DEGREE {
        return Err(VerifyError::DegreeTooHigh {
            degree,
            max: MAX_DEGREE,
        });
    }
    Ok(degree)
}

/// The normalized input along the ray through `features` (full effort), as polynomials.
fn input_ray(model: &TrainedModel, features: &[f64]) -> PolyVec {
    let var = var_index();
    let n = features.len();
    let mut coefs = vec![vec![0.0; n]; 3];
    for (j, (f, s)) in features.iter().zip(model.normalizer().scales()).enumerate() {
        let d = if j % FEATURES_PER_CHANNEL == var {
            2
        } else {
            1
        };
        coefs[d][j] = f * s;
    }
    PolyVec { coefs }
}

/// The named weight tensor of `m` and its row count.
fn tensor<'m>(m: &'m dyn Trainable, name: &str) -> (&'m [f64], usize) {
    let t = m
        .tensors()
        .into_iter()
        .find(|t| t.name == name)
        .unwrap_or_else(|| panic!("the model has no tensor {name}"));
    (&m.params()[t.offset..t.offset + t.len()], t.shape[0])
}

/// One polynomial (power basis in `k`) per output along the ray through `features`. The model
/// must have passed [`check_polynomial`]; `features` has the model's input length.
pub fn ray_polynomials(model: &TrainedModel, features: &[f64]) -> Vec<Vec<f64>> {
    let x = input_ray(model, features);
    let out = match model.model() {
        AnyModel::ResDd(m) => {
            let (w_in, h) = tensor(m, "w_in");
            let xh = x.mat_mul(w_in, h);
            let mut a = xh.clone();
            for l in 1..=m.spec().modules {
                let (w, _) = tensor(m, &format!("w_mod.{l}"));
                let g = a.mat_mul(w, h);
                a = match m.spec().variant {
                    ResDdVariant::InputGated => PolyVec::gated(&g, &xh),
                    ResDdVariant::Chained => PolyVec::gated(&g, &a),
                };
            }
            let (w_out, n_out) = tensor(m, "w_out");
            a.mat_mul(w_out, n_out)
        }
        AnyModel::Dense(m) => ["w1", "w2", "w3"].iter().fold(x, |v, name| {
            let (w, rows) = tensor(m, name);
            v.mat_mul(w, rows)
        }),
        AnyModel::Cnn(_) => unreachable!("check_polynomial rejects CNNs"),
    };
    (0..out.len()).map(|i| out.entry(i)).collect()
}
