//! How well one finger's output follows a reference signal (force, angle) recorded beside the
//! EMG: what `handctl decode` prints for a session with a reference.
//!
//! The output is in label units (full effort 1) and the reference in its own (newtons,
//! degrees), so two readings are given:
//!
//! * **As is**: `R² = 1 - SS_res / SS_tot` and the RMSE of the output against the reference
//!   with no scaling (`SS_res = Σ (ref - out)²`, `SS_tot = Σ (ref - mean ref)²`). Meaningful
//!   when the reference is in label units (a normalised force); hugely negative otherwise.
//! * **Through the best line**: the least-squares line `ref ≈ slope · out + intercept`, its
//!   `R²` (equal to Pearson r²) and RMSE in the reference's units: how much of the reference
//!   the output explains once its scale is calibrated, which is what a technician checks.
//!
//! And Pearson r. A constant output or reference leaves r and the line undefined (`None`).

use super::error::{check_pair, EvalError};
use super::stats::{linear_fit, pearson, r2_or_exact, LinearFit};

/// Agreement of an output with its reference.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Agreement {
    /// Number of windows compared.
    pub n: usize,
    /// `1 - SS_res / SS_tot` of the output against the reference as is.
    pub r2: f64,
    /// RMSE of the output against the reference as is (reference units).
    pub rmse: f64,
    /// Pearson correlation (`None` when either is constant).
    pub pearson: Option<f64>,
    /// The least-squares line `reference ≈ slope · output + intercept` and its R² (`None` when
    /// the output is constant).
    pub fit: Option<LinearFit>,
    /// RMSE of the reference about that line (reference units).
    pub fit_rmse: Option<f64>,
}

fn rmse(target: &[f64], pred: &[f64]) -> f64 {
    let ss: f64 = target
        .iter()
        .zip(pred)
        .map(|(t, p)| (t - p) * (t - p))
        .sum();
    (ss / target.len() as f64).sqrt()
}

/// Agreement of `output` with `reference` (one value per window each).
pub fn agreement(output: &[f64], reference: &[f64]) -> Result<Agreement, EvalError> {
    check_pair("reference agreement", output, reference)?;
    if output.len() < 2 {
        return Err(EvalError::NotEnoughData(
            "reference agreement: fewer than 2 windows".into(),
        ));
    }
    // Equal values whose mean is not representable would leave rounding-sized deviations and a
    // meaningless r: constancy is decided on the values themselves.
    let constant = |v: &[f64]| v.iter().all(|&x| x == v[0]);
    let fit = (!constant(output))
        .then(|| linear_fit(output, reference).ok())
        .flatten();
    let fit_rmse = fit.map(|f| {
        let line: Vec<f64> = output.iter().map(|o| f.slope * o + f.intercept).collect();
        rmse(reference, &line)
    });
    Ok(Agreement {
        n: output.len(),
        r2: r2_or_exact(reference, output),
        rmse: rmse(reference, output),
        pearson: (!constant(output) && !constant(reference))
            .then(|| pearson(output, reference).ok())
            .flatten(),
        fit,
        fit_rmse,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hand_computed() {
        // ref = 10 out + 5 exactly: the line explains everything, the raw R² does not.
        let out = [0.0, 0.5, 1.0];
        let reference = [5.0, 10.0, 15.0];
        let a = agreement(&out, &reference).unwrap();
        assert!((a.pearson.unwrap() - 1.0).abs() < 1e-12);
        let f = a.fit.unwrap();
        assert!((f.slope - 10.0).abs() < 1e-12 && (f.intercept - 5.0).abs() < 1e-12);
        assert!((f.r2 - 1.0).abs() < 1e-12 && a.fit_rmse.unwrap() < 1e-12);
        // SS_tot = 50; residuals 5, 9.5, 14: SS_res = 25 + 90.25 + 196 = 311.25.
        assert!((a.r2 - (1.0 - 311.25 / 50.0)).abs() < 1e-12);
        assert!((a.rmse - (311.25f64 / 3.0).sqrt()).abs() < 1e-12);
    }

    #[test]
    fn a_constant_output_has_no_correlation_but_a_raw_r2() {
        let a = agreement(&[0.2, 0.2, 0.2], &[1.0, 2.0, 3.0]).unwrap();
        assert_eq!((a.pearson, a.fit, a.fit_rmse), (None, None, None));
        assert!(a.r2 < 0.0);
        let a = agreement(&[0.1, 0.2, 0.3], &[4.0, 4.0, 4.0]).unwrap();
        assert_eq!(a.pearson, None);
        assert!(agreement(&[1.0], &[1.0]).is_err());
        assert!(agreement(&[1.0, 2.0], &[1.0]).is_err());
    }
}
