//! The largest reversal of a curve against its expected direction:
//! `max dir·(y(k1) - y(k2))` over `0 <= k1 < k2 <= 1` (0 for a curve that never goes back).

use super::poly::{derivative, eval};
use super::roots::roots_in_unit;

/// How a reversal was found.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Method {
    /// From the critical points of the output polynomial: exact up to [`Reversal::bound`].
    Exact,
    /// From the model's outputs at this many evenly spaced efforts: a lower bound only.
    Sampled(usize),
}

/// The worst reversal of one curve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Reversal {
    /// `max dir·(y(k1) - y(k2))`, `k1 < k2`, clamped at 0; label units.
    pub amount: f64,
    /// Effort where the reversal starts (the local peak).
    pub from_k: f64,
    /// Effort where it ends (the lowest point after it).
    pub to_k: f64,
    /// For [`Method::Exact`]: `amount` is within this of the true maximum.
    pub bound: f64,
    /// How it was found.
    pub method: Method,
}

impl Reversal {
    /// No reversal found.
    pub fn none(method: Method) -> Self {
        Reversal {
            amount: 0.0,
            from_k: 0.0,
            to_k: 0.0,
            bound: 0.0,
            method,
        }
    }
}

/// The largest drop of `dir·y` along `(k, y)` points sorted by `k`.
pub fn largest_drop(points: &[(f64, f64)], dir: f64, method: Method) -> Reversal {
    let mut best = Reversal::none(method);
    let Some(&(k0, y0)) = points.first() else {
        return best;
    };
    let (mut peak_k, mut peak) = (k0, dir * y0);
    for &(k, y) in &points[1..] {
        let z = dir * y;
        if peak - z > best.amount {
            best.amount = peak - z;
            best.from_k = peak_k;
            best.to_k = k;
        }
        if z > peak {
            peak = z;
            peak_k = k;
        }
    }
    best
}

/// The exact largest reversal of the polynomial `y` (power basis in `k`) against `dir`
/// (+1: should rise, -1: should fall): between consecutive critical points `y` is monotonic,
/// so its extremes on `[0, 1]` are among `{0, 1}` and the real roots of `y'` there.
pub fn exact_reversal(y: &[f64], dir: f64) -> Reversal {
    exact_reversal_through(y, dir, &|v| v, 1.0)
}

/// [`exact_reversal`] of `g(y(k))` for a non-decreasing `g` whose slope is at most `slope`
/// (the rest stage): `g` keeps the order of values, so the extremes of `g∘y` are still among
/// the critical points of `y`, and the bound grows by `slope`.
pub fn exact_reversal_through(y: &[f64], dir: f64, g: &dyn Fn(f64) -> f64, slope: f64) -> Reversal {
    let roots = roots_in_unit(&derivative(y));
    let mut ks = roots.points;
    ks.extend([0.0, 1.0]);
    ks.sort_by(f64::total_cmp);
    ks.dedup();
    let points: Vec<(f64, f64)> = ks.iter().map(|&k| (k, g(eval(y, k)))).collect();
    let mut r = largest_drop(&points, dir, Method::Exact);
    // Each of the two ends may be off by the bound.
    r.bound = 2.0 * roots.bound * slope;
    r
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_cubic_with_a_hump() {
        // y = k³ - 1.5k² + 0.6k: y' = 3k² - 3k + 0.6, roots (3 ± sqrt(1.8))/6.
        let y = [0.0, 0.6, -1.5, 1.0];
        let s = 1.8f64.sqrt();
        let (a, b) = ((3.0 - s) / 6.0, (3.0 + s) / 6.0);
        let r = exact_reversal(&y, 1.0);
        assert!(
            (r.amount - (eval(&y, a) - eval(&y, b))).abs() < 1e-14,
            "{r:?}"
        );
        assert!((r.from_k - a).abs() < 1e-12 && (r.to_k - b).abs() < 1e-12);
        // Against -1 every rise counts: the largest is from y(0) = 0 (the lowest point before
        // k = 1, since y(b) > 0) to y(1) = 0.1, above the hump's y(a).
        let down = exact_reversal(&y, -1.0);
        assert!(eval(&y, b) > 0.0 && eval(&y, 1.0) > eval(&y, a));
        assert!((down.amount - 0.1).abs() < 1e-14, "{down:?}");
        assert_eq!((down.from_k, down.to_k), (0.0, 1.0));
    }

    #[test]
    fn a_monotonic_curve_does_not_reverse() {
        assert_eq!(exact_reversal(&[0.0, 2.0, 1.0], 1.0).amount, 0.0);
        assert!((exact_reversal(&[0.0, 2.0, 1.0], -1.0).amount - 3.0).abs() < 1e-15);
    }
}
