//! The evaluation's curves as CSV: what the PNG figures draw, for builds without the `plots`
//! feature (the daemon's machine) and for any other plotting tool.

use std::fmt::Write as _;
use std::path::Path;

use super::direction::RocPoint;
use super::error::EvalError;
use super::interpolation::InterpolationCurve;

/// The ROC curves as `finger,auc,fpr,tpr` rows (one per curve point; fingers without data
/// have no rows).
pub fn roc_csv(per_finger: &[Option<(&[RocPoint], f64)>]) -> String {
    let mut out = String::from("finger,auc,fpr,tpr\n");
    for (f, curve) in per_finger.iter().enumerate() {
        let Some((points, auc)) = curve else { continue };
        for p in points.iter() {
            // Writing into a String cannot fail.
            let _ = writeln!(out, "{f},{auc},{},{}", p.fpr, p.tpr);
        }
    }
    out
}

/// The interpolation curves as `curve,finger,sign,failed,correct,level,output` rows (one per
/// curve and effort level).
pub fn interpolation_csv(levels: &[f64], curves: &[InterpolationCurve]) -> String {
    let mut out = String::from("curve,finger,sign,failed,correct,level,output\n");
    for (i, c) in curves.iter().enumerate() {
        for (k, y) in levels.iter().zip(&c.outputs) {
            let _ = writeln!(
                out,
                "{i},{},{},{},{},{k},{y}",
                c.finger, c.sign, c.failed, c.correct
            );
        }
    }
    out
}

/// Writes `text` to `path`.
pub fn write_csv(path: &Path, text: &str) -> Result<(), EvalError> {
    std::fs::write(path, text).map_err(|source| EvalError::Write {
        path: path.display().to_string(),
        source,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_per_point_and_level() {
        let roc = [
            RocPoint { fpr: 0.0, tpr: 0.5 },
            RocPoint { fpr: 1.0, tpr: 1.0 },
        ];
        let text = roc_csv(&[None, Some((&roc, 0.75))]);
        assert_eq!(text, "finger,auc,fpr,tpr\n1,0.75,0,0.5\n1,0.75,1,1\n");
        let curve = InterpolationCurve {
            finger: 2,
            sign: -1.0,
            outputs: vec![0.0, -0.5],
            failed: false,
            correct: true,
            spearman: Some(1.0),
            r2: 1.0,
        };
        let text = interpolation_csv(&[0.0, 1.0], &[curve]);
        assert_eq!(
            text,
            "curve,finger,sign,failed,correct,level,output\n0,2,-1,false,true,0,0\n0,2,-1,false,true,1,-0.5\n"
        );
    }
}
