//! The pattern gates: amplitude alone cannot tell a flexion from an extension, so these look at
//! *where* on the forearm a movement shows (its channel profile) and at which directions the
//! session asks for.
//!
//! A trial's **channel profile** is its per-channel mean windowed RMS, less the session's rest
//! level per channel when it has rest trials (so a channel that is merely noisy does not count
//! as active). Profiles are compared with Pearson's r across channels: centring removes the
//! common part (every channel rises a little in any contraction), so r measures the shape of the
//! pattern and not its size; it needs at least [`MIN_PATTERN_CHANNELS`] channels.
//!
//! * **Inconsistent pattern**: each repetition of one movement (finger and kind) against the
//!   mean profile of its other repetitions; r below `min_pattern_similarity` means the patient
//!   made another movement at that cue (e.g. extended once at a flexion cue).
//! * **Flexion like extension**: a finger's mean flexion profile against its mean extension
//!   profile; r above `max_flex_ext_similarity` means both cues got the same movement (a patient
//!   who extends at every flexion cue). The finger would be trained toward +1 and -1 on the same
//!   signal.
//! * **Swapped directions** (a cross-movement prior, only with at least
//!   [`MIN_REFERENCE_MOVEMENTS`] other movements that have both directions): a finger whose
//!   flexion looks more like the *other* movements' extension, and its extension more like their
//!   flexion, than the other way round (every finger's flexors share one side of the forearm and
//!   the extensors the other), by more than [`SWAP_MARGIN`]. It catches one finger swapped
//!   against the rest (this one prior is borne out by the simulator's layout only: the 3DC
//!   recordings have the whole hand alone and cannot test it); a patient who
//!   swaps every finger and the whole hand alike looks, to amplitude data, exactly like a correct
//!   session and passes: no gate here can see that, only a placement that says which electrodes
//!   sit over the flexors would.
//! * **One direction**: a finger that the session moves in one direction only (flexion without
//!   extension, or the reverse) would be trained with one anchor and could never be driven the
//!   other way; the session is refused for that finger, and `--ignore-gates` does not override it.

use super::gates::{GateConfig, GateIssue, GateKind, GateReport};
use super::trial::{Trial, TrialKind, FINGER_NAMES, N_FINGERS};

/// Fewest channels on which a channel profile has a shape: with two, Pearson's r is always ±1.
pub const MIN_PATTERN_CHANNELS: usize = 3;

/// Fewest other movements (fingers or the whole hand, each with both directions) the swapped
/// directions gate needs as its reference: with one, a swap of that one would look like a swap
/// of the finger checked.
pub const MIN_REFERENCE_MOVEMENTS: usize = 2;

/// A finger is refused as swapped when its swap score (see [`PatternFigures::swap_score`], in
/// -4..4) is below minus this. Measured in the simulator: correct fingers +0.93 (thumb and
/// pinky, the edges of the flexor group) to +3.9 (the whole hand); the index with its cues
/// swapped -2.24, and the thumb beside it, correct but with the swapped index in its reference,
/// -0.28. 1.0 refuses the first and not the second.
pub const SWAP_MARGIN: f64 = 1.0;

/// The pattern figures of one movement group (a finger, or the whole hand): what the gates
/// compared, for the report.
#[derive(Debug, Clone, PartialEq)]
pub struct PatternFigures {
    /// The finger, `None` for the whole hand.
    pub finger: Option<usize>,
    /// Per repetition: its trial id, kind and Pearson r against the mean profile of the other
    /// repetitions of the same kind (only kinds with two or more usable repetitions).
    pub repetitions: Vec<(u32, TrialKind, f64)>,
    /// Pearson r of the mean flexion profile against the mean extension profile.
    pub flexion_extension: Option<f64>,
    /// The swapped-directions score: r(flexion, others' flexion) + r(extension, others'
    /// extension) - r(flexion, others' extension) - r(extension, others' flexion). Below
    /// -[`SWAP_MARGIN`] the finger is refused as swapped against the other movements.
    pub swap_score: Option<f64>,
}

impl std::fmt::Display for PatternFigures {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "pattern {}:", finger_name(self.finger))?;
        for kind in [TrialKind::Flexion, TrialKind::Extension] {
            let rs: Vec<String> = self
                .repetitions
                .iter()
                .filter(|r| r.1 == kind)
                .map(|r| format!("{:.2}", r.2))
                .collect();
            if !rs.is_empty() {
                write!(f, " {} repetitions r = {};", kind.name(), rs.join(", "))?;
            }
        }
        if let Some(r) = self.flexion_extension {
            write!(f, " flexion vs extension r = {r:.2};")?;
        }
        if let Some(s) = self.swap_score {
            write!(f, " swap score {s:+.2}")?;
        }
        Ok(())
    }
}

fn finger_name(finger: Option<usize>) -> &'static str {
    match finger {
        None => "whole hand",
        Some(f) => FINGER_NAMES.get(f).copied().unwrap_or("?"),
    }
}

/// Pearson's r of two profiles across channels; `None` when either is flat (no shape).
pub fn pearson(a: &[f64], b: &[f64]) -> Option<f64> {
    let n = a.len();
    if n < MIN_PATTERN_CHANNELS || b.len() != n {
        return None;
    }
    let ma = a.iter().sum::<f64>() / n as f64;
    let mb = b.iter().sum::<f64>() / n as f64;
    let (mut ab, mut aa, mut bb) = (0.0, 0.0, 0.0);
    for (x, y) in a.iter().zip(b) {
        let (x, y) = (x - ma, y - mb);
        ab += x * y;
        aa += x * x;
        bb += y * y;
    }
    let norm = (aa * bb).sqrt();
    (norm > 1e-12 * (1.0 + ma.abs() * mb.abs()) && norm.is_finite()).then(|| ab / norm)
}

/// The mean of `profiles` (all the same length), each first scaled to unit length so that a
/// stronger repetition does not outweigh the others.
fn mean_shape<'a>(profiles: impl Iterator<Item = &'a [f64]>, ch: usize) -> Option<Vec<f64>> {
    let mut sum = vec![0.0; ch];
    let mut n = 0usize;
    for p in profiles {
        let norm = p.iter().map(|v| v * v).sum::<f64>().sqrt();
        if norm > 0.0 && norm.is_finite() {
            sum.iter_mut().zip(p).for_each(|(s, v)| *s += v / norm);
            n += 1;
        }
    }
    (n > 0).then(|| sum.into_iter().map(|s| s / n as f64).collect())
}

/// A movement group's mean flexion and extension shapes (each when it has usable trials).
type GroupShapes = (Option<usize>, Option<Vec<f64>>, Option<Vec<f64>>);

/// The inputs of the pattern gates: the session's trials, their per-channel mean RMS, which
/// trials have enough windows to be used, and the rest level per channel if there is one.
pub(super) struct PatternInput<'a> {
    pub trials: &'a [Trial],
    pub rms: &'a [Vec<f64>],
    pub usable: &'a [bool],
    pub rest: Option<&'a [f64]>,
}

/// Runs the pattern gates (see the module docs), adding issues, notes and figures to `report`.
pub(super) fn pattern_gates(
    input: &PatternInput<'_>,
    config: &GateConfig,
    report: &mut GateReport,
) {
    one_direction_gate(input.trials, report);
    let ch = input.rms.first().map_or(0, Vec::len);
    if ch < MIN_PATTERN_CHANNELS {
        report.notes.push(format!(
            "{ch} channel(s): the pattern gates need at least {MIN_PATTERN_CHANNELS} and did not run"
        ));
        return;
    }
    let profile: Vec<Vec<f64>> = input
        .rms
        .iter()
        .map(|r| match input.rest {
            Some(rest) => r.iter().zip(rest).map(|(v, r)| v - r).collect(),
            None => r.clone(),
        })
        .collect();
    let mut groups: Vec<Option<usize>> = Vec::new();
    for t in input.trials {
        if t.kind != TrialKind::Rest && !groups.contains(&t.finger) {
            groups.push(t.finger);
        }
    }
    let members = |g: Option<usize>, kind: TrialKind| -> Vec<usize> {
        (0..input.trials.len())
            .filter(|&i| {
                let t = &input.trials[i];
                input.usable[i] && t.finger == g && t.kind == kind
            })
            .collect()
    };
    let mut single: Vec<String> = Vec::new();
    let mut figures: Vec<PatternFigures> = Vec::new();
    // Mean shapes per group and kind, for the flexion-extension and swap gates.
    let mut shapes: Vec<GroupShapes> = Vec::new();
    for &g in &groups {
        let mut fig = PatternFigures {
            finger: g,
            repetitions: Vec::new(),
            flexion_extension: None,
            swap_score: None,
        };
        let mut kind_shape = [None, None];
        for (k, kind) in [TrialKind::Flexion, TrialKind::Extension]
            .into_iter()
            .enumerate()
        {
            let idx = members(g, kind);
            kind_shape[k] = mean_shape(idx.iter().map(|&i| profile[i].as_slice()), ch);
            if idx.len() == 1 {
                single.push(format!("{} {}", finger_name(g), kind.name()));
            }
            if idx.len() < 2 {
                continue;
            }
            for &i in &idx {
                let others = mean_shape(
                    idx.iter()
                        .filter(|&&j| j != i)
                        .map(|&j| profile[j].as_slice()),
                    ch,
                );
                let Some(r) = others.and_then(|o| pearson(&profile[i], &o)) else {
                    continue;
                };
                let t = &input.trials[i];
                fig.repetitions.push((t.id, kind, r));
                if r < config.min_pattern_similarity {
                    let names: Vec<String> = idx
                        .iter()
                        .filter(|&&j| j != i)
                        .map(|&j| input.trials[j].id.to_string())
                        .collect();
                    report.issues.push(GateIssue {
                        trial_id: t.id,
                        kind: GateKind::InconsistentPattern,
                        message: format!(
                            "{t}: its channel pattern is unlike the other repetitions' (trial(s) \
                             {}: r = {r:.2}, needs {:.2}): the patient made another movement at \
                             this cue (perhaps the other direction); show the movement again and \
                             record the trial again",
                            names.join(", "),
                            config.min_pattern_similarity
                        ),
                    });
                }
            }
        }
        let [flex, ext] = kind_shape;
        if let (Some(fl), Some(ex)) = (&flex, &ext) {
            fig.flexion_extension = pearson(fl, ex);
            if let Some(r) = fig.flexion_extension {
                if r > config.max_flex_ext_similarity {
                    let f_ids = ids(input, &members(g, TrialKind::Flexion));
                    let e_ids = ids(input, &members(g, TrialKind::Extension));
                    report.issues.push(GateIssue {
                        trial_id: input.trials[members(g, TrialKind::Flexion)[0]].id,
                        kind: GateKind::FlexionLikeExtension { finger: g },
                        message: format!(
                            "{}: flexion (trial(s) {f_ids}) and extension (trial(s) {e_ids}) \
                             show the same channel pattern (r = {r:.2}, limit {:.2}): the \
                             patient made the same movement at both cues (e.g. extended at the \
                             flexion cue); show both movements and record that finger's trials \
                             again",
                            finger_name(g),
                            config.max_flex_ext_similarity
                        ),
                    });
                }
            }
        }
        shapes.push((g, flex, ext));
        figures.push(fig);
    }
    swap_gate(input, &shapes, &mut figures, report);
    if !single.is_empty() {
        report.notes.push(format!(
            "a single usable repetition of {}: its pattern consistency was not checked",
            single.join(", ")
        ));
    }
    report.patterns = figures;
}

fn ids(input: &PatternInput<'_>, idx: &[usize]) -> String {
    idx.iter()
        .map(|&i| input.trials[i].id.to_string())
        .collect::<Vec<_>>()
        .join(", ")
}

/// The swapped-directions gate (see the module docs).
fn swap_gate(
    input: &PatternInput<'_>,
    shapes: &[GroupShapes],
    figures: &mut [PatternFigures],
    report: &mut GateReport,
) {
    let complete: Vec<(Option<usize>, &[f64], &[f64])> = shapes
        .iter()
        .filter_map(|(g, f, e)| Some((*g, f.as_deref()?, e.as_deref()?)))
        .collect();
    if complete.len() < MIN_REFERENCE_MOVEMENTS + 1 {
        return;
    }
    let ch = complete[0].1.len();
    for &(g, fl, ex) in &complete {
        let others = || complete.iter().filter(move |o| o.0 != g);
        let (Some(of), Some(oe)) = (
            mean_shape(others().map(|o| o.1), ch),
            mean_shape(others().map(|o| o.2), ch),
        ) else {
            continue;
        };
        let (Some(ff), Some(ee), Some(fe), Some(ef)) = (
            pearson(fl, &of),
            pearson(ex, &oe),
            pearson(fl, &oe),
            pearson(ex, &of),
        ) else {
            continue;
        };
        let score = ff + ee - fe - ef;
        if let Some(fig) = figures.iter_mut().find(|f| f.finger == g) {
            fig.swap_score = Some(score);
        }
        if score < -SWAP_MARGIN {
            let first = input
                .trials
                .iter()
                .find(|t| t.finger == g && t.kind == TrialKind::Flexion)
                .map_or(0, |t| t.id);
            report.issues.push(GateIssue {
                trial_id: first,
                kind: GateKind::SwappedDirections { finger: g },
                message: format!(
                    "{}: its flexion looks like the other movements' extension and its extension \
                     like their flexion (swap score {score:+.2}; r flexion/flexion {ff:.2}, \
                     extension/extension {ee:.2}, flexion/extension {fe:.2}, extension/flexion \
                     {ef:.2}): the patient likely swapped the two cues for this finger; show both \
                     movements and record that finger's trials again",
                    finger_name(g)
                ),
            });
        }
    }
}

/// The one-direction gate: per finger, a flexion without an extension (or the reverse), counting
/// whole-hand trials for every finger.
fn one_direction_gate(trials: &[Trial], report: &mut GateReport) {
    let mut unmoved: Vec<&str> = Vec::new();
    for (f, &name) in FINGER_NAMES.iter().enumerate().take(N_FINGERS) {
        let first = |kind: TrialKind| {
            trials
                .iter()
                .filter(|t| t.kind == kind && t.involved()[f])
                .min_by_key(|t| (t.finger.is_none(), t.id))
        };
        match (first(TrialKind::Flexion), first(TrialKind::Extension)) {
            (Some(_), Some(_)) => {}
            (None, None) => unmoved.push(name),
            (Some(t), None) | (None, Some(t)) => {
                let (has, lacks) = if t.kind == TrialKind::Flexion {
                    (TrialKind::Flexion, TrialKind::Extension)
                } else {
                    (TrialKind::Extension, TrialKind::Flexion)
                };
                report.issues.push(GateIssue {
                    trial_id: t.id,
                    kind: GateKind::OneDirection {
                        finger: f,
                        missing: lacks,
                    },
                    message: format!(
                        "{}: the session has {} trials for it (the first {t}) but no {} trial \
                         (of that finger or the whole hand): it would be trained with one anchor \
                         and never driven the other way; record its {} (a protocol needs both \
                         kinds), or leave the finger out of the session altogether. \
                         --ignore-gates does not override this",
                        name,
                        has.name(),
                        lacks.name(),
                        lacks.name()
                    ),
                });
            }
        }
    }
    if !unmoved.is_empty() && unmoved.len() < N_FINGERS {
        report.notes.push(format!(
            "no flexion or extension trial for {}: trained toward 0 only (it stays still)",
            unmoved.join(", ")
        ));
    }
}
