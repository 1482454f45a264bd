//! Rank statistics and least squares shared by the metrics.

use super::error::{check_pair, EvalError};

/// Ranks starting at 1, ties sharing the mean of the ranks they span (the "average" method of
/// `scipy.stats.rankdata`).
pub fn average_ranks(values: &[f64]) -> Vec<f64> {
    let mut order: Vec<usize> = (0..values.len()).collect();
    order.sort_by(|&a, &b| values[a].total_cmp(&values[b]));
    let mut ranks = vec![0.0; values.len()];
    let mut i = 0;
    while i < order.len() {
        let mut j = i + 1;
        while j < order.len() && values[order[j]] == values[order[i]] {
            j += 1;
        }
        // Positions i..j (0-based) hold equal values: ranks i+1..=j, mean (i+1+j)/2.
        let mean = (i + 1 + j) as f64 / 2.0;
        for &k in &order[i..j] {
            ranks[k] = mean;
        }
        i = j;
    }
    ranks
}

/// Pearson correlation; an error when either input is constant (the correlation is undefined).
pub fn pearson(x: &[f64], y: &[f64]) -> Result<f64, EvalError> {
    check_pair("pearson", x, y)?;
    if x.len() < 2 {
        return Err(EvalError::NotEnoughData(
            "pearson: fewer than 2 points".into(),
        ));
    }
    let n = x.len() as f64;
    let mx = x.iter().sum::<f64>() / n;
    let my = y.iter().sum::<f64>() / n;
    let (mut sxy, mut sxx, mut syy) = (0.0, 0.0, 0.0);
    for (a, b) in x.iter().zip(y) {
        sxy += (a - mx) * (b - my);
        sxx += (a - mx) * (a - mx);
        syy += (b - my) * (b - my);
    }
    if sxx == 0.0 || syy == 0.0 {
        return Err(EvalError::NotEnoughData(
            "pearson: an input is constant".into(),
        ));
    }
    Ok(sxy / (sxx * syy).sqrt())
}

/// Spearman's rho: the Pearson correlation of the average ranks.
pub fn spearman(x: &[f64], y: &[f64]) -> Result<f64, EvalError> {
    check_pair("spearman", x, y)?;
    pearson(&average_ranks(x), &average_ranks(y))
}

/// An ordinary least-squares line `y = slope * x + intercept` and its R².
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinearFit {
    /// Slope.
    pub slope: f64,
    /// Intercept.
    pub intercept: f64,
    /// Coefficient of determination of the fit, `1 - SS_res / SS_tot`.
    pub r2: f64,
}

/// Fits `y = slope * x + intercept` by least squares. When `y` is constant the fit is exact
/// and R² is reported as 1 if the residuals are zero (they are), which keeps flat-but-perfect
/// fits from poisoning averages; a constant `x` is an error.
pub fn linear_fit(x: &[f64], y: &[f64]) -> Result<LinearFit, EvalError> {
    check_pair("linear fit", x, y)?;
    if x.len() < 2 {
        return Err(EvalError::NotEnoughData(
            "linear fit: fewer than 2 points".into(),
        ));
    }
    let n = x.len() as f64;
    let mx = x.iter().sum::<f64>() / n;
    let my = y.iter().sum::<f64>() / n;
    let (mut sxy, mut sxx) = (0.0, 0.0);
    for (a, b) in x.iter().zip(y) {
        sxy += (a - mx) * (b - my);
        sxx += (a - mx) * (a - mx);
    }
    if sxx == 0.0 {
        return Err(EvalError::NotEnoughData("linear fit: x is constant".into()));
    }
    let slope = sxy / sxx;
    let intercept = my - slope * mx;
    let pred: Vec<f64> = x.iter().map(|a| slope * a + intercept).collect();
    let r2 = r2_or_exact(y, &pred);
    Ok(LinearFit {
        slope,
        intercept,
        r2,
    })
}

/// `1 - SS_res / SS_tot`, with a constant target counted as 1 when predicted exactly and 0
/// otherwise (the ratio itself is undefined there).
pub(crate) fn r2_or_exact(target: &[f64], pred: &[f64]) -> f64 {
    let n = target.len() as f64;
    let mean = target.iter().sum::<f64>() / n;
    let ss_tot: f64 = target.iter().map(|t| (t - mean) * (t - mean)).sum();
    let ss_res: f64 = target
        .iter()
        .zip(pred)
        .map(|(t, p)| (t - p) * (t - p))
        .sum();
    if ss_tot == 0.0 {
        return if ss_res <= 1e-24 { 1.0 } else { 0.0 };
    }
    1.0 - ss_res / ss_tot
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ties_share_the_mean_rank() {
        assert_eq!(
            average_ranks(&[3.0, 1.0, 3.0, 2.0]),
            vec![3.5, 1.0, 3.5, 2.0]
        );
        assert_eq!(average_ranks(&[5.0, 5.0, 5.0]), vec![2.0, 2.0, 2.0]);
    }

    #[test]
    fn spearman_of_a_monotone_map_is_one() {
        let x = [1.0, 2.0, 3.0, 4.0];
        let y = [1.0, 8.0, 27.0, 64.0];
        assert!((spearman(&x, &y).unwrap() - 1.0).abs() < 1e-12);
        let z = [4.0, 3.0, 2.0, 1.0];
        assert!((spearman(&x, &z).unwrap() + 1.0).abs() < 1e-12);
    }

    #[test]
    fn spearman_hand_computed_with_ties() {
        // ranks x = [1,2,3,4], ranks y = [1.5,1.5,4,3]: mean 2.5 each;
        // dx = [-1.5,-0.5,0.5,1.5], dy = [-1,-1,1.5,0.5]; sxy = 1.5+0.5+0.75+0.75 = 3.5;
        // sxx = 5, syy = 1+1+2.25+0.25 = 4.5; rho = 3.5/sqrt(22.5).
        let rho = spearman(&[1.0, 2.0, 3.0, 4.0], &[0.0, 0.0, 9.0, 5.0]).unwrap();
        assert!((rho - 3.5 / 22.5f64.sqrt()).abs() < 1e-12);
    }

    #[test]
    fn linear_fit_hand_computed() {
        // y = 2x + 1 exactly.
        let f = linear_fit(&[0.0, 1.0, 2.0], &[1.0, 3.0, 5.0]).unwrap();
        assert!((f.slope - 2.0).abs() < 1e-12 && (f.intercept - 1.0).abs() < 1e-12);
        assert!((f.r2 - 1.0).abs() < 1e-12);
        // x = [0,1,2], y = [0,2,1]: slope 0.5, intercept 0.5, pred [0.5,1,1.5],
        // SS_res = 0.25+1+0.25 = 1.5, SS_tot = 2, R² = 0.25.
        let f = linear_fit(&[0.0, 1.0, 2.0], &[0.0, 2.0, 1.0]).unwrap();
        assert!((f.slope - 0.5).abs() < 1e-12 && (f.intercept - 0.5).abs() < 1e-12);
        assert!((f.r2 - 0.25).abs() < 1e-12);
    }

    #[test]
    fn degenerate_inputs_are_errors() {
        assert!(pearson(&[1.0, 1.0], &[1.0, 2.0]).is_err());
        assert!(linear_fit(&[1.0, 1.0], &[1.0, 2.0]).is_err());
        assert!(spearman(&[1.0, f64::NAN], &[1.0, 2.0]).is_err());
        assert!(spearman(&[1.0], &[1.0, 2.0]).is_err());
    }
}
