//! Tracking metrics for following a continuous target (sine tracking with the simulated user).

use super::error::{check_pair, EvalError};
use super::stats::r2_or_exact;

/// Targets whose magnitude is below this are left out of the MAPE: a percentage of a target
/// near zero is meaningless.
pub const MAPE_MIN_TARGET: f64 = 0.1;

/// Tracking figures of one output against its target.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrackingMetrics {
    /// Root mean square error.
    pub rmse: f64,
    /// Mean absolute percentage error (in percent) over samples with `|target| >= 0.1`;
    /// `None` when no sample qualifies.
    pub mape: Option<f64>,
    /// `1 - SS_res / SS_tot`.
    pub r2: f64,
}

/// RMSE, MAPE and R² of `output` against `target`.
pub fn tracking_metrics(target: &[f64], output: &[f64]) -> Result<TrackingMetrics, EvalError> {
    check_pair("tracking metrics", target, output)?;
    if target.is_empty() {
        return Err(EvalError::NotEnoughData(
            "tracking metrics: no samples".into(),
        ));
    }
    let n = target.len() as f64;
    let mse = target
        .iter()
        .zip(output)
        .map(|(t, o)| (t - o) * (t - o))
        .sum::<f64>()
        / n;
    let (mut sum_ape, mut count) = (0.0, 0usize);
    for (t, o) in target.iter().zip(output) {
        if t.abs() >= MAPE_MIN_TARGET {
            sum_ape += ((t - o) / t).abs();
            count += 1;
        }
    }
    let mape = (count > 0).then(|| 100.0 * sum_ape / count as f64);
    Ok(TrackingMetrics {
        rmse: mse.sqrt(),
        mape,
        r2: r2_or_exact(target, output),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hand_computed() {
        let t = [0.0, 0.5, 1.0, -1.0];
        let o = [0.1, 0.4, 0.8, -1.0];
        let m = tracking_metrics(&t, &o).unwrap();
        // errors 0.1, 0.1, 0.2, 0: mse = (0.01+0.01+0.04)/4 = 0.015
        assert!((m.rmse - 0.015f64.sqrt()).abs() < 1e-12);
        // |t| >= 0.1: 0.1/0.5, 0.2/1, 0/1 -> (0.2+0.2+0)/3 = 13.333 %
        assert!((m.mape.unwrap() - 40.0 / 3.0).abs() < 1e-9);
        // mean t = 0.125; SS_tot = 0.015625+0.140625+0.765625+1.265625 = 2.1875; SS_res = 0.06
        assert!((m.r2 - (1.0 - 0.06 / 2.1875)).abs() < 1e-12);
    }

    #[test]
    fn no_qualifying_target_gives_no_mape() {
        let m = tracking_metrics(&[0.0, 0.05], &[0.0, 0.0]).unwrap();
        assert_eq!(m.mape, None);
        assert!(tracking_metrics(&[], &[]).is_err());
        assert!(tracking_metrics(&[1.0], &[1.0, 2.0]).is_err());
    }
}
