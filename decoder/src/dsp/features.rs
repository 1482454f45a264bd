//! The 8 amplitude features of the paper's Table 1 over one window of one channel.

use super::config::FeatureSignal;
use super::feature_passes::{
    first_pass, first_pass_beside, lane_sum, squared_deviations, FirstPass,
};
use super::simd::Simd;

/// Features per channel.
pub const FEATURES_PER_CHANNEL: usize = 8;

/// Names of the per-channel features in the order they appear in the feature vector.
pub const FEATURE_NAMES: [&str; FEATURES_PER_CHANNEL] =
    ["RMS", "MAV", "VAR", "SD", "INT", "WL", "DASDV", "DAMV"];

/// Index of RMS within one channel's features.
pub const RMS_FEATURE: usize = 0;
const _: () = assert!(matches!(FEATURE_NAMES[RMS_FEATURE].as_bytes(), b"RMS"));

/// The 8 features of one window `x` (at least 2 samples; formulas in the module docs).
///
/// A window shorter than 2 samples has no defined VAR/DASDV/DAMV: all features are 0 then.
pub fn window_features(x: &[f64]) -> [f64; FEATURES_PER_CHANNEL] {
    let mut out = [0.0; FEATURES_PER_CHANNEL];
    strided_features_into(
        Simd::detect(),
        x,
        0,
        0,
        x.len(),
        FeatureSignal::Filtered,
        &mut out,
    );
    out
}

/// The features of one multi-channel window stored channel-major (`n_channels` runs of
/// `window.len() / n_channels` samples each) into `out`, 8 per channel in [`FEATURE_NAMES`]
/// order: the features-only path, the same per-channel computation as
/// [`super::Chain::features`] (bit for bit), with the instruction set detected at run time
/// (see [`multichannel_features_with`]). Allocation-free.
///
/// # Panics
/// If `n_channels` is 0, `window.len()` is not a multiple of it, or `out` is not
/// `8 * n_channels` long.
pub fn multichannel_features_into(window: &[f64], n_channels: usize, out: &mut [f64]) {
    multichannel_features_with(Simd::detect(), window, n_channels, out);
}

/// [`multichannel_features_into`] with the build of the loops chosen by `simd`; every choice
/// gives the same bits. Allocation-free.
///
/// # Panics
/// As [`multichannel_features_into`].
pub fn multichannel_features_with(simd: Simd, window: &[f64], n_channels: usize, out: &mut [f64]) {
    multichannel(simd, window, n_channels, FeatureSignal::Filtered, out);
}

/// [`multichannel_features_with`] for a rectified window (every value `>= 0`, as the chain's
/// default feature signal is): the same bits, one sum fewer per sample (the sum of `|x|` is the
/// plain sum there). A window with a negative value breaks the promise and gets wrong MAV and
/// INT (debug builds panic). Allocation-free.
///
/// # Panics
/// As [`multichannel_features_into`].
pub fn multichannel_rectified_features_with(
    simd: Simd,
    window: &[f64],
    n_channels: usize,
    out: &mut [f64],
) {
    debug_assert!(
        !window.iter().any(|&v| v < 0.0),
        "multichannel_rectified_features_with: a negative value in a rectified window"
    );
    multichannel(simd, window, n_channels, FeatureSignal::Rectified, out);
}

/// The checks and the dispatch both multichannel entry points share.
fn multichannel(
    simd: Simd,
    window: &[f64],
    n_channels: usize,
    signal: FeatureSignal,
    out: &mut [f64],
) {
    assert!(
        n_channels > 0 && window.len().is_multiple_of(n_channels),
        "multichannel features: {} values is not {n_channels} equal channels",
        window.len()
    );
    assert_eq!(
        out.len(),
        FEATURES_PER_CHANNEL * n_channels,
        "multichannel features: output length for {n_channels} channels"
    );
    let len = window.len() / n_channels;
    strided_features_into(simd, window, len, 0, len, signal, out);
}

/// Sums over one window: enough to get its 8 features.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(super) struct Stats {
    n: f64,
    sum_abs: f64,
    sum_sq: f64,
    /// Sums of `|x[i+1] - x[i]|` and of `(x[i+1] - x[i])^2`.
    wl: f64,
    d_sq: f64,
    /// Sum of squared deviations from the mean (two-pass).
    m2: f64,
}

impl Stats {
    /// The statistics from the first pass (`RECTIFIED` as it ran) and the squared deviations
    /// `m2`.
    #[inline(always)]
    pub(super) fn new<const RECTIFIED: bool>(nf: f64, first: &FirstPass, m2: f64) -> Stats {
        Stats {
            n: nf,
            sum_abs: lane_sum(first.sum_abs::<RECTIFIED>()),
            sum_sq: lane_sum(first.sum_sq),
            wl: lane_sum(first.wl),
            d_sq: lane_sum(first.d_sq),
            m2,
        }
    }

    /// The 8 features into `out[..8]`.
    #[inline(always)]
    pub(super) fn features_into(&self, out: &mut [f64]) {
        let nf = self.n;
        let var = self.m2 / (nf - 1.0);
        out[0] = (self.sum_sq / nf).sqrt();
        out[1] = self.sum_abs / nf;
        out[2] = var;
        out[3] = var.sqrt();
        out[4] = self.sum_abs;
        out[5] = self.wl;
        out[6] = (self.d_sq / (nf - 1.0)).sqrt();
        out[7] = self.wl / (nf - 1.0);
    }
}

/// The features of `out.len() / 8` windows of `len` samples each, window `c` being
/// `data[c * stride + offset..][..len]`, into `out` (8 per window; all 0 if `len < 2`, where
/// VAR, DASDV and DAMV are undefined). `signal` says what the windows hold: with
/// [`FeatureSignal::Rectified`] every value must be `>= 0` (the sum of `|x|` is then read from
/// the plain sum, the same bits). The loops are compiled for the instruction set `simd`
/// chooses; with AVX-512 two windows go through each pass side by side (`feature_pairs_x86`),
/// the same bits. Allocation-free.
///
/// # Panics
/// If a window lies outside `data`.
pub(crate) fn strided_features_into(
    simd: Simd,
    data: &[f64],
    stride: usize,
    offset: usize,
    len: usize,
    signal: FeatureSignal,
    out: &mut [f64],
) {
    #[cfg(target_arch = "x86_64")]
    if let Some(v4) = simd.x86_v4() {
        let windows = StridedWindows {
            data,
            stride,
            offset,
            len,
        };
        return super::feature_pairs_x86::strided_features_into(v4, windows, signal, out);
    }
    simd.run(
        #[inline(always)]
        || match signal {
            FeatureSignal::Rectified => strided::<true>(data, stride, offset, len, out),
            FeatureSignal::Filtered => strided::<false>(data, stride, offset, len, out),
        },
    )
}

/// Window `c` of a strided store is `data[c * stride + offset..][..len]`.
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy)]
pub(super) struct StridedWindows<'a> {
    pub(super) data: &'a [f64],
    pub(super) stride: usize,
    pub(super) offset: usize,
    pub(super) len: usize,
}

#[cfg(target_arch = "x86_64")]
impl<'a> StridedWindows<'a> {
    /// Window `c`.
    #[inline(always)]
    pub(super) fn get(self, c: usize) -> &'a [f64] {
        &self.data[c * self.stride + self.offset..][..self.len]
    }
}

/// [`strided_features_into`] for windows that are rectified or not.
#[inline(always)]
fn strided<const RECTIFIED: bool>(
    data: &[f64],
    stride: usize,
    offset: usize,
    len: usize,
    out: &mut [f64],
) {
    if len < 2 {
        out.fill(0.0);
        return;
    }
    let window = |c: usize| &data[c * stride + offset..c * stride + offset + len];
    let nf = len as f64;
    let mean = |first: &FirstPass| lane_sum(first.sum) / nf;
    // Window c's first pass runs beside window c - 1's second pass (see `first_pass_beside`).
    let mut prev: Option<FirstPass> = None;
    let n_windows = out.len() / FEATURES_PER_CHANNEL;
    let mut outs = out.chunks_exact_mut(FEATURES_PER_CHANNEL);
    for c in 0..n_windows {
        let x = window(c);
        let first = match prev {
            None => first_pass::<RECTIFIED>(x),
            Some(p) => {
                let (first, m2) = first_pass_beside::<RECTIFIED>(x, window(c - 1), mean(&p));
                if let Some(o) = outs.next() {
                    Stats::new::<RECTIFIED>(nf, &p, m2).features_into(o);
                }
                first
            }
        };
        prev = Some(first);
    }
    if let (Some(p), Some(o)) = (prev, outs.next()) {
        let m2 = squared_deviations(window(n_windows - 1), mean(&p));
        Stats::new::<RECTIFIED>(nf, &p, m2).features_into(o);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn known_window() {
        let f = window_features(&[1.0, -2.0, 3.0, -4.0]);
        let close = |a: f64, b: f64| (a - b).abs() < 1e-12;
        assert!(close(f[0], (30.0f64 / 4.0).sqrt()));
        assert!(close(f[1], 2.5));
        // mean -0.5: deviations 1.5, -1.5, 3.5, -3.5 -> 29 / 3
        assert!(close(f[2], 29.0 / 3.0));
        assert!(close(f[3], (29.0f64 / 3.0).sqrt()));
        assert!(close(f[4], 10.0));
        assert!(close(f[5], 3.0 + 5.0 + 7.0));
        assert!(close(f[6], ((9.0 + 25.0 + 49.0) / 3.0f64).sqrt()));
        assert!(close(f[7], 15.0 / 3.0));
    }

    #[test]
    fn lengths_not_multiple_of_lanes() {
        // A plain single-accumulator reference for every length around the lane width.
        for n in 2..11 {
            let x: Vec<f64> = (0..n).map(|i| ((i * 37) % 11) as f64 - 4.5).collect();
            let f = window_features(&x);
            let nf = n as f64;
            let mean = x.iter().sum::<f64>() / nf;
            let var = x.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (nf - 1.0);
            let wl: f64 = x.windows(2).map(|p| (p[1] - p[0]).abs()).sum();
            let dsq: f64 = x.windows(2).map(|p| (p[1] - p[0]).powi(2)).sum();
            let want = [
                (x.iter().map(|v| v * v).sum::<f64>() / nf).sqrt(),
                x.iter().map(|v| v.abs()).sum::<f64>() / nf,
                var,
                var.sqrt(),
                x.iter().map(|v| v.abs()).sum::<f64>(),
                wl,
                (dsq / (nf - 1.0)).sqrt(),
                wl / (nf - 1.0),
            ];
            for (a, b) in f.iter().zip(want) {
                assert!(
                    (a - b).abs() <= 1e-12 * b.abs().max(1.0),
                    "n {n}: {a} vs {b}"
                );
            }
        }
        assert_eq!(window_features(&[3.0]), [0.0; 8]);
    }

    /// The features as the three-pass 4-lane code before the passes were fused and dispatched
    /// computed them: the per-lane order that must never change.
    fn three_pass_reference(x: &[f64]) -> [f64; 8] {
        let lane_sum = |a: [f64; 4]| (a[0] + a[2]) + (a[1] + a[3]);
        let nf = x.len() as f64;
        let (mut s, mut sa, mut sq, mut wl, mut dsq, mut ss) =
            ([0.0; 4], [0.0; 4], [0.0; 4], [0.0; 4], [0.0; 4], [0.0; 4]);
        for (i, &v) in x.iter().enumerate() {
            s[i % 4] += v;
            sa[i % 4] += v.abs();
            sq[i % 4] += v * v;
        }
        for (i, p) in x.windows(2).enumerate() {
            let d = p[1] - p[0];
            wl[i % 4] += d.abs();
            dsq[i % 4] += d * d;
        }
        let mean = lane_sum(s) / nf;
        for (i, &v) in x.iter().enumerate() {
            ss[i % 4] += (v - mean) * (v - mean);
        }
        let (sa, wl, var) = (lane_sum(sa), lane_sum(wl), lane_sum(ss) / (nf - 1.0));
        [
            (lane_sum(sq) / nf).sqrt(),
            sa / nf,
            var,
            var.sqrt(),
            sa,
            wl,
            (lane_sum(dsq) / (nf - 1.0)).sqrt(),
            wl / (nf - 1.0),
        ]
    }

    #[test]
    fn the_rectified_pass_gives_the_bits_of_the_general_one_on_rectified_windows() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(16);
        for len in (2..=13).chain([31, 32, 33, 199, 200, 201]) {
            for ch in [1, 2, 3, 4, 5, 12] {
                let scale = 10f64.powi(rng.gen_range(-3..6));
                // Rectified values, with exact zeros of both signs among them.
                let w: Vec<f64> = (0..len * ch)
                    .map(|i| match i % 7 {
                        3 => 0.0,
                        5 => -0.0,
                        _ => rng.gen_range(0.0..1.0) * scale,
                    })
                    .collect();
                for simd in [
                    Simd::portable(),
                    Simd::detect().without_avx512(),
                    Simd::detect(),
                ] {
                    let (mut general, mut rectified) = (vec![0.0; 8 * ch], vec![0.0; 8 * ch]);
                    multichannel_features_with(simd, &w, ch, &mut general);
                    multichannel_rectified_features_with(simd, &w, ch, &mut rectified);
                    assert!(
                        general
                            .iter()
                            .zip(&rectified)
                            .all(|(a, b)| a.to_bits() == b.to_bits()),
                        "length {len}, {ch} channels, {simd:?}: {general:?} vs {rectified:?}"
                    );
                }
            }
        }
    }

    #[test]
    fn every_build_gives_the_bits_of_the_three_pass_code() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(15);
        let lengths = (2..=13).chain([31, 32, 33, 199, 200, 201]);
        for len in lengths {
            for ch in [1, 2, 3, 4, 5, 12] {
                let scale = 10f64.powi(rng.gen_range(-3..6));
                let w: Vec<f64> = (0..len * ch)
                    .map(|_| rng.gen_range(-1.0..1.0) * scale)
                    .collect();
                let mut outs = [vec![0.0; 8 * ch], vec![0.0; 8 * ch], vec![0.0; 8 * ch]];
                for (simd, out) in [
                    Simd::portable(),
                    Simd::detect().without_avx512(),
                    Simd::detect(),
                ]
                .into_iter()
                .zip(&mut outs)
                {
                    multichannel_features_with(simd, &w, ch, out);
                }
                for c in 0..ch {
                    let want = three_pass_reference(&w[c * len..(c + 1) * len]);
                    for out in &outs {
                        let got = &out[c * 8..(c + 1) * 8];
                        assert!(
                            got.iter()
                                .zip(want)
                                .all(|(a, b)| a.to_bits() == b.to_bits()),
                            "length {len}, {ch} channels, channel {c}: {got:?} vs {want:?}"
                        );
                    }
                }
            }
        }
    }
}
