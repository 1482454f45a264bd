//! The features' two passes over two windows at once, for AVX-512: window `a`'s four lanes in
//! the low half of one eight-lane vector, window `b`'s in the high half.
//!
//! Lane `l` of each half is lane `l` of [`super::feature_passes`]: it sums the same terms of its
//! own window in the same order, and the tail and the final reduction are that module's scalar
//! code, so every window gets the bits of [`super::feature_passes::first_pass`] and
//! [`super::feature_passes::squared_deviations`]. What changes is only how many instructions
//! it takes: one eight-lane add where the four-lane build needs two, which is what bounds that
//! loop (its adds, not its add chains' latency). Every operation is an IEEE add, subtract,
//! multiply or absolute value (no FMA: a multiply and an add stay two roundings).

use pulp::{f64x8, x86::V4};

use super::config::FeatureSignal;
use super::feature_passes::{add_squared_deviations, lane_sum, whole_chunks, FirstPass, LANES};
use super::features::{Stats, StridedWindows, FEATURES_PER_CHANNEL};

/// Two windows (or their chunks) side by side.
type Pair<'a> = [&'a [f64]; 2];

/// Window `a`'s chunk in lanes 0..4, window `b`'s in lanes 4..8.
#[inline(always)]
fn join(a: &[f64; LANES], b: &[f64; LANES]) -> f64x8 {
    f64x8(a[0], a[1], a[2], a[3], b[0], b[1], b[2], b[3])
}

/// The two halves of `v`: window `a`'s lanes, window `b`'s lanes.
#[inline(always)]
fn split(v: f64x8) -> [[f64; LANES]; 2] {
    [[v.0, v.1, v.2, v.3], [v.4, v.5, v.6, v.7]]
}

/// The first-pass accumulators of two windows.
#[derive(Clone, Copy)]
struct PairPass {
    sum: f64x8,
    sum_abs: f64x8,
    sum_sq: f64x8,
    wl: f64x8,
    d_sq: f64x8,
}

impl PairPass {
    #[inline(always)]
    fn new(s: V4) -> PairPass {
        let zero = s.splat_f64x8(0.0);
        PairPass {
            sum: zero,
            sum_abs: zero,
            sum_sq: zero,
            wl: zero,
            d_sq: zero,
        }
    }

    /// [`FirstPass::add_chunk`] for both windows: the samples `p` and the differences `q - p`.
    #[inline(always)]
    fn add_chunk<const RECTIFIED: bool>(&mut self, s: V4, p: f64x8, q: f64x8) {
        self.sum = s.add_f64x8(self.sum, p);
        if !RECTIFIED {
            self.sum_abs = s.add_f64x8(self.sum_abs, s.abs_f64x8(p));
        }
        self.sum_sq = s.add_f64x8(self.sum_sq, s.mul_f64x8(p, p));
        let d = s.sub_f64x8(q, p);
        self.wl = s.add_f64x8(self.wl, s.abs_f64x8(d));
        self.d_sq = s.add_f64x8(self.d_sq, s.mul_f64x8(d, d));
    }

    /// Window `w`'s (0 or 1) four lanes of every sum.
    #[inline(always)]
    fn half(&self, w: usize) -> FirstPass {
        FirstPass {
            sum: split(self.sum)[w],
            sum_abs: split(self.sum_abs)[w],
            sum_sq: split(self.sum_sq)[w],
            wl: split(self.wl)[w],
            d_sq: split(self.d_sq)[w],
        }
    }

    /// Each window's [`FirstPass`], its tail (from the whole chunks on) added by the scalar
    /// code.
    #[inline(always)]
    fn finish<const RECTIFIED: bool>(self, x: Pair<'_>, full: usize) -> [FirstPass; 2] {
        let mut halves = [self.half(0), self.half(1)];
        for (acc, x) in halves.iter_mut().zip(x) {
            acc.add_tail::<RECTIFIED>(x, full * LANES);
        }
        halves
    }
}

/// The whole chunks of two windows, `full` of them, zipped: window `a`'s and window `b`'s.
#[inline(always)]
fn zipped<'a>(
    a: &'a [f64],
    b: &'a [f64],
    full: usize,
) -> impl Iterator<Item = (&'a [f64; LANES], &'a [f64; LANES])> {
    a.as_chunks().0[..full].iter().zip(&b.as_chunks().0[..full])
}

/// Adds `(c - mean)^2` of both windows' chunks to `ss`.
#[inline(always)]
fn add_squared(s: V4, ss: f64x8, c: f64x8, mean: f64x8) -> f64x8 {
    let d = s.sub_f64x8(c, mean);
    s.add_f64x8(ss, s.mul_f64x8(d, d))
}

/// Each window's sum of squared deviations: `ss` holds the whole chunks, the scalar code adds
/// the rest.
#[inline(always)]
fn finish_squared(ss: f64x8, x: Pair<'_>, means: [f64; 2], full: usize) -> [f64; 2] {
    let [mut a, mut b] = split(ss);
    add_squared_deviations(&mut a, x[0], means[0], full);
    add_squared_deviations(&mut b, x[1], means[1], full);
    [lane_sum(a), lane_sum(b)]
}

/// [`super::feature_passes::first_pass`] of two windows of the same length (at least 2).
#[inline(always)]
fn first_pass<const RECTIFIED: bool>(s: V4, x: Pair<'_>) -> [FirstPass; 2] {
    let full = whole_chunks(x[0].len());
    let mut acc = PairPass::new(s);
    for ((a, b), (a1, b1)) in zipped(x[0], x[1], full).zip(zipped(&x[0][1..], &x[1][1..], full)) {
        acc.add_chunk::<RECTIFIED>(s, join(a, b), join(a1, b1));
    }
    acc.finish::<RECTIFIED>(x, full)
}

/// [`super::feature_passes::first_pass_beside`] for two windows `x` beside the two windows
/// `prev` before them (all of the same length, at least 2), whose means are `means`: `x`'s
/// first passes and `prev`'s sums of squared deviations.
#[inline(always)]
fn first_pass_beside<const RECTIFIED: bool>(
    s: V4,
    x: Pair<'_>,
    prev: Pair<'_>,
    means: [f64; 2],
) -> ([FirstPass; 2], [f64; 2]) {
    let full = whole_chunks(x[0].len());
    let mean = join(&[means[0]; LANES], &[means[1]; LANES]);
    let mut acc = PairPass::new(s);
    let mut ss = s.splat_f64x8(0.0);
    let now = zipped(x[0], x[1], full);
    let next = zipped(&x[0][1..], &x[1][1..], full);
    let before = zipped(prev[0], prev[1], full);
    for (((a, b), (a1, b1)), (pa, pb)) in now.zip(next).zip(before) {
        acc.add_chunk::<RECTIFIED>(s, join(a, b), join(a1, b1));
        ss = add_squared(s, ss, join(pa, pb), mean);
    }
    (
        acc.finish::<RECTIFIED>(x, full),
        finish_squared(ss, prev, means, full),
    )
}

/// [`super::feature_passes::squared_deviations`] of two windows of the same length (at least
/// 2) with means `means`.
#[inline(always)]
fn squared_deviations(s: V4, x: Pair<'_>, means: [f64; 2]) -> [f64; 2] {
    let full = whole_chunks(x[0].len());
    let mean = join(&[means[0]; LANES], &[means[1]; LANES]);
    let mut ss = s.splat_f64x8(0.0);
    for (a, b) in zipped(x[0], x[1], full) {
        ss = add_squared(s, ss, join(a, b), mean);
    }
    finish_squared(ss, x, means, full)
}

/// [`super::features::strided_features_into`] with AVX-512: the same windows, the same bits.
pub(super) fn strided_features_into(
    s: V4,
    windows: StridedWindows<'_>,
    signal: FeatureSignal,
    out: &mut [f64],
) {
    // A `WithSimd` value rather than a closure: every call from here down is
    // `#[inline(always)]`, so all of it is compiled for AVX-512 (a closure's call shim is
    // only an inlining hint and, once the body is large, stays a plain baseline function).
    match signal {
        FeatureSignal::Rectified => pulp::Simd::vectorize(s, Op::<true> { s, windows, out }),
        FeatureSignal::Filtered => pulp::Simd::vectorize(s, Op::<false> { s, windows, out }),
    }
}

/// The whole feature computation as one operation for [`pulp::Simd::vectorize`].
struct Op<'a, const RECTIFIED: bool> {
    s: V4,
    windows: StridedWindows<'a>,
    out: &'a mut [f64],
}

impl<const RECTIFIED: bool> pulp::WithSimd for Op<'_, RECTIFIED> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _: S) {
        pairs::<RECTIFIED>(self.s, self.windows, self.out);
    }
}

/// Pair `p`'s first pass beside pair `p - 1`'s second pass; an odd last window goes through
/// the four-lane passes alone. Every window gets the bits the four-lane code gives it.
#[inline(always)]
fn pairs<const RECTIFIED: bool>(s: V4, w: StridedWindows<'_>, out: &mut [f64]) {
    if w.len < 2 {
        out.fill(0.0);
        return;
    }
    let nf = w.len as f64;
    let n_windows = out.len() / FEATURES_PER_CHANNEL;
    let mut outs = out.chunks_exact_mut(FEATURES_PER_CHANNEL);
    let mut prev: Option<(usize, [FirstPass; 2])> = None;
    let mut c = 0;
    while c + 2 <= n_windows {
        let x = [w.get(c), w.get(c + 1)];
        let firsts = match prev {
            None => first_pass::<RECTIFIED>(s, x),
            Some((pc, [p0, p1])) => {
                let means = [mean(&p0, nf), mean(&p1, nf)];
                let before = [w.get(pc), w.get(pc + 1)];
                let (firsts, m2) = first_pass_beside::<RECTIFIED>(s, x, before, means);
                emit::<RECTIFIED>(&mut outs, nf, &p0, m2[0]);
                emit::<RECTIFIED>(&mut outs, nf, &p1, m2[1]);
                firsts
            }
        };
        prev = Some((c, firsts));
        c += 2;
    }
    if let Some((pc, [p0, p1])) = prev {
        let means = [mean(&p0, nf), mean(&p1, nf)];
        let m2 = squared_deviations(s, [w.get(pc), w.get(pc + 1)], means);
        emit::<RECTIFIED>(&mut outs, nf, &p0, m2[0]);
        emit::<RECTIFIED>(&mut outs, nf, &p1, m2[1]);
    }
    if c < n_windows {
        let x = w.get(c);
        let first = super::feature_passes::first_pass::<RECTIFIED>(x);
        let m2 = super::feature_passes::squared_deviations(x, mean(&first, nf));
        emit::<RECTIFIED>(&mut outs, nf, &first, m2);
    }
}

/// The mean of a window of `nf` samples from its first pass.
#[inline(always)]
fn mean(first: &FirstPass, nf: f64) -> f64 {
    lane_sum(first.sum) / nf
}

/// The features of one window from its passes into the next 8 values of `outs`.
#[inline(always)]
fn emit<const RECTIFIED: bool>(
    outs: &mut std::slice::ChunksExactMut<'_, f64>,
    nf: f64,
    first: &FirstPass,
    m2: f64,
) {
    if let Some(o) = outs.next() {
        Stats::new::<RECTIFIED>(nf, first, m2).features_into(o);
    }
}
