//! Beyond full effort (issue 25 item 3): every calibration ray for efforts `k` in
//! `[0, BEYOND_EFFORT]`, not only `[0, 1]`.
//!
//! Along the ray through a window `x`, the predictor first holds its input inside the
//! calibration's envelope ([`crate::model::Envelope::project`]): the window at effort `k` is
//! scaled back by `s(k) = min(1, k_e / k)`, where `k_e` is the ray's edge (the largest effort at
//! which every feature is inside the envelope), so the model sees the ray at `min(k, k_e)`. So:
//! - on `[0, min(k_e, K)]` the output is the polynomial of the ray, analysed exactly (its
//!   critical points, through the output stage) on that interval, rescaled to `[0, 1]`;
//! - beyond `k_e` the output is held at its value at `k_e`. The edge is read from the same
//!   [`crate::model::Envelope::scale_of`] the predictor runs (`k_e = K · s(K)`), and the hold is
//!   checked on the predictor itself at `k_e`, halfway and at the end: a ray on which the
//!   predictor's output differs from the polynomial's at `k_e` is counted as `not_held` (a
//!   failure: the proof would not describe the deployed path);
//! - a window whose shape the calibration never saw (one channel standing alone, far above the
//!   next, or channel powers off the calibration's patterns:
//!   [`crate::model::Envelope::implausible`]) outputs rest. Along a ray the channels' ratios
//!   are fixed (and a pattern's misfit does not change with its scale), so a ray turns
//!   implausible only where its top channel passes the floor, at some `k_r`, and stays so
//!   beyond: the output drops to 0, towards rest, not the
//!   wrong way. Those rays are counted (`resting`), and the drop is not a reversal; `k_r` is
//!   found by bisection on the predictor. (A calibration window standing alone itself would
//!   turn implausible before its edge; none does on P4, P6 and P7, where the top channel is
//!   at most 1.79x the next; and none is off the patterns: the bar is above the worst of the
//!   calibration's own windows.)
//!
//! A model without an envelope (an older file) is analysed on the whole `[0, K]`. MLP and CNN
//! are sampled at [`super::SAMPLED_POINTS`] efforts over the same interval.
//!
//! Per ray and finger: the worst reversal against the trial's direction, and the overshoot, how
//! far `dir·y` rises above the trial's full-effort value for that finger: the larger of full
//! scale (1) and the largest `dir·y(1)` of the trial's windows (what the calibration's own
//! strongest window gave), both against the tolerance.
//!
//! Both judge the label the hand gets: the output stage, then [`hand_label`] (clamped to full
//! scale, as the daemon's conditioner clamps it; the same function). An output that rises above
//! full scale and comes back to it is no reversal the hand can show, and the label never rises
//! above full scale: the overshoot count guards that the clamp is on the path (a path without
//! it would show the raw outputs' overshoot, up to 1.2 on the 3DC participants). On `[0, 1]`
//! ([`super::verify_windows`]) the raw output stays the judge: the training's own property.

use std::fmt;

use super::error::VerifyError;
use super::poly::{derivative, eval};
use super::ray::RayVerifier;
use super::reversal::{exact_reversal_through, largest_drop, Method, Reversal};
use super::roots::roots_in_unit;
use crate::eval::scale_features;
use crate::model::{hand_label, OutputStage, N_FINGERS};
use crate::session::{LabelledWindows, Trial, FINGER_NAMES};

/// The largest effort checked: ten times the calibration window's.
pub const BEYOND_EFFORT: f64 = 10.0;

/// Bisection steps finding where a ray turns implausible (interval `K / 2^40`).
const BISECT_STEPS: usize = 40;

/// The rays of one trial for one finger, on `[0, K]`.
#[derive(Debug, Clone, PartialEq)]
pub struct BeyondEntry {
    /// The trial as the session names it.
    pub trial: String,
    /// Finger index, 0 thumb .. 4 pinky.
    pub finger: usize,
    /// Rays checked.
    pub rays: usize,
    /// Rays whose worst reversal on `[0, K]` exceeds the tolerance.
    pub reversing: usize,
    /// Of those, the rays that do not reverse beyond the tolerance on `[0, 1]`.
    pub reversing_beyond_only: usize,
    /// The worst reversal (efforts in the ray's own units, `0..K`).
    pub worst: Reversal,
    /// Rays whose output rises above the trial's full-effort value by more than the tolerance.
    pub overshooting: usize,
    /// The largest overshoot, label units.
    pub worst_overshoot: f64,
    /// Rays that turn implausible (rest) before `K`.
    pub resting: usize,
    /// Rays on which the predictor does not hold the edge's output beyond it (must be 0).
    pub not_held: usize,
    /// The smallest edge `k_e` among the rays (`K` or more: never clipped before `K`).
    pub lowest_edge: f64,
    /// The trial's full-effort value for the finger: `max(1, largest dir·y(1))`.
    pub full_effort: f64,
}

/// The check of one model on `[0, K]` along every calibration ray.
#[derive(Debug, Clone, PartialEq)]
pub struct BeyondReport {
    /// Exact or sampled.
    pub method: Method,
    /// Reversals and overshoots up to this are accepted (label units).
    pub tolerance: f64,
    /// The largest effort checked.
    pub k_max: f64,
    /// Whether the model holds its inputs inside an envelope.
    pub has_envelope: bool,
    /// Per trial and finger, in trial order.
    pub entries: Vec<BeyondEntry>,
}

impl BeyondReport {
    fn sum(&self, f: impl Fn(&BeyondEntry) -> usize) -> usize {
        self.entries.iter().map(f).sum()
    }
    /// Rays checked.
    pub fn rays(&self) -> usize {
        self.sum(|e| e.rays)
    }
    /// Rays reversing beyond the tolerance somewhere on `[0, K]`.
    pub fn reversing(&self) -> usize {
        self.sum(|e| e.reversing)
    }
    /// Rays reversing beyond the tolerance only beyond full effort.
    pub fn reversing_beyond_only(&self) -> usize {
        self.sum(|e| e.reversing_beyond_only)
    }
    /// Rays overshooting.
    pub fn overshooting(&self) -> usize {
        self.sum(|e| e.overshooting)
    }
    /// Rays turning to rest (implausible) before `K`.
    pub fn resting(&self) -> usize {
        self.sum(|e| e.resting)
    }
    /// Rays where the predictor does not hold the edge's output.
    pub fn not_held(&self) -> usize {
        self.sum(|e| e.not_held)
    }
    /// The worst reversal, if any ray was checked.
    pub fn worst(&self) -> Option<&BeyondEntry> {
        self.entries.iter().reduce(|a, b| {
            if b.worst.amount.total_cmp(&a.worst.amount).is_gt() {
                b
            } else {
                a
            }
        })
    }
    /// No reversal, no overshoot, and the hold confirmed on every ray.
    pub fn passed(&self) -> bool {
        self.reversing() == 0 && self.overshooting() == 0 && self.not_held() == 0
    }
}

/// One ray's outcome for one finger.
struct RayOutcome {
    reversal: Reversal,
    reversal_unit: f64,
    /// Largest `dir·y` on `[0, K]`.
    peak: f64,
    /// `dir·y(1)`.
    full: f64,
}

/// Checks every flexion and extension window's ray on `[0, k_max]` for every finger its trial
/// moves (as [`super::verify_windows`] does on `[0, 1]`).
pub fn verify_beyond(
    verifier: &mut RayVerifier<'_>,
    windows: &LabelledWindows,
    trials: &[Trial],
    tolerance: f64,
    k_max: f64,
) -> Result<BeyondReport, VerifyError> {
    super::report::check_inputs(verifier, windows, trials, tolerance)?;
    if !(k_max.is_finite() && k_max >= 1.0) {
        return Err(VerifyError::Effort(k_max));
    }
    let mut entries: Vec<BeyondEntry> = Vec::new();
    let mut scaled = vec![0.0; verifier.n_inputs()];
    // (entry, peak) per ray and finger: the overshoot needs every ray's full effort first.
    let mut peaks: Vec<(usize, f64)> = Vec::new();
    for (i, label) in windows.labels.iter().enumerate() {
        let fingers: Vec<usize> = (0..N_FINGERS)
            .filter(|&f| label.mask[f] && label.targets[f] != 0.0)
            .collect();
        if fingers.is_empty() {
            continue;
        }
        let row = windows.row(i);
        let edge = match verifier.envelope() {
            Some(e) => {
                scale_features(row, k_max, &mut scaled);
                k_max * e.scale_of(&scaled)
            }
            None => k_max,
        };
        let rest_from = resting_from(verifier, row, edge.min(k_max), k_max);
        let end = edge.min(k_max);
        let polys = verifier.polynomials(row);
        let held = held_outputs(
            verifier,
            row,
            &polys,
            edge,
            rest_from.unwrap_or(k_max),
            k_max,
        );
        let name = trials[label.trial].to_string();
        for f in fingers {
            let dir = label.targets[f].signum();
            let o = ray_outcome(verifier, row, &polys, f, dir, end);
            let held_ok = held.iter().all(|(y, want)| close(y[f], want[f]));
            let at = entry_at(&mut entries, &name, f, verifier.method());
            entries[at].count(&o, tolerance, rest_from.is_some(), held_ok, edge);
            peaks.push((at, o.peak));
        }
    }
    for (at, peak) in peaks {
        let e = &mut entries[at];
        let over = (peak - e.full_effort).max(0.0);
        e.overshooting += usize::from(over > tolerance);
        e.worst_overshoot = e.worst_overshoot.max(over);
    }
    Ok(BeyondReport {
        method: verifier.method(),
        tolerance,
        k_max,
        has_envelope: verifier.envelope().is_some(),
        entries,
    })
}

/// The index of the entry of `trial` and `finger` in `entries`, added when missing.
fn entry_at(entries: &mut Vec<BeyondEntry>, trial: &str, finger: usize, method: Method) -> usize {
    match entries
        .iter()
        .position(|e| e.trial == trial && e.finger == finger)
    {
        Some(at) => at,
        None => {
            entries.push(BeyondEntry::new(trial.to_string(), finger, method));
            entries.len() - 1
        }
    }
}

/// Two outputs of the same computation, up to rounding of the projection.
fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-9 * b.abs().max(1.0)
}

/// Where the ray through `row` turns implausible (rest), if it does before `k_max`: the
/// predictor's own check, bisected between `lo` (plausible: inside the envelope) and `k_max`.
fn resting_from(v: &mut RayVerifier<'_>, row: &[f64], lo: f64, k_max: f64) -> Option<f64> {
    if !v.implausible_at(row, k_max) {
        return None;
    }
    let (mut a, mut b) = (lo, k_max);
    for _ in 0..BISECT_STEPS {
        let m = 0.5 * (a + b);
        if v.implausible_at(row, m) {
            b = m;
        } else {
            a = m;
        }
    }
    Some(b)
}

/// Beyond the edge (when it is before `k_max`), the predictor's outputs at the edge, halfway to
/// `until` (where the ray turns to rest, or `k_max`) and just before `until`, each with the
/// outputs the analysis assumes there: the polynomial's value at the edge (sampled: the
/// predictor's at the edge).
fn held_outputs(
    v: &mut RayVerifier<'_>,
    row: &[f64],
    polys: &Option<(Vec<Vec<f64>>, OutputStage)>,
    edge: f64,
    until: f64,
    k_max: f64,
) -> Vec<([f64; N_FINGERS], [f64; N_FINGERS])> {
    if edge >= k_max {
        return Vec::new();
    }
    let want: [f64; N_FINGERS] = match polys {
        Some((p, stage)) => std::array::from_fn(|f| stage.map(f, eval(&p[f], edge))),
        None => v.output_at(row, edge),
    };
    let last = edge + (until - edge) * (1.0 - 1e-9);
    [edge, 0.5 * (edge + until), last]
        .into_iter()
        .map(|k| (v.output_at(row, k), want))
        .collect()
}

/// The reversal and overshoot of `finger` on `[0, end]`: exact on the polynomial (rescaled to
/// `[0, 1]`) through the output stage, or sampled.
fn ray_outcome(
    v: &mut RayVerifier<'_>,
    row: &[f64],
    polys: &Option<(Vec<Vec<f64>>, OutputStage)>,
    f: usize,
    dir: f64,
    end: f64,
) -> RayOutcome {
    match polys {
        Some((p, stage)) => exact_outcome(&p[f], stage, f, dir, end),
        None => sampled_outcome(v, row, f, dir, end),
    }
}

/// [`ray_outcome`] on the ray's polynomial `p`, through the output stage and the hand's clamp.
fn exact_outcome(p: &[f64], stage: &OutputStage, f: usize, dir: f64, end: f64) -> RayOutcome {
    // q(t) = p(end·t), t in [0, 1].
    let mut s = 1.0;
    let q: Vec<f64> = p
        .iter()
        .map(|c| {
            let v = c * s;
            s *= end;
            v
        })
        .collect();
    let g = |y: f64| hand_label(stage.map(f, y));
    let mut r = exact_reversal_through(&q, dir, &g, stage.max_slope(f));
    r.from_k *= end;
    r.to_k *= end;
    let unit = exact_reversal_through(p, dir, &g, stage.max_slope(f)).amount;
    let roots = roots_in_unit(&derivative(&q));
    let peak = roots
        .points
        .iter()
        .chain(&[0.0, 1.0])
        .map(|&t| dir * g(eval(&q, t)))
        .fold(f64::NEG_INFINITY, f64::max);
    RayOutcome {
        reversal: r,
        reversal_unit: unit,
        peak,
        full: dir * g(eval(p, end.min(1.0))),
    }
}

/// [`ray_outcome`] sampled on the predictor at [`super::SAMPLED_POINTS`] efforts.
fn sampled_outcome(
    v: &mut RayVerifier<'_>,
    row: &[f64],
    f: usize,
    dir: f64,
    end: f64,
) -> RayOutcome {
    let n = super::SAMPLED_POINTS;
    let points: Vec<(f64, f64)> = (0..n)
        .map(|i| {
            let k = end * i as f64 / (n - 1) as f64;
            (k, hand_label(v.output_at(row, k)[f]))
        })
        .collect();
    let unit: Vec<(f64, f64)> = points.iter().copied().filter(|p| p.0 <= 1.0).collect();
    let peak = points
        .iter()
        .map(|p| dir * p.1)
        .fold(f64::NEG_INFINITY, f64::max);
    RayOutcome {
        reversal: largest_drop(&points, dir, Method::Sampled(n)),
        reversal_unit: largest_drop(&unit, dir, Method::Sampled(n)).amount,
        peak,
        full: dir * hand_label(v.output_at(row, end.min(1.0))[f]),
    }
}

impl BeyondEntry {
    /// Counts one ray's outcome (its overshoot is counted once every ray's full effort is
    /// known).
    fn count(&mut self, o: &RayOutcome, tolerance: f64, resting: bool, held: bool, edge: f64) {
        self.rays += 1;
        let rev = o.reversal.amount > tolerance;
        self.reversing += usize::from(rev);
        self.reversing_beyond_only += usize::from(rev && o.reversal_unit <= tolerance);
        if o.reversal.amount > self.worst.amount || self.rays == 1 {
            self.worst = o.reversal;
        }
        self.full_effort = self.full_effort.max(o.full);
        self.resting += usize::from(resting);
        self.not_held += usize::from(!held);
        self.lowest_edge = self.lowest_edge.min(edge);
    }

    fn new(trial: String, finger: usize, method: Method) -> Self {
        BeyondEntry {
            trial,
            finger,
            rays: 0,
            reversing: 0,
            reversing_beyond_only: 0,
            worst: Reversal::none(method),
            overshooting: 0,
            worst_overshoot: 0.0,
            resting: 0,
            not_held: 0,
            lowest_edge: f64::INFINITY,
            full_effort: 1.0,
        }
    }
}

impl fmt::Display for BeyondReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "beyond full effort, efforts 0 to {}: {}; {}",
            self.k_max,
            self.method,
            if self.has_envelope {
                "inputs held at the calibration's edge (envelope), checked on the predictor"
            } else {
                "NO envelope (older file): the raw model on the whole range"
            }
        )?;
        for e in self
            .entries
            .iter()
            .filter(|e| e.reversing > 0 || e.overshooting > 0 || e.not_held > 0)
        {
            writeln!(
                f,
                "  BEYOND {} {}: {} of {} rays reverse ({} only beyond effort 1), worst {:.4} \
                 from effort {:.3} to {:.3}; {} overshoot (worst {:.4}); {} not held",
                e.trial,
                FINGER_NAMES.get(e.finger).copied().unwrap_or("?"),
                e.reversing,
                e.rays,
                e.reversing_beyond_only,
                e.worst.amount,
                e.worst.from_k,
                e.worst.to_k,
                e.overshooting,
                e.worst_overshoot,
                e.not_held
            )?;
        }
        let worst = self.worst().map_or(0.0, |e| e.worst.amount);
        writeln!(
            f,
            "{} rays checked to effort {}: {} reverse by more than {} (worst {worst:.4}; {} of \
             them only beyond effort 1), {} overshoot their trial's full effort, {} go to rest (implausible \
             shape), {} not held by the predictor",
            self.rays(),
            self.k_max,
            self.reversing(),
            self.tolerance,
            self.reversing_beyond_only(),
            self.overshooting(),
            self.resting(),
            self.not_held()
        )?;
        if self.passed() {
            writeln!(f, "beyond full effort every finger holds its direction")?;
        } else {
            writeln!(
                f,
                "BEYOND FULL EFFORT some fingers move against a stronger effort than the \
                 calibration's"
            )?;
        }
        Ok(())
    }
}
