//! Offline evaluation as in the paper: direction AUC with the Hanley-McNeil standard error and
//! sign accuracy (Table 3), the interpolation analysis (Table 4), tracking metrics (RMSE, MAPE,
//! R²), decoding a recording and its agreement with a reference signal, text tables, the curves as CSV and (with the `plots` feature) PNG figures.
//!
//! The metric functions take plain slices and a prediction closure, so they know nothing of
//! how a model was built; [`evaluate_model`] ties them to trained models and calibration sessions.

mod agreement;
mod csv;
mod decode;
mod direction;
mod error;
mod evaluate;
mod interpolation;
#[cfg(feature = "plots")]
mod plot;
mod stats;
mod stress;
mod table;
mod tracking;

pub use agreement::{agreement, Agreement};
pub use csv::{interpolation_csv, roc_csv, write_csv};
pub use decode::{decode, Decoded};
pub use direction::{
    auc, direction_metrics, hanley_mcneil_se, roc_curve, sign_accuracy, DirectionMetrics, RocPoint,
};
pub use error::EvalError;
pub use evaluate::{evaluate_model, ModelEvaluation};
pub use interpolation::{
    interpolation_curves, judge_curve, scale_features, InterpolationConfig, InterpolationCurve,
    InterpolationInput, InterpolationSummary, VAR_INDEX,
};
#[cfg(feature = "plots")]
pub use plot::{interpolation_png, roc_png};
pub use stats::{average_ranks, linear_fit, pearson, spearman, LinearFit};
pub use stress::{
    stress, stress_table, stress_transients, StressReport, StressRow, STRESS_GAINS, TRANSIENT_GAIN,
    TRANSIENT_MS, WRONG_WAY,
};
pub use table::{direction_table, interpolation_table};
pub use tracking::{tracking_metrics, TrackingMetrics, MAPE_MIN_TARGET};
