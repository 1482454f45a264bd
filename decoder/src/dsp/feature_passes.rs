//! The two passes over a group of windows that the features need, as 4-lane partial sums.
//!
//! Lane `l` of every accumulator sums the terms of the samples `i` with `i % 4 == l`, in
//! increasing `i`, and the four lanes are reduced as `(l0 + l2) + (l1 + l3)`: that order is
//! part of the results (training, replay and the daemon must agree bit for bit), so it never
//! depends on the instruction set or on how the loops are arranged. Within it the loops are
//! arranged for speed: the sums of the samples and of their differences share one pass, and
//! several windows (channels) go through each pass side by side, so the add latency of one
//! accumulator does not bound the loop; every function is inlined into the caller's
//! [`super::Simd::run`] and so compiled for its instruction set.
//!
//! `RECTIFIED` passes are for a rectified window (every value `>= 0`): there `|x| = x`, so the
//! sum of `|x|` is the plain sum, value for value in the same order (`+0 + -0 = +0`), the same
//! bits; it is not accumulated a second time.

/// Lanes of partial sums (the width of one AVX register of f64).
pub(super) const LANES: usize = 4;

/// The fixed reduction of the lanes.
#[inline(always)]
pub(super) fn lane_sum(acc: [f64; LANES]) -> f64 {
    (acc[0] + acc[2]) + (acc[1] + acc[3])
}

/// The lane accumulators of the first pass over one window.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct FirstPass {
    /// Sums of `x[i]`, `|x[i]|` and `x[i]^2`.
    pub(super) sum: [f64; LANES],
    pub(super) sum_abs: [f64; LANES],
    pub(super) sum_sq: [f64; LANES],
    /// Sums of `|d[i]|` and `d[i]^2`, `d[i] = x[i+1] - x[i]`, `i < n - 1`.
    pub(super) wl: [f64; LANES],
    pub(super) d_sq: [f64; LANES],
}

impl FirstPass {
    /// Adds sample `v` to lane `l`.
    #[inline(always)]
    fn add_sample<const RECTIFIED: bool>(&mut self, l: usize, v: f64) {
        self.sum[l] += v;
        if !RECTIFIED {
            self.sum_abs[l] += v.abs();
        }
        self.sum_sq[l] += v * v;
    }

    /// The lanes of the sum of `|x|` (of a rectified window: the plain sum, see the module
    /// docs).
    #[inline(always)]
    pub(super) fn sum_abs<const RECTIFIED: bool>(&self) -> [f64; LANES] {
        if RECTIFIED {
            self.sum
        } else {
            self.sum_abs
        }
    }

    /// Adds the difference `q - p` to lane `l`.
    #[inline(always)]
    fn add_difference(&mut self, l: usize, p: f64, q: f64) {
        let d = q - p;
        self.wl[l] += d.abs();
        self.d_sq[l] += d * d;
    }

    /// Adds the 4 samples `p` (lanes 0..4) and the differences `q[l] - p[l]`, where `q` is `p`
    /// one sample later.
    #[inline(always)]
    fn add_chunk<const RECTIFIED: bool>(&mut self, p: &[f64; LANES], q: &[f64; LANES]) {
        for l in 0..LANES {
            self.add_sample::<RECTIFIED>(l, p[l]);
            self.add_difference(l, p[l], q[l]);
        }
    }

    /// Adds the samples `x[start..]` and the differences from `start` on, lane `i % 4`.
    #[inline(always)]
    pub(super) fn add_tail<const RECTIFIED: bool>(&mut self, x: &[f64], start: usize) {
        for (i, &v) in x.iter().enumerate().skip(start) {
            self.add_sample::<RECTIFIED>(i % LANES, v);
        }
        for (i, p) in x.windows(2).enumerate().skip(start) {
            self.add_difference(i % LANES, p[0], p[1]);
        }
    }
}

/// Chunks of 4 where both the samples and the differences of an `n`-sample window are whole.
#[inline(always)]
pub(super) fn whole_chunks(n: usize) -> usize {
    (n - 1) / LANES
}

/// The first pass over a window (at least 2 samples): sums of the samples and of their
/// differences.
#[inline(always)]
pub(super) fn first_pass<const RECTIFIED: bool>(x: &[f64]) -> FirstPass {
    let full = whole_chunks(x.len());
    let now = &x.as_chunks().0[..full];
    let next = &x[1..].as_chunks().0[..full];
    let mut acc = FirstPass::default();
    for (p, q) in now.iter().zip(next) {
        acc.add_chunk::<RECTIFIED>(p, q);
    }
    acc.add_tail::<RECTIFIED>(x, full * LANES);
    acc
}

/// The first pass over `x` beside the second pass over `prev`, the window before it (of the
/// same length, at least 2), whose mean is `prev_mean`: `x`'s first-pass sums and `prev`'s sum
/// of squared deviations. One loop for both, so the single add chain of the second pass runs
/// next to the first pass's independent work instead of bounding its own loop.
#[inline(always)]
pub(super) fn first_pass_beside<const RECTIFIED: bool>(
    x: &[f64],
    prev: &[f64],
    prev_mean: f64,
) -> (FirstPass, f64) {
    let full = whole_chunks(x.len());
    let now = &x.as_chunks().0[..full];
    let next = &x[1..].as_chunks().0[..full];
    let before = &prev.as_chunks().0[..full];
    let mut acc = FirstPass::default();
    let mut ss = [0.0; LANES];
    for ((p, q), b) in now.iter().zip(next).zip(before) {
        acc.add_chunk::<RECTIFIED>(p, q);
        add_chunk_squared_deviations(&mut ss, b, prev_mean);
    }
    acc.add_tail::<RECTIFIED>(x, full * LANES);
    add_squared_deviations(&mut ss, prev, prev_mean, full);
    (acc, lane_sum(ss))
}

/// Adds `(c[l] - mean)^2` to lane `l`.
#[inline(always)]
fn add_chunk_squared_deviations(ss: &mut [f64; LANES], c: &[f64; LANES], mean: f64) {
    for l in 0..LANES {
        let d = c[l] - mean;
        ss[l] += d * d;
    }
}

/// Adds `(x[i] - mean)^2` for `i >= 4 * from_chunk` to the lanes `ss`.
#[inline(always)]
pub(super) fn add_squared_deviations(
    ss: &mut [f64; LANES],
    x: &[f64],
    mean: f64,
    from_chunk: usize,
) {
    let (chunks, rest) = x.as_chunks::<LANES>();
    for c in &chunks[from_chunk.min(chunks.len())..] {
        add_chunk_squared_deviations(ss, c, mean);
    }
    for (l, &v) in rest.iter().enumerate() {
        let d = v - mean;
        ss[l] += d * d;
    }
}

/// Sum of `(x[i] - mean)^2`, the second pass: the rectified signal has a large mean next to
/// its spread, and the one-pass form would cancel catastrophically.
#[inline(always)]
pub(super) fn squared_deviations(x: &[f64], mean: f64) -> f64 {
    let mut ss = [0.0; LANES];
    add_squared_deviations(&mut ss, x, mean, 0);
    lane_sum(ss)
}
