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

use std::path::PathBuf;

use decoder::session::{
    check_gates, GateConfig, GateKind, Recording, Segment, Session, SessionMeta, Trial,
};

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

/// Filter warm-up before each trial in the check's recording, µs (the band-pass and notch
/// settle well within it).
pub const WARMUP_US: u64 = 1_000_000;

/// The check of `candidate` on `recording` (the EMG of this run, in memory). `base` is the
/// session's metadata (chain, recording) with the trials kept so far. Only the stretches of
/// the trials compared are checked, each from [`WARMUP_US`] before it as a segment of its
/// own, so a check costs the same at the end of a long calibration as at its start.
pub fn check_trial(
    recording: &Recording,
    base: &SessionMeta,
    candidate: Trial,
) -> Result<Verdict, CalibrateError> {
    // A redone trial replaces its kept attempt, so that one is left out; a trial older than
    // the recording (none: a resumed run starts from the old log) could not be compared.
    let first = recording.time_us.first().copied().unwrap_or(u64::MAX);
    let related = |t: &&Trial| {
        t.id != candidate.id
            && t.start_us >= first
            && (t.kind == decoder::session::TrialKind::Rest
                || (t.kind == candidate.kind && t.finger == candidate.finger))
    };
    let mut meta = base.clone();
    meta.trials = base.trials.iter().filter(related).copied().collect();
    meta.trials.push(candidate);
    let (segments, part) = stretches(recording, &meta.trials);
    meta.segments = segments;
    let session = Session::from_parts(PathBuf::from("(this calibration)"), meta, part)?;
    let report = check_gates(&session, &gate_config())?;
    let mut v = Verdict::default();
    for i in report.issues {
        // The session so far holds this movement's kind alone: that a finger lacks the other
        // direction is the whole session's matter, checked after the last trial.
        if matches!(i.kind, GateKind::OneDirection { .. }) {
            continue;
        }
        if i.trial_id == candidate.id {
            v.reasons.push(i.message);
        } else if i.kind == GateKind::WeakRepetition {
            v.weaker_kept.push((i.trial_id, i.message));
        }
    }
    Ok(v)
}

/// The stretches of `r` holding `trials` (each from [`WARMUP_US`] before it, overlapping
/// ones merged) as segments, and a recording of those samples alone.
pub(super) fn stretches(r: &Recording, trials: &[Trial]) -> (Vec<Segment>, Recording) {
    let mut spans: Vec<(u64, u64)> = trials
        .iter()
        .map(|t| (t.start_us.saturating_sub(WARMUP_US), t.end_us))
        .collect();
    spans.sort_unstable();
    let mut merged: Vec<Segment> = Vec::new();
    for (s, e) in spans {
        match merged.last_mut() {
            Some(m) if s <= m.end_us => m.end_us = m.end_us.max(e),
            _ => merged.push(Segment {
                start_us: s,
                end_us: e,
            }),
        }
    }
    let mut part = Recording {
        channels: r.channels,
        samples: Vec::new(),
        time_us: Vec::new(),
        lost_samples: r.lost_samples,
        breaks: Vec::new(),
        bad_frames: r.bad_frames,
        unit_per_raw: r.unit_per_raw,
    };
    for seg in &merged {
        let range = r.range_of(seg.start_us, seg.end_us);
        let base = part.time_us.len();
        part.breaks.extend(
            r.breaks
                .iter()
                .filter(|&&b| b > range.start && b < range.end)
                .map(|&b| b - range.start + base),
        );
        part.samples.extend_from_slice(r.slice(range.clone()));
        part.time_us.extend_from_slice(&r.time_us[range]);
    }
    (merged, part)
}
