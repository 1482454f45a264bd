//! One model, checked once, evaluated along effort rays.

use super::error::VerifyError;
use super::poly::eval;
use super::propagate::{check_polynomial, ray_polynomials};
use super::reversal::{exact_reversal_through, largest_drop, Method, Reversal};
use crate::eval::scale_features;
use crate::model::{Envelope, Model, ModelKind, OutputStage, Predictor, TrainedModel, N_FINGERS};

/// Efforts sampled for a model that is not polynomial (MLP, CNN).
pub const SAMPLED_POINTS: usize = 1001;

/// A model's outputs along one ray.
#[derive(Debug, Clone, PartialEq)]
pub enum RayCurves {
    /// One polynomial in `k` per finger (power basis): the model's raw output, and the output
    /// stage the model applies to it (the curve is the stage of the polynomial).
    Polynomials(Vec<Vec<f64>>, OutputStage),
    /// Outputs at `k = i / (n - 1)`, `i = 0..n`.
    Sampled(Vec<[f64; N_FINGERS]>),
}

/// Verifies rays of one trained model: exactly for ResDD and LN, by [`SAMPLED_POINTS`] samples
/// otherwise.
#[derive(Debug, Clone)]
pub struct RayVerifier<'m> {
    model: &'m TrainedModel,
    method: Method,
    predictor: Predictor,
    scaled: Vec<f64>,
}

impl<'m> RayVerifier<'m> {
    /// Picks the method for `model`: exact when its outputs are polynomials of a handled degree.
    pub fn new(model: &'m TrainedModel) -> Self {
        let method = match check_polynomial(model) {
            Ok(_) => Method::Exact,
            Err(_) => Method::Sampled(SAMPLED_POINTS),
        };
        Self::with_method(model, method)
    }

    /// Exact verification, or why it is impossible for this model.
    pub fn exact(model: &'m TrainedModel) -> Result<Self, VerifyError> {
        check_polynomial(model)?;
        Ok(Self::with_method(model, Method::Exact))
    }

    fn with_method(model: &'m TrainedModel, method: Method) -> Self {
        RayVerifier {
            model,
            method,
            predictor: model.predictor(),
            scaled: vec![0.0; model.normalizer().len()],
        }
    }

    /// How reversals are found.
    pub fn method(&self) -> Method {
        self.method
    }

    /// The model's kind.
    pub fn kind(&self) -> ModelKind {
        self.model.model().kind()
    }

    /// Features per window expected.
    pub fn n_inputs(&self) -> usize {
        self.model.model().n_inputs()
    }

    /// The model's outputs along the ray through `features` (full effort). Panics if
    /// `features` does not have [`RayVerifier::n_inputs`] values.
    pub fn curves(&mut self, features: &[f64]) -> RayCurves {
        assert_eq!(features.len(), self.n_inputs(), "ray feature count");
        match self.method {
            Method::Exact => RayCurves::Polynomials(
                ray_polynomials(self.model, features),
                self.model.output_stage(),
            ),
            Method::Sampled(n) => RayCurves::Sampled(
                (0..n)
                    .map(|i| self.output_at(features, i as f64 / (n - 1) as f64))
                    .collect(),
            ),
        }
    }

    /// The envelope the model holds its inputs inside (None: an older file).
    pub fn envelope(&self) -> Option<&'m Envelope> {
        self.model.envelope()
    }

    /// For an exact method, each finger's raw output polynomial along the ray through
    /// `features` and the output stage applied to it (None when sampled).
    pub(super) fn polynomials(&self, features: &[f64]) -> Option<(Vec<Vec<f64>>, OutputStage)> {
        (self.method == Method::Exact).then(|| {
            (
                ray_polynomials(self.model, features),
                self.model.output_stage(),
            )
        })
    }

    /// Whether the predictor finds the window at effort `k` on the ray through `features`
    /// implausible (it then outputs rest).
    pub fn implausible_at(&mut self, features: &[f64], k: f64) -> bool {
        self.output_at(features, k);
        self.predictor.last_implausible()
    }

    /// The model's real forward pass at effort `k` on the ray through `features`.
    pub fn output_at(&mut self, features: &[f64], k: f64) -> [f64; N_FINGERS] {
        scale_features(features, k, &mut self.scaled);
        self.predictor.run(&self.scaled)
    }
}

impl RayCurves {
    /// The worst reversal of `finger`'s output against `dir` (+1 flexion, -1 extension).
    pub fn reversal(&self, finger: usize, dir: f64) -> Reversal {
        match self {
            RayCurves::Polynomials(p, st) => exact_reversal_through(
                &p[finger],
                dir,
                &|v| st.map(finger, v),
                st.max_slope(finger),
            ),
            RayCurves::Sampled(ys) => {
                let last = (ys.len().max(2) - 1) as f64;
                let points: Vec<(f64, f64)> = ys
                    .iter()
                    .enumerate()
                    .map(|(i, y)| (i as f64 / last, y[finger]))
                    .collect();
                largest_drop(&points, dir, Method::Sampled(ys.len()))
            }
        }
    }

    /// `finger`'s output at effort `k` (polynomials only; sampled curves give the nearest
    /// sample).
    pub fn value(&self, finger: usize, k: f64) -> f64 {
        match self {
            RayCurves::Polynomials(p, st) => st.map(finger, eval(&p[finger], k)),
            RayCurves::Sampled(ys) => {
                let i = (k.clamp(0.0, 1.0) * (ys.len() - 1) as f64).round() as usize;
                ys[i][finger]
            }
        }
    }
}
