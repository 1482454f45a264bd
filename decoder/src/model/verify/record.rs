//! The verification as a model file records it: [`VerificationRecord`]. Written by
//! `handctl train` after it verified every calibration ray, shown by `handctl status` and
//! `handctl eval --model`; a file without one (written before verification existed) is "NOT
//! verified".

use std::fmt;

use serde::{Deserialize, Serialize};

use super::report::VerifyReport;
use super::reversal::Method;
use crate::model::N_FINGERS;
use crate::session::FINGER_NAMES;

/// The worst ray of a verification.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct WorstRay {
    /// The trial as the calibration session named it, e.g. "trial 3 (index flexion,
    /// repetition 1)".
    pub trial: String,
    /// Finger index, 0 thumb .. 4 pinky.
    pub finger: usize,
    /// The reversal, label units (0 when the finger never goes back).
    pub amount: f64,
    /// Effort where the reversal starts.
    pub from_k: f64,
    /// Effort where it ends.
    pub to_k: f64,
}

/// What verifying a model on its calibration session found, as stored in the model file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct VerificationRecord {
    /// Exact (ResDD, LN) or sampled (MLP, CNN: a lower bound, not a proof).
    pub method: Method,
    /// Reversals up to this (label units) were accepted.
    pub tolerance: f64,
    /// Rays checked (flexion and extension windows x the fingers each moves).
    pub rays: usize,
    /// Rays reversing beyond the tolerance.
    pub reversing: usize,
    /// The worst ray (None when no ray was checked).
    pub worst: Option<WorstRay>,
    /// The model reverses beyond the tolerance and was written anyway (`handctl train
    /// --force`). A model that passed is never forced.
    pub forced: bool,
}

impl VerificationRecord {
    /// The record of `report`; `forced` only counts for a model that does not pass.
    pub fn from_report(report: &VerifyReport, forced: bool) -> Self {
        VerificationRecord {
            method: report.method,
            tolerance: report.tolerance,
            rays: report.rays(),
            reversing: report.reversing(),
            worst: report.worst().map(|e| WorstRay {
                trial: e.trial.clone(),
                finger: e.finger,
                amount: e.worst.amount,
                from_k: e.worst.from_k,
                to_k: e.worst.to_k,
            }),
            forced: forced && !report.passed(),
        }
    }

    /// True when no ray reverses beyond the tolerance.
    pub fn passed(&self) -> bool {
        self.reversing == 0
    }

    /// Checks a record read from a file: what is wrong with it, if anything.
    pub fn check(&self) -> Result<(), String> {
        let unit = |v: f64| v.is_finite() && (0.0..=1.0).contains(&v);
        if !(self.tolerance.is_finite() && self.tolerance >= 0.0) {
            return Err(format!(
                "tolerance {} is not finite and >= 0",
                self.tolerance
            ));
        }
        if self.reversing > self.rays {
            return Err(format!(
                "{} reversing rays of {} checked",
                self.reversing, self.rays
            ));
        }
        if self.forced && self.passed() {
            return Err("forced, yet no ray reverses".into());
        }
        if let Method::Sampled(n) = self.method {
            if n < 2 {
                return Err(format!("sampled at {n} efforts"));
            }
        }
        match &self.worst {
            None if self.rays > 0 => Err(format!("{} rays but no worst ray", self.rays)),
            Some(w) if w.finger >= N_FINGERS => Err(format!("worst ray's finger {}", w.finger)),
            Some(w) if !(w.amount.is_finite() && w.amount >= 0.0) => {
                Err(format!("worst reversal {}", w.amount))
            }
            Some(w) if !(unit(w.from_k) && unit(w.to_k)) => Err(format!(
                "worst reversal's efforts {} to {} outside [0, 1]",
                w.from_k, w.to_k
            )),
            _ => Ok(()),
        }
    }

    /// The method in a few words: "exact" or "sampled at N efforts, not a proof".
    pub fn method_words(&self) -> String {
        match self.method {
            Method::Exact => "exact".into(),
            Method::Sampled(n) => format!("sampled at {n} efforts, not a proof"),
        }
    }
}

/// One line: "verified: 0 of 3375 rays reverse beyond 0.01 (exact)", "FORCED: 12 of 3375 rays
/// reverse beyond 0.01 (exact); worst ...", or "REVERSES: ..." for a reversing model saved
/// without `--force` (by a program, not `handctl train`).
impl fmt::Display for VerificationRecord {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let head = match (self.passed(), self.forced) {
            (true, _) => "verified",
            (false, true) => "FORCED",
            (false, false) => "REVERSES",
        };
        write!(
            f,
            "{head}: {} of {} rays reverse beyond {} ({})",
            self.reversing,
            self.rays,
            self.tolerance,
            self.method_words()
        )?;
        if let Some(w) = self.worst.as_ref().filter(|_| !self.passed()) {
            write!(f, "; worst {w}")?;
        }
        Ok(())
    }
}

impl fmt::Display for WorstRay {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} in {} by {:.4} (effort {:.3} to {:.3})",
            FINGER_NAMES.get(self.finger).copied().unwrap_or("?"),
            self.trial,
            self.amount,
            self.from_k,
            self.to_k
        )
    }
}

/// The verification line of a model file that may have no record.
pub fn describe_verification(record: Option<&VerificationRecord>) -> String {
    match record {
        Some(r) => r.to_string(),
        None => "NOT verified (the model file records no verification)".into(),
    }
}
