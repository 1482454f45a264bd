//! Exact monotonicity of a decoder along effort rays (issue 12).
//!
//! An effort ray scales a calibration window's signal by `k` in `[0, 1]`: the amplitude
//! features scale by `k`, VAR by `k²`, the normalizer is scale-only and ResDD and LN are
//! bias-free polynomial maps, so each finger's output is a polynomial in `k`
//! (`propagate.rs` builds it layer by layer in `f64`). Its largest reversal against the
//! trial's direction, `max dir·(y(k1) - y(k2))` over `k1 < k2`, is read at its critical points,
//! the real roots of `y'` in `[0, 1]`, found by Bernstein subdivision (see `roots.rs`: a
//! root-free interval is proven root-free, never assumed). The models have no output clamp or
//! squashing; a model with an output stage ([`crate::model::OutputStage`]: rest stage and untaught
//! directions held at 0, non-decreasing) is
//! read through it at the same critical points. MLP and CNN (ReLU) are checked by sampling
//! [`SAMPLED_POINTS`] efforts and say so. A model file keeps the outcome as a
//! [`VerificationRecord`]. Beyond full effort, [`verify_beyond`] checks the rays out to
//! [`BEYOND_EFFORT`] through the calibration envelope's clipping (`beyond.rs`).

mod beyond;
mod error;
mod poly;
mod propagate;
mod ray;
mod record;
mod report;
mod reversal;
mod roots;

pub use beyond::{verify_beyond, BeyondEntry, BeyondReport, BEYOND_EFFORT};
pub use error::VerifyError;
pub use poly::eval as eval_polynomial;
pub use propagate::{output_degree, var_index, MAX_DEGREE};
pub use ray::{RayCurves, RayVerifier, SAMPLED_POINTS};
pub use record::{describe_verification, VerificationRecord, WorstRay};
pub use report::{verify_windows, TrialFinger, VerifyReport, DEFAULT_TOLERANCE};
pub use reversal::{exact_reversal, exact_reversal_through, largest_drop, Method, Reversal};
pub use roots::{roots_in_unit, Roots, SLOPE_FLOOR, WIDTH_FLOOR};
