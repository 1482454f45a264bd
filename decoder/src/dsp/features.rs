//! The 8 amplitude features of the paper's Table 1 over one window of one channel.

/// Features per channel.
pub const FEATURES_PER_CHANNEL: usize = 8;

/// Names of the per-channel features in the order they appear in the feature vector.
pub const FEATURE_NAMES: [&str; FEATURES_PER_CHANNEL] =
    ["RMS", "MAV", "VAR", "SD", "INT", "WL", "DASDV", "DAMV"];

/// The 8 features of one window `x` (at least 2 samples; formulas in the module docs).
///
/// A window shorter than 2 samples has no defined VAR/DASDV/DAMV: all features are 0 then.
pub fn window_features(x: &[f64]) -> [f64; FEATURES_PER_CHANNEL] {
    let mut out = [0.0; FEATURES_PER_CHANNEL];
    features_of_split(x, &[], &mut out);
    out
}

/// Features of the window `older ++ newer` (a ring buffer read in chronological order without
/// copying). `out` has 8 slots. Allocation-free.
pub(crate) fn features_of_split(older: &[f64], newer: &[f64], out: &mut [f64]) {
    let n = older.len() + newer.len();
    if n < 2 {
        out[..FEATURES_PER_CHANNEL].fill(0.0);
        return;
    }
    let nf = n as f64;
    let mut sum = 0.0;
    let mut sum_abs = 0.0;
    let mut sum_sq = 0.0;
    let mut wl = 0.0;
    let mut d_sq = 0.0;
    let mut prev = if older.is_empty() { newer[0] } else { older[0] };
    for &v in older.iter().chain(newer) {
        sum += v;
        sum_abs += v.abs();
        sum_sq += v * v;
        let d = v - prev;
        wl += d.abs();
        d_sq += d * d;
        prev = v;
    }
    // Two-pass variance: the rectified signal has a large mean next to its spread, and the
    // one-pass form would cancel catastrophically.
    let mean = sum / nf;
    let mut ss = 0.0;
    for &v in older.iter().chain(newer) {
        let c = v - mean;
        ss += c * c;
    }
    let var = ss / (nf - 1.0);
    out[0] = (sum_sq / nf).sqrt();
    out[1] = sum_abs / nf;
    out[2] = var;
    out[3] = var.sqrt();
    out[4] = sum_abs;
    out[5] = wl;
    out[6] = (d_sq / (nf - 1.0)).sqrt();
    out[7] = wl / (nf - 1.0);
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
    fn split_equals_contiguous() {
        let x = [0.5, 1.5, -0.25, 4.0, 2.0, -1.0];
        let whole = window_features(&x);
        let mut split = [0.0; 8];
        features_of_split(&x[..2], &x[2..], &mut split);
        assert_eq!(whole, split);
    }
}
