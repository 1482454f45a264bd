//! The check of one trial right after its RELAX: the session's own quality gates
//! ([`decoder::session::check_gates`]) on the log recorded so far, with the trials kept so far
//! that the gates compare against (the rest trials, the other repetitions of the same finger
//! and kind) and the new attempt. Only the issues of the new attempt count: saturation, a flat
//! channel (lead-off), a noisy channel (on the rest trial), too little contrast against rest,
//! and a repetition much weaker than the strongest of its kind.
//!
//! Calibration is stricter than `handctl check` on one point: a repetition under
//! [`MIN_REPEAT_RATIO`] of the strongest one is redone (`handctl check` allows 0.5). The cue
//! asks for a maximal contraction every time; with the sEMG amplitude near-linear in effort
//! (slightly convex), a half-effort contraction gives about 0.45 of the maximal RMS, which the
//! 0.5 threshold would let through on a noisy day, while honest maximal repetitions stay
//! within about 20 % of each other.

use std::path::Path;

use decoder::session::{check_gates, GateConfig, GateKind, Recording, Session, SessionMeta, Trial};

use super::error::CalibrateError;

/// A repetition weaker than this fraction of the strongest of its kind is redone.
pub const MIN_REPEAT_RATIO: f64 = 0.65;

/// The gates the calibration applies to each trial.
pub fn gate_config() -> GateConfig {
    GateConfig {
        min_repeat_ratio: MIN_REPEAT_RATIO,
        ..GateConfig::default()
    }
}

/// The outcome of one attempt's check.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Verdict {
    /// Why the attempt fails; empty when it passes.
    pub reasons: Vec<String>,
    /// Kept repetitions that this attempt shows much weaker than itself (their ids, and why):
    /// a weak first repetition is only seen when a stronger one follows.
    pub weaker_kept: Vec<(u32, String)>,
}

/// The check of `candidate`. `base` is the session's metadata (chain, recording) with the
/// trials kept so far; the log in `dir` must be flushed.
pub fn check_trial(
    dir: &Path,
    base: &SessionMeta,
    candidate: Trial,
) -> Result<Verdict, CalibrateError> {
    // A redone trial replaces its kept attempt, so that one is left out.
    let related = |t: &&Trial| {
        t.id != candidate.id
            && (t.kind == decoder::session::TrialKind::Rest
                || (t.kind == candidate.kind && t.finger == candidate.finger))
    };
    let mut meta = base.clone();
    meta.trials = base.trials.iter().filter(related).copied().collect();
    meta.trials.push(candidate);
    let recording = Recording::load(&meta, dir)?;
    let session = Session::from_parts(dir.to_path_buf(), meta, recording)?;
    let report = check_gates(&session, &gate_config())?;
    let mut v = Verdict::default();
    for i in report.issues {
        if i.trial_id == candidate.id {
            v.reasons.push(i.message);
        } else if i.kind == GateKind::WeakRepetition {
            v.weaker_kept.push((i.trial_id, i.message));
        }
    }
    Ok(v)
}
