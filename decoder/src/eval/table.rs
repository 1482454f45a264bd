//! The paper's tables as plain text.

use std::fmt::Write;

use super::evaluate::ModelEvaluation;

use hand_dbc::hand::FINGER_NAMES as FINGERS;

/// Table 3: per finger and model, direction AUC ± Hanley-McNeil SE and sign accuracy.
pub fn direction_table(evals: &[ModelEvaluation]) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "Table 3: direction AUC ± SE (sign accuracy) per finger");
    let _ = write!(s, "{:<7}", "model");
    for f in FINGERS {
        let _ = write!(s, " {f:>22}");
    }
    let _ = writeln!(s);
    for e in evals {
        let _ = write!(s, "{:<7}", e.kind.name());
        for d in &e.direction {
            let cell = match d {
                Some(d) => format!("{:.3}±{:.3} ({:5.1}%)", d.auc, d.auc_se, 100.0 * d.accuracy),
                None => "no data".to_string(),
            };
            let _ = write!(s, " {cell:>22}");
        }
        let _ = writeln!(s);
    }
    if let Some((p, n)) = evals
        .iter()
        .flat_map(|e| e.direction.iter().flatten())
        .map(|d| (d.n_pos, d.n_neg))
        .next()
    {
        let _ = writeln!(
            s,
            "(first finger with data: {p} flexion and {n} extension windows)"
        );
    }
    s
}

/// Table 4: per model, interpolation failures, correct rate, mean Spearman rho and mean
/// linear-fit R², over all fingers' curves; plus the mean |output| at rest.
pub fn interpolation_table(evals: &[ModelEvaluation], tolerance: f64) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "Table 4: interpolation (k = 0..1, step 0.05; a curve fails when it is monotonic in neither direction beyond {tolerance})"
    );
    let _ = writeln!(
        s,
        "{:<7} {:>7} {:>9} {:>12} {:>10} {:>8} {:>9} {:>10}",
        "model", "curves", "failures", "correct", "spearman", "R²", "constant", "rest|y|"
    );
    for e in evals {
        let t = &e.interpolation_total;
        let rest = e
            .rest_mean_abs
            .map_or("-".to_string(), |v| format!("{v:.3}"));
        let _ = writeln!(
            s,
            "{:<7} {:>7} {:>9} {:>12} {:>10.3} {:>8.3} {:>9} {:>10}",
            e.kind.name(),
            t.curves,
            t.failures,
            format!("{} {:.1}%", t.correct, 100.0 * t.correct_rate()),
            t.mean_spearman,
            t.mean_r2,
            t.constant,
            rest
        );
    }
    let _ = writeln!(s, "Per finger: failures / curves, correct rate");
    let _ = write!(s, "{:<7}", "model");
    for f in FINGERS {
        let _ = write!(s, " {f:>17}");
    }
    let _ = writeln!(s);
    for e in evals {
        let _ = write!(s, "{:<7}", e.kind.name());
        for i in &e.interpolation {
            let cell = if i.curves == 0 {
                "no data".to_string()
            } else {
                format!(
                    "{}/{} {:5.1}%",
                    i.failures,
                    i.curves,
                    100.0 * i.correct_rate()
                )
            };
            let _ = write!(s, " {cell:>17}");
        }
        let _ = writeln!(s);
    }
    s
}
