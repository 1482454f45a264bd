//! Why a verification could not run.

use thiserror::Error;

/// A verification's inputs do not fit together.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum VerifyError {
    /// Exact verification asked of a model that is not polynomial along a ray.
    #[error("a {0} model is not a polynomial in the effort: only ResDD and LN verify exactly")]
    NotPolynomial(crate::model::ModelKind),
    /// The output polynomials would be of too high a degree (a chained ResDD with many modules).
    #[error("the outputs are polynomials of degree {degree}, above the {max} handled")]
    DegreeTooHigh {
        /// Degree of the outputs.
        degree: usize,
        /// Largest handled.
        max: usize,
    },
    /// The windows do not have the model's feature count.
    #[error("the windows have {found} features, the model expects {expected}")]
    Features {
        /// Model inputs.
        expected: usize,
        /// Window features.
        found: usize,
    },
    /// A window names a trial the session does not have.
    #[error("window {window} belongs to trial index {trial}, the session has {trials} trials")]
    Trial {
        /// Window index.
        window: usize,
        /// Its trial index.
        trial: usize,
        /// Trials in the session.
        trials: usize,
    },
    /// A largest effort below 1 or not finite.
    #[error("largest effort {0} must be finite and >= 1")]
    Effort(f64),
    /// A tolerance that is negative or not finite.
    #[error("tolerance {0} must be finite and >= 0")]
    Tolerance(f64),
}
