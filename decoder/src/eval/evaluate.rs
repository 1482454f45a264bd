//! Scoring trained models on a session's held-out windows: direction (Table 3), interpolation
//! (Table 4) and the output at rest.

use super::direction::{direction_metrics, DirectionMetrics};
use super::error::EvalError;
use super::interpolation::{
    interpolation_curves, InterpolationConfig, InterpolationCurve, InterpolationInput,
    InterpolationSummary,
};
use crate::model::{ModelKind, TrainedModel, N_FINGERS};
use crate::session::LabelledWindows;

/// Everything measured for one model on one set of test windows.
#[derive(Debug, Clone)]
pub struct ModelEvaluation {
    /// Which model.
    pub kind: ModelKind,
    /// Per finger: direction figures over the windows whose trial moved that finger (`None`
    /// when the test set lacks flexion or extension windows for it).
    pub direction: [Option<DirectionMetrics>; N_FINGERS],
    /// Every interpolation curve (one per flexion/extension window and involved finger).
    pub curves: Vec<InterpolationCurve>,
    /// Per finger interpolation summary.
    pub interpolation: [InterpolationSummary; N_FINGERS],
    /// All fingers' curves together.
    pub interpolation_total: InterpolationSummary,
    /// Mean |output| over rest windows and fingers (`None` without rest windows): how far rest
    /// drifts from zero.
    pub rest_mean_abs: Option<f64>,
    /// The effort levels of the curves.
    pub levels: Vec<f64>,
}

/// Scores `model` on `test` windows.
pub fn evaluate_model(
    model: &TrainedModel,
    test: &LabelledWindows,
    config: &InterpolationConfig,
) -> Result<ModelEvaluation, EvalError> {
    if test.n_features != model.normalizer().len() {
        return Err(EvalError::Shape(format!(
            "the test windows have {} features, the model expects {}",
            test.n_features,
            model.normalizer().len()
        )));
    }
    let mut pred = model.predictor();
    let outputs: Vec<[f64; N_FINGERS]> = (0..test.len()).map(|i| pred.run(test.row(i))).collect();
    if let Some(i) = outputs
        .iter()
        .position(|y| y.iter().any(|v| !v.is_finite()))
    {
        return Err(EvalError::NonFinite {
            what: "model output on a test window",
            index: i,
        });
    }

    let mut direction: [Option<DirectionMetrics>; N_FINGERS] = Default::default();
    let mut inputs = Vec::new();
    for (f, slot) in direction.iter_mut().enumerate() {
        let mut scores = Vec::new();
        let mut positive = Vec::new();
        for (i, l) in test.labels.iter().enumerate() {
            if l.mask[f] && l.targets[f] != 0.0 {
                scores.push(outputs[i][f]);
                positive.push(l.targets[f] > 0.0);
                inputs.push(InterpolationInput {
                    features: test.row(i),
                    finger: f,
                    sign: l.targets[f].signum(),
                });
            }
        }
        *slot = match direction_metrics(&scores, &positive) {
            Ok(m) => Some(m),
            Err(EvalError::NotEnoughData(_)) => None,
            Err(e) => return Err(e),
        };
    }
    let curves = interpolation_curves(&inputs, N_FINGERS, config, &mut |x, y| {
        y.copy_from_slice(&pred.run(x));
    })?;
    let interpolation: [InterpolationSummary; N_FINGERS] =
        std::array::from_fn(|f| InterpolationSummary::of(curves.iter().filter(|c| c.finger == f)));
    let interpolation_total = InterpolationSummary::of(&curves);
    let (mut rest_sum, mut rest_n) = (0.0, 0usize);
    for (i, l) in test.labels.iter().enumerate() {
        if l.targets.iter().all(|&t| t == 0.0) && l.mask.iter().all(|&m| m) {
            rest_sum += outputs[i].iter().map(|v| v.abs()).sum::<f64>();
            rest_n += N_FINGERS;
        }
    }
    Ok(ModelEvaluation {
        kind: model.summary().kind,
        direction,
        curves,
        interpolation,
        interpolation_total,
        rest_mean_abs: (rest_n > 0).then(|| rest_sum / rest_n as f64),
        levels: config.levels()?,
    })
}
