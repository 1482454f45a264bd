//! Polynomials in the effort `k`, coefficients lowest degree first.

/// `p(k)` by Horner's rule.
pub fn eval(p: &[f64], k: f64) -> f64 {
    p.iter().rev().fold(0.0, |acc, c| acc * k + c)
}

/// The derivative `p'`.
pub fn derivative(p: &[f64]) -> Vec<f64> {
    p.iter()
        .enumerate()
        .skip(1)
        .map(|(i, c)| i as f64 * c)
        .collect()
}

/// The product `a·b`.
pub fn mul(a: &[f64], b: &[f64]) -> Vec<f64> {
    if a.is_empty() || b.is_empty() {
        return Vec::new();
    }
    let mut out = vec![0.0; a.len() + b.len() - 1];
    for (i, x) in a.iter().enumerate() {
        for (j, y) in b.iter().enumerate() {
            out[i + j] += x * y;
        }
    }
    out
}

/// A vector of polynomials stored coefficient-major: `coefs[d][i]` is the coefficient of `k^d`
/// in entry `i`. A matrix times it is then one matrix-vector product per degree.
#[derive(Debug, Clone, PartialEq)]
pub struct PolyVec {
    /// One row of entries per degree `0..=degree`.
    pub coefs: Vec<Vec<f64>>,
}

impl PolyVec {
    /// Number of entries.
    pub fn len(&self) -> usize {
        self.coefs.first().map_or(0, Vec::len)
    }

    /// `W·v` for a row-major `rows x self.len()` matrix `w`.
    pub fn mat_mul(&self, w: &[f64], rows: usize) -> PolyVec {
        let cols = self.len();
        debug_assert_eq!(w.len(), rows * cols);
        let coefs = self
            .coefs
            .iter()
            .map(|c| {
                w.chunks_exact(cols)
                    .map(|row| row.iter().zip(c).map(|(a, b)| a * b).sum())
                    .collect()
            })
            .collect();
        PolyVec { coefs }
    }

    /// Entry `i` as a coefficient list.
    pub fn entry(&self, i: usize) -> Vec<f64> {
        self.coefs.iter().map(|c| c[i]).collect()
    }

    /// The ResDD module output `g∘m + g`, entry by entry.
    pub fn gated(g: &PolyVec, m: &PolyVec) -> PolyVec {
        let n = g.len();
        let degree = (g.coefs.len() - 1) + (m.coefs.len() - 1);
        let entries: Vec<Vec<f64>> = (0..n)
            .map(|i| {
                let gi = g.entry(i);
                let mut a = mul(&gi, &m.entry(i));
                a.resize(degree + 1, 0.0);
                for (ad, c) in a.iter_mut().zip(&gi) {
                    *ad += c;
                }
                a
            })
            .collect();
        let coefs = (0..=degree)
            .map(|d| entries.iter().map(|e| e[d]).collect())
            .collect();
        PolyVec { coefs }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn horner_product_and_derivative() {
        let p = [1.0, -2.0, 3.0]; // 1 - 2k + 3k²
        assert_eq!(eval(&p, 2.0), 9.0);
        assert_eq!(derivative(&p), vec![-2.0, 6.0]);
        assert_eq!(mul(&[1.0, 1.0], &[-1.0, 1.0]), vec![-1.0, 0.0, 1.0]);
    }

    #[test]
    fn gated_is_g_times_m_plus_g() {
        let g = PolyVec {
            coefs: vec![vec![0.0], vec![2.0]],
        }; // 2k
        let m = PolyVec {
            coefs: vec![vec![0.0], vec![0.0], vec![1.0]],
        }; // k²
        let a = PolyVec::gated(&g, &m);
        assert_eq!(a.entry(0), vec![0.0, 2.0, 0.0, 2.0]);
    }
}
