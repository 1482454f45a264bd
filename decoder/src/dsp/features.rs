//! The 8 amplitude features of the paper's Table 1 over one window of one channel.

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
    features_into(x, &mut out);
    out
}

/// The features of one multi-channel window stored channel-major (`n_channels` runs of
/// `window.len() / n_channels` samples each) into `out`, 8 per channel in [`FEATURE_NAMES`]
/// order: the features-only path, the same per-channel computation as
/// [`super::Chain::features`] (bit for bit). Allocation-free.
///
/// # Panics
/// If `n_channels` is 0, `window.len()` is not a multiple of it, or `out` is not
/// `8 * n_channels` long.
pub fn multichannel_features_into(window: &[f64], n_channels: usize, out: &mut [f64]) {
    assert!(
        n_channels > 0 && window.len().is_multiple_of(n_channels),
        "multichannel_features_into: {} values is not {n_channels} equal channels",
        window.len()
    );
    assert_eq!(
        out.len(),
        FEATURES_PER_CHANNEL * n_channels,
        "multichannel_features_into: output length for {n_channels} channels"
    );
    let len = window.len() / n_channels;
    for (x, o) in window
        .chunks_exact(len.max(1))
        .zip(out.chunks_exact_mut(FEATURES_PER_CHANNEL))
    {
        features_into(x, o);
    }
    if len == 0 {
        out.fill(0.0);
    }
}

/// Lanes of partial sums: four independent accumulators break the add latency chain and let
/// the compiler vectorise; the order of additions is fixed, so results are deterministic.
const LANES: usize = 4;

fn lane_sum(acc: [f64; LANES]) -> f64 {
    (acc[0] + acc[2]) + (acc[1] + acc[3])
}

/// Sums over one window: enough to get its 8 features.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
struct Stats {
    n: f64,
    sum_abs: f64,
    sum_sq: f64,
    /// Sum of |x[i+1] - x[i]| and of (x[i+1] - x[i])^2.
    wl: f64,
    d_sq: f64,
    /// Sum of squared deviations from the mean (two-pass).
    m2: f64,
}

impl Stats {
    /// Statistics of the window `x` (at least 2 samples). Allocation-free.
    ///
    /// Three short passes (sums of x; of the differences; of squared deviations from the
    /// mean), each a plain loop over fixed-size chunks that the compiler vectorises; the
    /// window is in L1, so the extra passes cost less than one tangled loop.
    fn of(x: &[f64]) -> Stats {
        let n = x.len();
        debug_assert!(n > 1);
        let (sum, sum_abs, sum_sq) = sums(x);
        let (wl, d_sq) = difference_sums(x);
        let nf = n as f64;
        Stats {
            n: nf,
            sum_abs,
            sum_sq,
            wl,
            d_sq,
            m2: squared_deviations(x, sum / nf),
        }
    }

    /// The 8 features into `out[..8]`.
    fn features_into(&self, out: &mut [f64]) {
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

/// Sums of `x[i]`, `|x[i]|` and `x[i]^2`.
fn sums(x: &[f64]) -> (f64, f64, f64) {
    let (mut sum, mut sum_abs, mut sum_sq) = ([0.0; LANES], [0.0; LANES], [0.0; LANES]);
    let (chunks, rest) = x.as_chunks::<LANES>();
    for c in chunks {
        for l in 0..LANES {
            sum[l] += c[l];
            sum_abs[l] += c[l].abs();
            sum_sq[l] += c[l] * c[l];
        }
    }
    for (l, &v) in rest.iter().enumerate() {
        sum[l] += v;
        sum_abs[l] += v.abs();
        sum_sq[l] += v * v;
    }
    (lane_sum(sum), lane_sum(sum_abs), lane_sum(sum_sq))
}

/// Sums of `|x[i+1] - x[i]|` and `(x[i+1] - x[i])^2`, `i < n - 1`.
fn difference_sums(x: &[f64]) -> (f64, f64) {
    let (mut wl, mut d_sq) = ([0.0; LANES], [0.0; LANES]);
    let n = x.len();
    let (pc, prest) = x[..n - 1].as_chunks::<LANES>();
    let (nc, nrest) = x[1..].as_chunks::<LANES>();
    for (p, q) in pc.iter().zip(nc) {
        for l in 0..LANES {
            let d = q[l] - p[l];
            wl[l] += d.abs();
            d_sq[l] += d * d;
        }
    }
    for (l, (&p, &q)) in prest.iter().zip(nrest).enumerate() {
        let d = q - p;
        wl[l] += d.abs();
        d_sq[l] += d * d;
    }
    (lane_sum(wl), lane_sum(d_sq))
}

/// Sum of `(x[i] - mean)^2`, the second pass: the rectified signal has a large mean next to
/// its spread, and the one-pass form would cancel catastrophically.
fn squared_deviations(x: &[f64], mean: f64) -> f64 {
    let mut ss = [0.0; LANES];
    let (chunks, rest) = x.as_chunks::<LANES>();
    for c in chunks {
        for l in 0..LANES {
            let d = c[l] - mean;
            ss[l] += d * d;
        }
    }
    for (l, &v) in rest.iter().enumerate() {
        let d = v - mean;
        ss[l] += d * d;
    }
    lane_sum(ss)
}

/// Features of the window `x` into `out[..8]`. Allocation-free.
pub(crate) fn features_into(x: &[f64], out: &mut [f64]) {
    if x.len() < 2 {
        out[..FEATURES_PER_CHANNEL].fill(0.0);
        return;
    }
    Stats::of(x).features_into(out);
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
}
