//! Direction metrics (the paper's Table 3): does a finger's output tell flexion from extension?
//!
//! The score is the model's continuous output for the finger; positives are flexion windows
//! (target +1), negatives extension windows (target -1). The AUC is the Mann-Whitney statistic
//! with ties counted as one half, its standard error is Hanley and McNeil's (1982), and the
//! accuracy counts windows whose output has the trial's sign (an output of exactly zero is wrong
//! for both directions).

use super::error::{check_pair, EvalError};
use super::stats::average_ranks;

/// One point of an ROC curve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RocPoint {
    /// False positive rate (extension windows scored at or above the threshold).
    pub fpr: f64,
    /// True positive rate (flexion windows scored at or above the threshold).
    pub tpr: f64,
}

/// The direction figures of one finger.
#[derive(Debug, Clone, PartialEq)]
pub struct DirectionMetrics {
    /// Area under the ROC curve.
    pub auc: f64,
    /// Hanley-McNeil standard error of the AUC.
    pub auc_se: f64,
    /// Fraction of windows whose output sign equals the trial's direction.
    pub accuracy: f64,
    /// Number of flexion (positive) windows.
    pub n_pos: usize,
    /// Number of extension (negative) windows.
    pub n_neg: usize,
    /// The ROC curve from (0, 0) to (1, 1), one point per distinct score.
    pub roc: Vec<RocPoint>,
}

/// AUC by the Mann-Whitney U statistic: `(R_pos - n_pos (n_pos + 1) / 2) / (n_pos n_neg)` with
/// average ranks, which counts a tied positive/negative pair as one half.
pub fn auc(scores: &[f64], positive: &[bool]) -> Result<f64, EvalError> {
    let (n_pos, n_neg) = class_counts(scores, positive)?;
    let ranks = average_ranks(scores);
    let r_pos: f64 = ranks
        .iter()
        .zip(positive)
        .filter(|(_, &p)| p)
        .map(|(r, _)| r)
        .sum();
    let np = n_pos as f64;
    Ok((r_pos - np * (np + 1.0) / 2.0) / (np * n_neg as f64))
}

/// Hanley-McNeil standard error of an AUC `a` from `n_pos` positives and `n_neg` negatives.
pub fn hanley_mcneil_se(a: f64, n_pos: usize, n_neg: usize) -> f64 {
    let q1 = a / (2.0 - a);
    let q2 = 2.0 * a * a / (1.0 + a);
    let (np, nn) = (n_pos as f64, n_neg as f64);
    let var = (a * (1.0 - a) + (np - 1.0) * (q1 - a * a) + (nn - 1.0) * (q2 - a * a)) / (np * nn);
    var.max(0.0).sqrt()
}

/// The ROC curve: thresholds at every distinct score from high to low, tied scores moving
/// together (a diagonal step), starting at (0, 0) and ending at (1, 1).
pub fn roc_curve(scores: &[f64], positive: &[bool]) -> Result<Vec<RocPoint>, EvalError> {
    let (n_pos, n_neg) = class_counts(scores, positive)?;
    let mut order: Vec<usize> = (0..scores.len()).collect();
    order.sort_by(|&a, &b| scores[b].total_cmp(&scores[a]));
    let mut points = vec![RocPoint { fpr: 0.0, tpr: 0.0 }];
    let (mut tp, mut fp) = (0usize, 0usize);
    let mut i = 0;
    while i < order.len() {
        let s = scores[order[i]];
        while i < order.len() && scores[order[i]] == s {
            if positive[order[i]] {
                tp += 1;
            } else {
                fp += 1;
            }
            i += 1;
        }
        points.push(RocPoint {
            fpr: fp as f64 / n_neg as f64,
            tpr: tp as f64 / n_pos as f64,
        });
    }
    Ok(points)
}

/// Fraction of windows with `output > 0` for positives and `output < 0` for negatives.
pub fn sign_accuracy(scores: &[f64], positive: &[bool]) -> Result<f64, EvalError> {
    class_counts(scores, positive)?;
    let right = scores
        .iter()
        .zip(positive)
        .filter(|(s, &p)| if p { **s > 0.0 } else { **s < 0.0 })
        .count();
    Ok(right as f64 / scores.len() as f64)
}

/// All direction figures of one finger.
pub fn direction_metrics(scores: &[f64], positive: &[bool]) -> Result<DirectionMetrics, EvalError> {
    let (n_pos, n_neg) = class_counts(scores, positive)?;
    let a = auc(scores, positive)?;
    Ok(DirectionMetrics {
        auc: a,
        auc_se: hanley_mcneil_se(a, n_pos, n_neg),
        accuracy: sign_accuracy(scores, positive)?,
        n_pos,
        n_neg,
        roc: roc_curve(scores, positive)?,
    })
}

fn class_counts(scores: &[f64], positive: &[bool]) -> Result<(usize, usize), EvalError> {
    if scores.len() != positive.len() {
        return Err(EvalError::LengthMismatch {
            what: "direction metrics",
            left: scores.len(),
            right: positive.len(),
        });
    }
    check_pair("direction metrics", scores, scores)?;
    let n_pos = positive.iter().filter(|&&p| p).count();
    let n_neg = positive.len() - n_pos;
    if n_pos == 0 || n_neg == 0 {
        return Err(EvalError::NotEnoughData(format!(
            "direction metrics need flexion and extension windows, got {n_pos} flexion and {n_neg} extension"
        )));
    }
    Ok((n_pos, n_neg))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn auc_hand_computed_with_a_tie() {
        // Positives 0.9, 0.5; negatives 0.5, 0.1. Pairs: (0.9>0.5)=1, (0.9>0.1)=1,
        // (0.5=0.5)=0.5, (0.5>0.1)=1 -> 3.5 / 4.
        let s = [0.9, 0.5, 0.5, 0.1];
        let p = [true, true, false, false];
        assert!((auc(&s, &p).unwrap() - 0.875).abs() < 1e-12);
    }

    #[test]
    fn auc_extremes() {
        let p = [true, true, false, false];
        assert_eq!(auc(&[2.0, 3.0, -1.0, -2.0], &p).unwrap(), 1.0);
        assert_eq!(auc(&[-2.0, -3.0, 1.0, 2.0], &p).unwrap(), 0.0);
        assert_eq!(auc(&[0.0; 4], &p).unwrap(), 0.5);
    }

    #[test]
    fn hanley_mcneil_hand_computed() {
        // A = 0.8, n1 = 10, n2 = 20: Q1 = 0.8/1.2 = 2/3, Q2 = 1.28/1.8 = 0.71111..;
        // var = (0.16 + 9*(2/3-0.64) + 19*(0.711111-0.64)) / 200
        //     = (0.16 + 0.24 + 1.351111) / 200 = 0.0087555..; SE = 0.093571..
        let se = hanley_mcneil_se(0.8, 10, 20);
        let q2: f64 = 1.28 / 1.8;
        let var: f64 = (0.16 + 9.0 * (2.0 / 3.0 - 0.64) + 19.0 * (q2 - 0.64)) / 200.0;
        assert!((se - var.sqrt()).abs() < 1e-12);
        assert!((se - 0.09357).abs() < 1e-4);
        assert_eq!(hanley_mcneil_se(1.0, 10, 10), 0.0);
    }

    #[test]
    fn roc_curve_hand_computed() {
        let s = [0.9, 0.5, 0.5, 0.1];
        let p = [true, true, false, false];
        let roc = roc_curve(&s, &p).unwrap();
        let want = [(0.0, 0.0), (0.0, 0.5), (0.5, 1.0), (1.0, 1.0)];
        assert_eq!(roc.len(), want.len());
        for (r, (f, t)) in roc.iter().zip(want) {
            assert!(
                (r.fpr - f).abs() < 1e-12 && (r.tpr - t).abs() < 1e-12,
                "{roc:?}"
            );
        }
        // Trapezoids under the curve equal the Mann-Whitney AUC.
        let area: f64 = roc
            .windows(2)
            .map(|w| (w[1].fpr - w[0].fpr) * (w[1].tpr + w[0].tpr) / 2.0)
            .sum();
        assert!((area - auc(&s, &p).unwrap()).abs() < 1e-12);
    }

    #[test]
    fn sign_accuracy_counts_zero_as_wrong() {
        let s = [0.3, 0.0, -0.2, 0.1];
        let p = [true, true, false, false];
        assert_eq!(sign_accuracy(&s, &p).unwrap(), 0.5);
    }

    #[test]
    fn one_class_or_bad_input_is_an_error() {
        assert!(auc(&[1.0, 2.0], &[true, true]).is_err());
        assert!(auc(&[1.0, f64::NAN], &[true, false]).is_err());
        assert!(auc(&[1.0], &[true, false]).is_err());
        let m = direction_metrics(&[1.0, -1.0], &[true, false]).unwrap();
        assert_eq!((m.auc, m.accuracy, m.n_pos, m.n_neg), (1.0, 1.0, 1, 1));
    }
}
