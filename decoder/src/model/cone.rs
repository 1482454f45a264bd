//! The calibration's channel patterns, and how far a window's lies from them (issue 25: a
//! window whose shape the calibration never saw, such as an electrode band that slipped).
//!
//! Each muscle reaches every electrode through its own fixed gains, and the powers of
//! independent muscles add on an electrode. So a window's per-channel power (its level squared:
//! RMS over the calibration's largest RMS of that channel) during any genuine contraction is,
//! to within the noise of a window's estimate, a sum of the powers of the movements it is made
//! of: a **non-negative combination of the calibration's patterns**, one per movement the
//! calibration recorded (each finger flexed and extended, the whole hand, rest). A grip of two
//! fingers is the sum of the two; a stronger grip is the same pattern larger (the fit is of
//! the shape: scale does not change it). A band turned around the forearm sees every muscle
//! from another place, and its patterns are not in that cone.
//!
//! The **misfit** of a window is the distance of its power vector from the cone (the residual
//! of a non-negative least-squares fit, Lawson and Hanson's active-set method on the patterns'
//! Gram matrix) over the vector's length: 0 on the cone, at most 1. The bar is relative to the
//! calibration, as the *alone* test's is: [`CONE_MARGIN`] times the worst misfit of the
//! calibration's own windows (those whose top channel is above the plausibility floor), and at
//! least [`CONE_LEAST`]. Measured (`cargo run --release -p driver --features sim --example
//! pattern_probe`):
//! - the simulator's calibration fits to 0.035 at worst (0.036 on another seed), its gestures
//!   (fist, pinch, point, thumbs-up: combinations the calibration never recorded as such) to
//!   0.057, that is 1.63 times; the band turned by half a spacing misfits 0.2 (median) and
//!   passes the bar (0.07) in 91% of its windows (the rest are mostly the whole hand, whose
//!   pattern a turn hardly changes), by 0.3 spacing in 84%;
//! - on the 3DC recordings a window's power is far noisier: the calibration (train) windows
//!   fit only to within 0.68, 0.67 and 0.63 (P4, P6, P7), the test windows to 0.74, 0.71 and
//!   0.79 (1.05-1.25 times). The bar is then above 1 and the test can never fire there: no
//!   false alarm, and no protection against a shifted band either. On real electrodes the
//!   test guards a patient whose calibration's patterns are as clean as a simulated one's;
//!   it is not a shift detector for every band.
//!
//! No allocation: the fit runs on fixed arrays of [`MAX_PATTERNS`] (`driver/tests/tick_alloc.rs`
//! runs it in the tick). Cost per window, same command, this 2-core Xeon: about 0.2 us where a
//! single recorded movement fits (the closest single pattern bounds the misfit and settles it),
//! 0.8 us for the gestures (the active set stops at the first fit within the bar), 1.1 us for a
//! window off the patterns (the whole fit), against 0.06 us for the rest of the plausibility
//! check; nothing below the floor (rest). The tick figures of BENCHMARKS.md run a calibrated
//! model (the demo's), so the plausibility check is in them (the model stage: 5.6 us there,
//! against 2.8 us for a random model without envelope or rest stage).

use super::error::ModelError;

/// The bar over the calibration's own worst misfit: the simulator's gestures reach 1.63 times
/// it, the 3DC test recordings 1.25 times.
pub const CONE_MARGIN: f64 = 2.0;

/// The least bar: below it a misfit is the noise of a window's power estimate (the simulator's
/// calibration windows reach 0.035).
pub const CONE_LEAST: f64 = 0.05;

/// Most patterns a cone holds (movements the calibration recorded, rest included).
pub const MAX_PATTERNS: usize = 24;

/// Most channels a cone covers.
pub const MAX_CHANNELS: usize = 32;

/// The calibration's patterns (per-channel power, unit length) and its own worst misfit.
#[derive(Debug, Clone, PartialEq)]
pub struct PatternCone {
    channels: usize,
    /// Pattern `k` is `patterns[k * channels..(k + 1) * channels]`.
    patterns: Vec<f64>,
    /// The patterns' Gram matrix, row-major `k x k`.
    gram: Vec<f64>,
    /// The calibration's worst misfit.
    worst: f64,
    /// The bar over `worst` ([`CONE_MARGIN`] unless set): a setting of the daemon (handd.toml),
    /// not of the model file.
    margin: f64,
}

impl PatternCone {
    /// A cone of `patterns` (each `channels` powers: finite, >= 0, of unit length to within
    /// 1e-9; kept bit for bit, so a file loads as it was saved) whose calibration misfit at
    /// worst `worst` (in [0, 1]).
    pub fn try_new(
        channels: usize,
        patterns: Vec<Vec<f64>>,
        worst: f64,
    ) -> Result<Self, ModelError> {
        let bad = |m: String| Err(ModelError::InvalidSpec(format!("channel patterns: {m}")));
        if !(1..=MAX_CHANNELS).contains(&channels) {
            return bad(format!("{channels} channels (1 to {MAX_CHANNELS})"));
        }
        if !(1..=MAX_PATTERNS).contains(&patterns.len()) {
            return bad(format!("{} patterns (1 to {MAX_PATTERNS})", patterns.len()));
        }
        if !(0.0..=1.0).contains(&worst) {
            return bad(format!(
                "the calibration's worst misfit {worst} is not in [0, 1]"
            ));
        }
        let mut flat = Vec::with_capacity(channels * patterns.len());
        for (k, p) in patterns.iter().enumerate() {
            if p.len() != channels {
                return bad(format!(
                    "pattern {k} has {} channels, not {channels}",
                    p.len()
                ));
            }
            if p.iter().any(|v| !(v.is_finite() && *v >= 0.0)) {
                return bad(format!("pattern {k} has a value not finite and >= 0"));
            }
            let n = norm(p);
            if (n - 1.0).abs() > 1e-9 {
                return bad(format!("pattern {k} has length {n}, not 1"));
            }
            flat.extend_from_slice(p);
        }
        let k = patterns.len();
        let mut gram = vec![0.0; k * k];
        for i in 0..k {
            for j in 0..k {
                gram[i * k + j] = dot(
                    &flat[i * channels..(i + 1) * channels],
                    &flat[j * channels..(j + 1) * channels],
                );
            }
        }
        Ok(Self {
            channels,
            patterns: flat,
            gram,
            worst,
            margin: CONE_MARGIN,
        })
    }

    /// The cone of a calibration: `powers` per window (`channels` each) and the window's
    /// movement (`key`: per finger +1, -1 or 0; all 0 is rest). One pattern per movement, the
    /// mean power of its windows; `worst` is the largest misfit among the windows for which
    /// `counts` is true (those above the plausibility floor). None with more movements than
    /// [`MAX_PATTERNS`] or none with any power.
    pub fn fit<'a>(
        channels: usize,
        windows: impl Iterator<Item = (&'a [f64], [i8; 5], bool)>,
    ) -> Result<Option<Self>, ModelError> {
        let mut groups: Vec<([i8; 5], Vec<f64>)> = Vec::new();
        let mut counted: Vec<&[f64]> = Vec::new();
        for (p, key, counts) in windows {
            if p.len() != channels {
                return Err(ModelError::Shape {
                    what: "channel powers".into(),
                    expected: channels,
                    found: p.len(),
                });
            }
            match groups.iter_mut().find(|g| g.0 == key) {
                Some(g) => g.1.iter_mut().zip(p).for_each(|(a, b)| *a += b),
                None => groups.push((key, p.to_vec())),
            }
            if counts {
                counted.push(p);
            }
        }
        // Any sum of powers is a pattern already: its mean has the same shape.
        let patterns: Vec<Vec<f64>> = groups
            .into_iter()
            .filter_map(|(_, p)| {
                let n = norm(&p);
                (n > 0.0).then(|| p.iter().map(|v| v / n).collect())
            })
            .collect();
        if patterns.is_empty() || patterns.len() > MAX_PATTERNS {
            return Ok(None);
        }
        let cone = Self::try_new(channels, patterns, 0.0)?;
        let worst = counted.iter().map(|p| cone.misfit(p)).fold(0.0, f64::max);
        Ok(Some(Self { worst, ..cone }))
    }

    /// Channels.
    pub fn channels(&self) -> usize {
        self.channels
    }

    /// The patterns, unit length, one per movement.
    pub fn patterns(&self) -> impl Iterator<Item = &[f64]> {
        self.patterns.chunks_exact(self.channels)
    }

    /// The calibration's own worst misfit.
    pub fn worst(&self) -> f64 {
        self.worst
    }

    /// The misfit above which a window is implausible: the margin ([`CONE_MARGIN`] unless set)
    /// times [`PatternCone::worst`], at least [`CONE_LEAST`]. Above 1 the test never fires.
    pub fn bar(&self) -> f64 {
        (self.margin * self.worst).max(CONE_LEAST)
    }

    /// Sets the margin over the calibration's worst misfit; finite and >= 1 (the caller
    /// validated it: handd's config allows 1.2 to 100).
    pub fn set_margin(&mut self, margin: f64) {
        debug_assert!(margin.is_finite() && margin >= 1.0, "margin {margin}");
        self.margin = margin;
    }

    /// The margin over the calibration's worst misfit.
    pub fn margin(&self) -> f64 {
        self.margin
    }

    /// Whether `power` (one value per channel, >= 0) is off the calibration's patterns. The
    /// closest single pattern bounds the misfit from above: when it is within the bar (a
    /// movement the calibration recorded, the usual case) the full fit is not needed.
    #[inline]
    pub fn off(&self, power: &[f64]) -> bool {
        let bar = self.bar();
        if bar >= 1.0 {
            return false;
        }
        let bb = dot(power, power);
        let best = self
            .patterns()
            .map(|p| dot(p, power).max(0.0))
            .fold(0.0f64, f64::max);
        if bb <= 0.0 || bb - best * best <= bar * bar * bb {
            return false;
        }
        self.distance2(power, bar * bar * bb) > bar * bar * bb
    }

    /// The distance of `power` from the cone over its length, in [0, 1] (0 for a zero
    /// vector). Panics on another channel count. No allocation.
    #[inline]
    pub fn misfit(&self, power: &[f64]) -> f64 {
        assert_eq!(power.len(), self.channels, "channel count");
        let bb = dot(power, power);
        if bb <= 0.0 {
            return 0.0;
        }
        (self.distance2(power, 0.0) / bb).sqrt().min(1.0)
    }

    /// The squared distance of `power` from the cone, or, as soon as the active-set method
    /// holds a feasible fit within `enough` (squared), that fit's: every step of the method
    /// is a non-negative combination, so its distance bounds the cone's from above.
    fn distance2(&self, power: &[f64], enough: f64) -> f64 {
        let k = self.patterns.len() / self.channels;
        let mut g = [0.0f64; MAX_PATTERNS];
        for (gi, p) in g.iter_mut().zip(self.patterns()) {
            *gi = dot(p, power);
        }
        let bb = dot(power, power);
        nnls(&self.gram, k, &g[..k], bb, enough)
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

fn norm(a: &[f64]) -> f64 {
    dot(a, a).sqrt()
}

/// `|b - Aq|²` at the minimiser `q` of `½ qᵀHq - gᵀq` over `q >= 0` (`H` the `k x k` Gram
/// matrix of unit patterns, `g` the patterns' products with the target `b`, `bb = b·b`):
/// non-negative least squares in its normal form, by Lawson and Hanson's active set. It
/// returns early with a feasible fit's residual once that is within `enough` (0: never).
/// Bounded work: at most `3k` additions to the set.
fn nnls(h: &[f64], k: usize, g: &[f64], bb: f64, enough: f64) -> f64 {
    let q = nnls_solution(h, k, g, bb, enough);
    residual(h, k, g, bb, &q)
}

/// `|b - Aq|² = b·b - 2 g·q + q·Hq`.
fn residual(h: &[f64], k: usize, g: &[f64], bb: f64, q: &[f64; MAX_PATTERNS]) -> f64 {
    let mut r2 = bb;
    for i in 0..k {
        if q[i] != 0.0 {
            let hq: f64 = (0..k).map(|j| h[i * k + j] * q[j]).sum();
            r2 += q[i] * (hq - 2.0 * g[i]);
        }
    }
    r2.max(0.0)
}

/// The active-set iteration of [`nnls`]: the solution, or the first feasible one within
/// `enough` (0: never).
#[inline(never)]
fn nnls_solution(h: &[f64], k: usize, g: &[f64], bb: f64, enough: f64) -> [f64; MAX_PATTERNS] {
    let mut q = [0.0f64; MAX_PATTERNS];
    let mut passive = [false; MAX_PATTERNS];
    // The Cholesky factor's room, filled afresh by every solve (initialised once per fit).
    let mut l = [0.0f64; MAX_PATTERNS * MAX_PATTERNS];
    let tol = 1e-12
        * g.iter()
            .fold(0.0f64, |a, v| a.max(v.abs()))
            .max(f64::MIN_POSITIVE);
    for _ in 0..3 * k {
        // The gradient's descent direction: w = g - Hq; the most promising inactive pattern.
        let mut best = None;
        let mut best_w = tol;
        for i in 0..k {
            if passive[i] {
                continue;
            }
            let mut w = g[i];
            for j in 0..k {
                w -= h[i * k + j] * q[j];
            }
            if w > best_w {
                best_w = w;
                best = Some(i);
            }
        }
        let Some(t) = best else { break };
        passive[t] = true;
        for _ in 0..k {
            let z = solve_passive(h, k, g, &passive, &mut l);
            let mut alpha = 1.0f64;
            for i in 0..k {
                if passive[i] && z[i] <= 0.0 {
                    alpha = alpha.min(q[i] / (q[i] - z[i]));
                }
            }
            if alpha >= 1.0 {
                q = z;
                if enough > 0.0 && residual(h, k, g, bb, &q) <= enough {
                    return q;
                }
                break;
            }
            for i in 0..k {
                if !passive[i] {
                    continue;
                }
                q[i] += alpha * (z[i] - q[i]);
                if q[i] <= tol {
                    q[i] = 0.0;
                    passive[i] = false;
                }
            }
        }
    }
    q
}

/// The unconstrained least-squares solution on the passive patterns (`H_PP z = g_P`, zero
/// elsewhere), by Cholesky; a pattern that depends on the others (a non-positive pivot) gets 0.
#[inline(never)]
fn solve_passive(
    h: &[f64],
    k: usize,
    g: &[f64],
    passive: &[bool; MAX_PATTERNS],
    l: &mut [f64; MAX_PATTERNS * MAX_PATTERNS],
) -> [f64; MAX_PATTERNS] {
    let mut idx = [0usize; MAX_PATTERNS];
    let mut m = 0;
    for (i, _) in passive[..k].iter().enumerate().filter(|(_, p)| **p) {
        idx[m] = i;
        m += 1;
    }
    // Lower-triangular factor of H_PP, row-major m x m; every entry of the lower triangle is
    // written before it is read (0 in a dependent pattern's column).
    let mut live = [true; MAX_PATTERNS];
    for r in 0..m {
        for c in 0..=r {
            let mut s = h[idx[r] * k + idx[c]];
            for j in 0..c {
                s -= l[r * m + j] * l[c * m + j];
            }
            if r == c {
                if s > 1e-12 {
                    l[r * m + r] = s.sqrt();
                } else {
                    live[r] = false;
                    l[r * m + r] = 0.0;
                }
            } else {
                l[r * m + c] = if live[c] { s / l[c * m + c] } else { 0.0 };
            }
        }
    }
    // Forward then back substitution; a dependent pattern's entries are 0 and it gets 0.
    let mut y = [0.0f64; MAX_PATTERNS];
    for r in 0..m {
        if live[r] {
            let mut s = g[idx[r]];
            for j in 0..r {
                s -= l[r * m + j] * y[j];
            }
            y[r] = s / l[r * m + r];
        }
    }
    let mut x = [0.0f64; MAX_PATTERNS];
    for r in (0..m).rev() {
        if live[r] {
            let mut s = y[r];
            for j in r + 1..m {
                s -= l[j * m + r] * x[j];
            }
            x[r] = s / l[r * m + r];
        }
    }
    let mut z = [0.0f64; MAX_PATTERNS];
    for r in 0..m {
        z[idx[r]] = x[r];
    }
    z
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit(p: &[f64]) -> Vec<f64> {
        let n = norm(p);
        p.iter().map(|v| v / n).collect()
    }

    /// Three channels, three patterns: two single channels and their even mix.
    fn cone() -> PatternCone {
        PatternCone::try_new(
            3,
            vec![
                vec![1.0, 0.0, 0.0],
                vec![0.0, 1.0, 0.0],
                unit(&[1.0, 1.0, 0.0]),
            ],
            0.01,
        )
        .expect("cone")
    }

    #[test]
    fn on_the_cone_nothing_is_off_and_beyond_it_the_distance_is_exact() {
        let c = cone();
        assert!(c.misfit(&[2.0, 3.0, 0.0]) < 1e-12);
        assert!(c.misfit(&[0.0, 0.0, 0.0]) == 0.0);
        // (1, 1, 1): the third channel no pattern has, |(0, 0, 1)| / |(1, 1, 1)|.
        assert!((c.misfit(&[1.0, 1.0, 1.0]) - 1.0 / 3f64.sqrt()).abs() < 1e-12);
        // Opposite a pattern's span direction is not reachable with q >= 0: all misfit.
        assert!((c.misfit(&[0.0, 0.0, 5.0]) - 1.0).abs() < 1e-12);
        assert!(c.off(&[1.0, 1.0, 1.0]) && !c.off(&[2.0, 3.0, 0.0]));
    }

    #[test]
    fn the_bar_is_relative_to_the_calibration_and_off_above_one() {
        let c = cone();
        assert_eq!(c.bar(), CONE_LEAST);
        let noisy = PatternCone::try_new(3, vec![vec![1.0, 0.0, 0.0]], 0.6).expect("cone");
        assert!((noisy.bar() - 1.2).abs() < 1e-12);
        assert!(!noisy.off(&[0.0, 0.0, 1.0]), "a bar above 1 never fires");
    }

    /// A deterministic pseudo-random source for the property below.
    fn lcg(s: &mut u64) -> f64 {
        *s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (*s >> 11) as f64 / (1u64 << 53) as f64
    }

    #[test]
    fn the_fit_meets_the_optimality_conditions_on_random_cones() {
        // Karush-Kuhn-Tucker: q >= 0, w = Aᵀ(b - Aq) <= 0 where q = 0 and = 0 where q > 0. Each
        // is checked against a brute force too: no pattern subset's fit is closer.
        let mut s = 7u64;
        for case in 0..300 {
            let (n, k) = (2 + case % 11, 1 + case % 13);
            let pats: Vec<Vec<f64>> = (0..k)
                .map(|_| unit(&(0..n).map(|_| lcg(&mut s).powi(3)).collect::<Vec<_>>()))
                .collect();
            let Ok(c) = PatternCone::try_new(n, pats, 0.0) else {
                continue;
            };
            let b: Vec<f64> = (0..n).map(|_| lcg(&mut s)).collect();
            let g: Vec<f64> = c.patterns().map(|p| dot(p, &b)).collect();
            let q = nnls_solution(&c.gram, k, &g, dot(&b, &b), 0.0);
            for i in 0..k {
                let w = g[i] - (0..k).map(|j| c.gram[i * k + j] * q[j]).sum::<f64>();
                assert!(q[i] >= 0.0, "case {case}: q[{i}] = {}", q[i]);
                assert!(w <= 1e-9, "case {case}: w[{i}] = {w} > 0");
                if q[i] > 0.0 {
                    assert!(w.abs() <= 1e-9, "case {case}: w[{i}] = {w} with q > 0");
                }
            }
            // Each single pattern alone (the best non-negative multiple) is never closer.
            let m = c.misfit(&b);
            let bb = dot(&b, &b);
            for p in c.patterns() {
                let a = dot(p, &b).max(0.0);
                let single = ((bb - a * a).max(0.0) / bb).sqrt();
                assert!(
                    m <= single + 1e-9,
                    "case {case}: {m} > a single pattern's {single}"
                );
            }
        }
    }

    #[test]
    fn fit_takes_one_pattern_per_movement_and_the_calibrations_worst() {
        let w: Vec<(Vec<f64>, [i8; 5], bool)> = vec![
            (vec![0.01, 0.01, 0.01], [0; 5], false),
            (vec![1.0, 0.1, 0.0], [1, 0, 0, 0, 0], true),
            (vec![2.0, 0.2, 0.0], [1, 0, 0, 0, 0], true),
            (vec![0.0, 0.1, 1.0], [-1, 0, 0, 0, 0], true),
            (vec![0.0, 0.1, 1.1], [-1, 0, 0, 0, 0], true),
        ];
        let c = PatternCone::fit(3, w.iter().map(|(p, k, c)| (p.as_slice(), *k, *c)))
            .expect("fit")
            .expect("a cone");
        assert_eq!(c.patterns().count(), 3);
        assert!(c.worst() > 0.0 && c.worst() < 0.01, "worst {}", c.worst());
        assert!(PatternCone::fit(2, w.iter().map(|(p, k, c)| (p.as_slice(), *k, *c))).is_err());
    }

    #[test]
    fn try_new_refuses_what_cannot_be_a_pattern() {
        assert!(PatternCone::try_new(2, vec![vec![0.0, 0.0]], 0.0).is_err());
        assert!(PatternCone::try_new(2, vec![vec![2.0, 0.0]], 0.0).is_err());
        assert!(PatternCone::try_new(2, vec![unit(&[1.0, -1.0])], 0.0).is_err());
        assert!(PatternCone::try_new(2, vec![vec![1.0, f64::NAN]], 0.0).is_err());
        assert!(PatternCone::try_new(2, vec![vec![1.0]], 0.0).is_err());
        assert!(PatternCone::try_new(2, vec![vec![1.0, 0.0]], 1.5).is_err());
        assert!(PatternCone::try_new(2, vec![], 0.0).is_err());
    }
}
