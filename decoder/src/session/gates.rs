//! Quality gates run before training: every trial must be usable, or the technician is told
//! which trial to redo and why.
//!
//! * **Saturated channel**: more than `saturation_fraction` of a trial's raw samples on a channel
//!   reach the front end's full scale (only when the session states its full scale).
//! * **Flat channel** (lead-off, broken wire): the raw signal does not move at all, or its
//!   windowed RMS is below `flat_ratio` times the median channel of the same trial.
//! * **Noisy electrode**: a channel's rest level (mean windowed RMS over the rest trials) is
//!   above `noisy_ratio` times the median of the other channels' rest levels: a loose or
//!   badly seated electrode picks up noise; reported once per channel, on the first rest trial.
//! * **Too little contrast**: a flexion or extension trial's mean RMS (over channels and
//!   windows) is below `min_contrast` times the mean of the rest trials.
//! * **Weak repetition**: a trial's mean RMS is below `min_repeat_ratio` times the strongest
//!   repetition of the same finger and kind.
//! * **Too few windows**: a trial gives fewer than [`MIN_WINDOWS_PER_TRIAL`] feature windows.
//! * **Patterns and directions** (the channel profile of each movement, not only its amplitude):
//!   repetitions of one movement that do not share a pattern, a finger whose flexion and
//!   extension look the same or swapped against the other movements, and a finger moved in one
//!   direction only; see [`super::patterns`].

use super::error::SessionError;
use super::patterns::{pattern_gates, PatternFigures, PatternInput};
use super::trial::{Trial, TrialKind};
use super::windows::WindowOptions;
use super::Session;
use crate::dsp::FEATURES_PER_CHANNEL;

/// Thresholds of the gates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GateConfig {
    /// Fraction of samples at full scale above which a channel counts as saturated.
    pub saturation_fraction: f64,
    /// A channel whose RMS is below this fraction of the trial's median channel is flat.
    pub flat_ratio: f64,
    /// A channel whose rest RMS is above this multiple of the other channels' median is noisy.
    pub noisy_ratio: f64,
    /// Minimum ratio of a contraction's mean RMS to rest's.
    pub min_contrast: f64,
    /// Minimum ratio of a trial's mean RMS to its strongest repetition's.
    pub min_repeat_ratio: f64,
    /// Minimum Pearson r of a repetition's channel profile against the mean of the other
    /// repetitions of the same movement.
    pub min_pattern_similarity: f64,
    /// Maximum Pearson r of a finger's mean flexion profile against its mean extension profile.
    pub max_flex_ext_similarity: f64,
}

/// Fewest feature windows a trial must give. The gates and the training average a trial over
/// its windows: one window (200 ms) is a single burst of motor-unit activity, whose RMS varies
/// by tens of percent from one window to the next, and a trial that short is a mis-timed cue
/// rather than a hold. Five windows at the 50 ms hop span 400 ms of hold, enough to average
/// that out; the shortest hold anywhere in the stack (the simulator's quick protocol, 0.5 s)
/// gives 7, `handctl calibrate`'s shortest (1 s) gives 17 and a 3DC recording about 85.
pub const MIN_WINDOWS_PER_TRIAL: usize = 5;

/// Default of [`GateConfig::min_pattern_similarity`]. Measured (Pearson r of a repetition against
/// the mean of the others): the six 3DC sessions 0.69 (P4 train, a varying power grip) to 1.00,
/// the simulator's sessions 1.00; a repetition of the opposite movement scores about the
/// session's flexion-extension r (-0.56 to 0.32 on five 3DC sessions, -0.29 in the simulator).
/// 0.5 keeps 0.19 below the lowest honest figure and still catches the opposite movement
/// wherever flexion and extension differ (not on P4 train, whose two grips correlate at 0.87).
pub const MIN_PATTERN_SIMILARITY: f64 = 0.5;

/// Default of [`GateConfig::max_flex_ext_similarity`]. Measured (mean flexion against mean
/// extension profile): the six 3DC sessions -0.56 to 0.87 (P4 train), the simulator's -0.99 to
/// -0.28. The same movement at both cues: 1.00 with the flexions' samples copied over the
/// extensions' (3DC and simulator); a patient's real second attempt at one movement would score
/// like one mean of repetitions against another, not measured here (single repetitions against
/// the mean of the others: 0.94 to 1.00 but for 0.69 and 0.72). 0.95 lies between the honest
/// 0.87 and those; a patient as variable as P4's power grip could slip under it.
pub const MAX_FLEX_EXT_SIMILARITY: f64 = 0.95;

impl Default for GateConfig {
    fn default() -> Self {
        Self {
            saturation_fraction: 0.01,
            flat_ratio: 0.02,
            noisy_ratio: 5.0,
            min_contrast: 1.5,
            min_repeat_ratio: 0.5,
            min_pattern_similarity: MIN_PATTERN_SIMILARITY,
            max_flex_ext_similarity: MAX_FLEX_EXT_SIMILARITY,
        }
    }
}

/// Which gate fired.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GateKind {
    /// A channel sits at full scale.
    Saturated {
        /// Channel index.
        channel: usize,
    },
    /// A channel does not move (lead-off).
    Flat {
        /// Channel index.
        channel: usize,
    },
    /// A channel is much noisier than the others at rest (a badly seated electrode).
    Noisy {
        /// Channel index.
        channel: usize,
    },
    /// The trial is hardly stronger than rest.
    LowContrast,
    /// The trial is much weaker than another repetition of it.
    WeakRepetition,
    /// The trial yields no window at all.
    NoWindows,
    /// The trial yields fewer than [`MIN_WINDOWS_PER_TRIAL`] windows.
    FewWindows {
        /// The windows it gave.
        windows: usize,
    },
    /// The trial's channel pattern is unlike the other repetitions of its movement.
    InconsistentPattern,
    /// A finger's (or the whole hand's, `None`) flexion and extension show the same pattern.
    FlexionLikeExtension {
        /// The finger, `None` for the whole hand.
        finger: Option<usize>,
    },
    /// A finger's flexion and extension look swapped against the other movements.
    SwappedDirections {
        /// The finger, `None` for the whole hand.
        finger: Option<usize>,
    },
    /// The session moves a finger in one direction only: it would be trained with one anchor.
    /// Not overridden by `--ignore-gates`.
    OneDirection {
        /// The finger.
        finger: usize,
        /// The kind the session lacks for it.
        missing: TrialKind,
    },
}

impl GateKind {
    /// False for problems no `--ignore-gates` may override: a finger moved in one direction only
    /// is never trained.
    pub fn can_be_ignored(&self) -> bool {
        !matches!(self, GateKind::OneDirection { .. })
    }
}

/// One problem found.
#[derive(Debug, Clone, PartialEq)]
pub struct GateIssue {
    /// The trial to redo.
    pub trial_id: u32,
    /// Which gate.
    pub kind: GateKind,
    /// What to tell the technician: the trial, the problem and what to do.
    pub message: String,
}

/// The outcome of all gates.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct GateReport {
    /// Problems, in trial order.
    pub issues: Vec<GateIssue>,
    /// Gates that could not run and why (e.g. no rest trial to compare against).
    pub notes: Vec<String>,
    /// What the pattern gates measured, per finger (and the whole hand).
    pub patterns: Vec<PatternFigures>,
}

impl GateReport {
    /// True when no gate fired.
    pub fn passed(&self) -> bool {
        self.issues.is_empty()
    }

    /// The issues that `--ignore-gates` may not override (see [`GateKind::can_be_ignored`]).
    pub fn binding(&self) -> impl Iterator<Item = &GateIssue> {
        self.issues.iter().filter(|i| !i.kind.can_be_ignored())
    }
}

impl std::fmt::Display for GateReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        for i in &self.issues {
            writeln!(f, "REDO {}", i.message)?;
        }
        for n in &self.notes {
            writeln!(f, "note: {n}")?;
        }
        for p in &self.patterns {
            writeln!(f, "{p}")?;
        }
        if self.passed() {
            writeln!(f, "all quality gates passed")?;
        }
        Ok(())
    }
}

/// The noisy-electrode rule on per-channel levels (µV or any common unit): channel `channel`
/// is noisy when its level is above `ratio` times the median of the *other* channels' levels
/// (the upper median for an even count). Returns that median when the channel is noisy, `None`
/// when it is not or when there are fewer than two channels. The calibration gate applies it to
/// the rest trials' levels; `handctl monitor` to the deployed model's rest levels, or to the
/// live levels when those are unknown.
pub fn noisy_against_others(levels: &[f64], channel: usize, ratio: f64) -> Option<f64> {
    let own = *levels.get(channel)?;
    let mut others: Vec<f64> = levels
        .iter()
        .enumerate()
        .filter(|&(o, _)| o != channel)
        .map(|(_, &l)| l)
        .collect();
    if others.is_empty() {
        return None;
    }
    others.sort_by(f64::total_cmp);
    let median = others[others.len() / 2];
    (own > ratio * median).then_some(median)
}

/// The rest level per channel: the mean windowed RMS over every window of the rest trials
/// (`rms[trial][channel]` is a trial's mean windowed RMS, `count[trial]` its windows); `None`
/// without a rest window.
fn rest_level(rms: &[Vec<f64>], count: &[usize], trials: &[Trial]) -> Option<Vec<f64>> {
    let rest: Vec<usize> = (0..trials.len())
        .filter(|&i| trials[i].kind == TrialKind::Rest && count[i] > 0)
        .collect();
    let ch = rms.first().map(Vec::len)?;
    let windows: usize = rest.iter().map(|&i| count[i]).sum();
    (windows > 0).then(|| {
        (0..ch)
            .map(|c| {
                rest.iter()
                    .map(|&i| rms[i][c] * count[i] as f64)
                    .sum::<f64>()
                    / windows as f64
            })
            .collect()
    })
}

/// The noisy-electrode gate on the rest level per channel, reported on the first rest trial.
fn noisy_at_rest(
    level: Option<&[f64]>,
    trials: &[Trial],
    count: &[usize],
    config: &GateConfig,
    report: &mut GateReport,
) {
    let first = (0..trials.len()).find(|&i| trials[i].kind == TrialKind::Rest && count[i] > 0);
    let (Some(first), Some(level)) = (first, level) else {
        return;
    };
    if level.len() < 2 {
        return;
    }
    for (c, &own) in level.iter().enumerate() {
        if let Some(median) = noisy_against_others(level, c, config.noisy_ratio) {
            report.issues.push(GateIssue {
                trial_id: trials[first].id,
                kind: GateKind::Noisy { channel: c },
                message: format!(
                    "{}: channel {c} is noisy at rest (RMS {own:.3}, {:.1}x the median of the \
                     other channels, {median:.3}; limit {}x): re-seat that electrode (clean \
                     skin, firm contact), then record the calibration again",
                    trials[first],
                    own / median,
                    config.noisy_ratio
                ),
            });
        }
    }
}

/// Runs every gate over a session.
pub fn check_gates(session: &Session, config: &GateConfig) -> Result<GateReport, SessionError> {
    let windows = session.windows(&WindowOptions::default())?;
    let trials = &session.meta.trials;
    let mut report = GateReport::default();
    let chain = &session.meta.chain;
    let (rms, count) = trial_rms(&windows, session.recording.channels, trials.len());
    let strength: Vec<f64> = rms
        .iter()
        .map(|r| r.iter().sum::<f64>() / r.len().max(1) as f64)
        .collect();
    for (ti, t) in trials.iter().enumerate() {
        if count[ti] == 0 {
            report.issues.push(GateIssue {
                trial_id: t.id,
                kind: GateKind::NoWindows,
                message: no_windows_message(session, t),
            });
            continue;
        }
        if count[ti] < MIN_WINDOWS_PER_TRIAL {
            report.issues.push(GateIssue {
                trial_id: t.id,
                kind: GateKind::FewWindows { windows: count[ti] },
                message: format!(
                    "{t}: only {} feature window(s) ({:.2} s long; a trial needs at least \
                     {MIN_WINDOWS_PER_TRIAL}, {} ms of hold at the {} ms window and {} ms \
                     step{}); record it again, holding the contraction longer",
                    count[ti],
                    t.end_us.saturating_sub(t.start_us) as f64 * 1e-6,
                    chain.window_ms + chain.step_ms * (MIN_WINDOWS_PER_TRIAL - 1) as f64,
                    chain.window_ms,
                    chain.step_ms,
                    if session.meta.onset_skip_ms > 0.0 {
                        format!(", after the {} ms onset skip", session.meta.onset_skip_ms)
                    } else {
                        String::new()
                    }
                ),
            });
        }
        channel_gates(session, config, t, &rms[ti], &mut report);
    }
    let usable: Vec<bool> = count.iter().map(|&n| n >= MIN_WINDOWS_PER_TRIAL).collect();
    let rest = rest_level(&rms, &count, trials);
    noisy_at_rest(rest.as_deref(), trials, &count, config, &mut report);
    contrast_gate(trials, &strength, &count, config, &mut report);
    repeat_gate(trials, &strength, &count, config, &mut report);
    let input = PatternInput {
        trials,
        rms: &rms,
        usable: &usable,
        rest: rest.as_deref(),
    };
    pattern_gates(&input, config, &mut report);
    report.issues.sort_by_key(|i| i.trial_id);
    Ok(report)
}

/// Why a trial gave no window: what the recording holds between its start and end.
fn no_windows_message(session: &Session, t: &super::Trial) -> String {
    let r = &session.recording;
    let range = r.range_of(t.start_us, t.end_us);
    let breaks = r
        .breaks
        .iter()
        .filter(|&&b| b > range.start && b < range.end)
        .count();
    let window_ms = session.meta.chain.window_ms;
    format!(
        "{t}: too short to give a single feature window ({:.2} s long, {} EMG samples in it, \
         {breaks} break(s) in the EMG stream; a window needs {window_ms} ms of unbroken \
         samples{}); record it again, longer",
        t.end_us.saturating_sub(t.start_us) as f64 * 1e-6,
        range.len(),
        if session.meta.onset_skip_ms > 0.0 {
            format!(" after the {} ms onset skip", session.meta.onset_skip_ms)
        } else {
            String::new()
        }
    )
}

/// Per trial, per channel: the mean windowed RMS; and each trial's window count.
fn trial_rms(
    windows: &super::windows::LabelledWindows,
    ch: usize,
    n_trials: usize,
) -> (Vec<Vec<f64>>, Vec<usize>) {
    let mut rms = vec![vec![0.0; ch]; n_trials];
    let mut count = vec![0usize; n_trials];
    for (i, l) in windows.labels.iter().enumerate() {
        let row = windows.row(i);
        for (c, r) in rms[l.trial].iter_mut().enumerate() {
            *r += row[c * FEATURES_PER_CHANNEL];
        }
        count[l.trial] += 1;
    }
    for (r, &n) in rms.iter_mut().zip(&count) {
        if n > 0 {
            r.iter_mut().for_each(|v| *v /= n as f64);
        }
    }
    (rms, count)
}

/// The saturation and flat-channel gates of one trial (`rms`: its channels' mean RMS).
fn channel_gates(
    session: &Session,
    config: &GateConfig,
    t: &Trial,
    rms: &[f64],
    report: &mut GateReport,
) {
    let ch = rms.len();
    let range = session.recording.range_of(t.start_us, t.end_us);
    let raw = session.recording.slice(range.clone());
    let n = range.len().max(1);
    let mut median = rms.to_vec();
    median.sort_by(f64::total_cmp);
    let median = median[ch / 2];
    for (c, &chan_rms) in rms.iter().enumerate() {
        let column = raw.iter().skip(c).step_by(ch);
        let (lo, hi) = column
            .clone()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
                (lo.min(v), hi.max(v))
            });
        if let Some(fs) = session.meta.recording.full_scale {
            let rail = fs * session.recording.unit_per_raw;
            let at_rail = column.filter(|v| v.abs() >= rail).count();
            let frac = at_rail as f64 / n as f64;
            if frac > config.saturation_fraction {
                report.issues.push(GateIssue {
                    trial_id: t.id,
                    kind: GateKind::Saturated { channel: c },
                    message: format!(
                        "{t}: channel {c} is saturated in {:.1}% of samples (full scale {fs}); \
                         lower the gain or check the electrode, then record the trial again",
                        100.0 * frac
                    ),
                });
                continue;
            }
        }
        if hi <= lo || chan_rms < config.flat_ratio * median {
            report.issues.push(GateIssue {
                trial_id: t.id,
                kind: GateKind::Flat { channel: c },
                message: format!(
                    "{t}: channel {c} is flat (RMS {:.3} against a median channel of {:.3}): \
                     electrode off or lead broken; fix the electrode, then record the trial again",
                    chan_rms, median
                ),
            });
        }
    }
}

/// Contrast against rest: each contraction's mean RMS against the rest trials'.
fn contrast_gate(
    trials: &[Trial],
    strength: &[f64],
    count: &[usize],
    config: &GateConfig,
    report: &mut GateReport,
) {
    let rest: Vec<usize> = (0..trials.len())
        .filter(|&i| trials[i].kind == TrialKind::Rest && count[i] > 0)
        .collect();
    if rest.is_empty() {
        report
            .notes
            .push("no rest trial: the contrast gate did not run".into());
        return;
    }
    let rest_strength = rest.iter().map(|&i| strength[i]).sum::<f64>() / rest.len() as f64;
    for (ti, t) in trials.iter().enumerate() {
        if t.kind == TrialKind::Rest || count[ti] == 0 {
            continue;
        }
        let ratio = strength[ti] / rest_strength;
        if ratio.is_nan() || ratio < config.min_contrast {
            report.issues.push(GateIssue {
                trial_id: t.id,
                kind: GateKind::LowContrast,
                message: format!(
                    "{t}: only {ratio:.2}x the RMS of rest (needs {:.2}x): \
                     record it again with a maximal contraction",
                    config.min_contrast
                ),
            });
        }
    }
}

/// Repeatability within (finger, kind): each trial against its strongest other repetition.
fn repeat_gate(
    trials: &[Trial],
    strength: &[f64],
    count: &[usize],
    config: &GateConfig,
    report: &mut GateReport,
) {
    for (ti, t) in trials.iter().enumerate() {
        if t.kind == TrialKind::Rest || count[ti] == 0 {
            continue;
        }
        let best = (0..trials.len())
            .filter(|&j| j != ti && count[j] > 0)
            .filter(|&j| trials[j].kind == t.kind && trials[j].finger == t.finger)
            .max_by(|&a, &b| strength[a].total_cmp(&strength[b]));
        if let Some(j) = best {
            let ratio = strength[ti] / strength[j];
            if ratio < config.min_repeat_ratio {
                report.issues.push(GateIssue {
                    trial_id: t.id,
                    kind: GateKind::WeakRepetition,
                    message: format!(
                        "{t}: only {ratio:.2}x the RMS of {} (needs {:.2}x): \
                         record it again with the same maximal effort",
                        trials[j], config.min_repeat_ratio
                    ),
                });
            }
        }
    }
}
