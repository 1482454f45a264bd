//! Every real root of a polynomial in `[0, 1]`, by Bernstein subdivision.
//!
//! On an interval, a polynomial lies inside the convex hull of its Bernstein coefficients (they
//! are its values' weights: `p(t) = Σ b_i B_i(t)` with `B_i >= 0`, `Σ B_i = 1`). So:
//!
//! * all coefficients of one strict sign (beyond a rounding margin) **prove** the interval
//!   root-free;
//! * exactly one sign change, every coefficient clear of the margin, proves exactly one root
//!   (Descartes' rule of signs in the Bernstein basis: the number of sign changes bounds the
//!   roots and has the same parity), and `b_0 = p(lo)`, `b_n = p(hi)` differ in sign, so
//!   bisection converges to it;
//! * otherwise the interval is halved (de Casteljau, convex combinations only: stable).
//!
//! Subdivision stops on an interval whose largest coefficient times its width is below
//! [`SLOPE_FLOOR`] (or whose width is below [`WIDTH_FLOOR`]): there `|p| <= max |b_i|`, and
//! `p` is the derivative of the curve being checked, so the curve moves by at most that product
//! inside it. Both ends go into the candidate list and the product into the error bound. Nothing
//! is dropped unproven, so no root is missed: each root either is bracketed to
//! [`WIDTH_FLOOR`] or lies in an interval over which the curve is constant to the bound.

/// Stop subdividing when `max |b_i| · width` is below this (curve units).
pub const SLOPE_FLOOR: f64 = 1e-14;
/// Stop subdividing when an interval is narrower than this.
pub const WIDTH_FLOOR: f64 = 1e-13;
/// Coefficients within this fraction of the largest one (of the whole `[0, 1]`) count as zero:
/// far above the rounding of the basis change and of de Casteljau.
const ROUNDING_MARGIN: f64 = 1e-12;

/// Candidate points for the roots in `[0, 1]` and the bound on what they can be off by.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Roots {
    /// Points in `[0, 1]`: every root is one of them, or lies in an interval between two of
    /// them over which `|∫p| <= bound`.
    pub points: Vec<f64>,
    /// Largest `max |p| · width` over the intervals not resolved to a single point.
    pub bound: f64,
}

/// Bernstein coefficients on `[0, 1]` of a power-basis polynomial of degree `p.len() - 1`.
fn to_bernstein(p: &[f64]) -> Vec<f64> {
    let n = p.len() - 1;
    let binom =
        |n: usize, k: usize| (0..k).fold(1.0, |acc, i| acc * (n - i) as f64 / (i + 1) as f64);
    (0..=n)
        .map(|i| (0..=i).map(|j| binom(i, j) / binom(n, j) * p[j]).sum())
        .collect()
}

/// The coefficients on the two halves of the interval (de Casteljau at 1/2).
fn split(b: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let n = b.len();
    let mut work = b.to_vec();
    let mut left = Vec::with_capacity(n);
    let mut right = Vec::with_capacity(n);
    for level in 0..n {
        left.push(work[0]);
        right.push(work[n - 1 - level]);
        for i in 0..n - 1 - level {
            work[i] = 0.5 * (work[i] + work[i + 1]);
        }
    }
    right.reverse();
    (left, right)
}

/// Signs of the coefficients, `None` if any is inside the rounding margin.
fn clear_sign_changes(b: &[f64], margin: f64) -> Option<usize> {
    if b.iter().any(|v| v.abs() <= margin) {
        return None;
    }
    Some(
        b.windows(2)
            .filter(|w| (w[0] > 0.0) != (w[1] > 0.0))
            .count(),
    )
}

/// All real roots of `p` (power basis) in `[0, 1]`; see the module docs.
pub fn roots_in_unit(p: &[f64]) -> Roots {
    let mut out = Roots::default();
    if p.len() < 2 {
        // A constant: no isolated root (a zero constant has no critical structure either).
        return out;
    }
    let b = to_bernstein(p);
    let margin = ROUNDING_MARGIN * b.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    isolate(p, b, 0.0, 1.0, margin, &mut out);
    out
}

fn isolate(p: &[f64], b: Vec<f64>, lo: f64, hi: f64, margin: f64, out: &mut Roots) {
    let big = b.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    if b.iter().all(|&v| v > margin) || b.iter().all(|&v| v < -margin) {
        return;
    }
    let width = hi - lo;
    if big * width <= SLOPE_FLOOR || width <= WIDTH_FLOOR {
        out.points.extend([lo, hi]);
        out.bound = out.bound.max(big * width);
        return;
    }
    if clear_sign_changes(&b, margin) == Some(1) {
        let (k, w) = bisect(p, lo, hi, b[0] > 0.0);
        out.points.push(k);
        out.bound = out.bound.max(big * w);
        return;
    }
    let mid = 0.5 * (lo + hi);
    let (left, right) = split(&b);
    isolate(p, left, lo, mid, margin, out);
    isolate(p, right, mid, hi, margin, out);
}

/// The single sign change of `p` on `[lo, hi]` (`p(lo) > 0` iff `lo_positive`), to the last
/// bit; returns the midpoint of the final bracket and its width.
fn bisect(p: &[f64], mut lo: f64, mut hi: f64, lo_positive: bool) -> (f64, f64) {
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        let v = super::poly::eval(p, mid);
        if v == 0.0 {
            return (mid, 0.0);
        }
        if (v > 0.0) == lo_positive {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    (0.5 * (lo + hi), hi - lo)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn from_roots(roots: &[f64]) -> Vec<f64> {
        roots.iter().fold(vec![1.0], |acc, r| {
            super::super::poly::mul(&acc, &[-r, 1.0])
        })
    }

    #[test]
    fn finds_close_roots_and_ignores_outside_ones() {
        let p = from_roots(&[0.3, 0.3001, 0.9, 1.7, -0.5]);
        let r = roots_in_unit(&p);
        for want in [0.3, 0.3001, 0.9] {
            assert!(
                r.points.iter().any(|k| (k - want).abs() < 1e-9),
                "{want} missing from {:?}",
                r.points
            );
        }
        assert!(r.points.iter().all(|k| (0.0..=1.0).contains(k)));
        assert!(r.bound < 1e-12, "{}", r.bound);
    }

    #[test]
    fn root_free_and_constant_polynomials() {
        assert!(roots_in_unit(&[1.0, 1.0, 1.0]).points.is_empty());
        assert!(roots_in_unit(&[0.0]).points.is_empty());
        let zero = roots_in_unit(&[0.0, 0.0, 0.0]);
        assert_eq!(zero.bound, 0.0);
    }

    #[test]
    fn bernstein_split_reproduces_the_polynomial() {
        let p = [0.5, -3.0, 2.0, 1.0];
        let b = to_bernstein(&p);
        let (l, r) = split(&b);
        // Ends of the halves are p(0), p(1/2), p(1).
        assert!((l[0] - p[0]).abs() < 1e-15);
        assert!((l[3] - super::super::poly::eval(&p, 0.5)).abs() < 1e-14);
        assert!((r[0] - l[3]).abs() < 1e-15);
        assert!((r[3] - super::super::poly::eval(&p, 1.0)).abs() < 1e-14);
    }
}
