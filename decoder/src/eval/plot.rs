//! PNG figures: ROC curves and interpolation curves.
//!
//! Text is drawn with a font compiled into the binary (Ubuntu Light from the
//! `epaint_default_fonts` crate, Ubuntu Font Licence), so plotting needs no system fonts,
//! fontconfig or freetype: a headless device or CI machine gets the same figures.

use std::path::Path;
use std::sync::OnceLock;

use plotters::prelude::*;

use super::direction::RocPoint;
use super::error::EvalError;
use super::interpolation::InterpolationCurve;

use hand_dbc::hand::{FINGER_NAMES, N_FINGERS};

const COLOURS: [RGBColor; N_FINGERS] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
];
/// At most this many curves per finger and direction are drawn, so a figure stays legible.
const MAX_CURVES_DRAWN: usize = 40;

fn ensure_font() -> Result<(), String> {
    static FONT: OnceLock<Result<(), String>> = OnceLock::new();
    FONT.get_or_init(|| {
        plotters::style::register_font(
            "sans-serif",
            FontStyle::Normal,
            epaint_default_fonts::UBUNTU_LIGHT,
        )
        .map_err(|_| "the embedded font could not be loaded".to_string())
    })
    .clone()
}

fn plot_err(path: &Path, e: impl std::fmt::Display) -> EvalError {
    EvalError::Plot {
        path: path.display().to_string(),
        message: e.to_string(),
    }
}

/// Writes one ROC figure: a curve per finger (None = finger without data), the chance diagonal.
pub fn roc_png(
    path: &Path,
    title: &str,
    per_finger: &[Option<(&[RocPoint], f64)>],
) -> Result<(), EvalError> {
    ensure_font().map_err(|e| plot_err(path, e))?;
    let root = BitMapBackend::new(path, (640, 600)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| plot_err(path, e))?;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(50)
        .build_cartesian_2d(0f64..1f64, 0f64..1f64)
        .map_err(|e| plot_err(path, e))?;
    chart
        .configure_mesh()
        .x_desc("false positive rate (extension scored as flexion)")
        .y_desc("true positive rate")
        .draw()
        .map_err(|e| plot_err(path, e))?;
    chart
        .draw_series(DashedLineSeries::new(
            [(0.0, 0.0), (1.0, 1.0)],
            6,
            4,
            BLACK.mix(0.4).into(),
        ))
        .map_err(|e| plot_err(path, e))?;
    for (f, entry) in per_finger.iter().enumerate() {
        let Some((roc, auc)) = entry else { continue };
        let colour = COLOURS[f % COLOURS.len()];
        chart
            .draw_series(LineSeries::new(
                roc.iter().map(|p| (p.fpr, p.tpr)),
                colour.stroke_width(2),
            ))
            .map_err(|e| plot_err(path, e))?
            .label(format!(
                "{} (AUC {auc:.3})",
                FINGER_NAMES.get(f).unwrap_or(&"?")
            ))
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 16, y)], colour.stroke_width(2))
            });
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::LowerRight)
        .background_style(WHITE.mix(0.9))
        .border_style(BLACK)
        .draw()
        .map_err(|e| plot_err(path, e))?;
    root.present().map_err(|e| plot_err(path, e))
}

/// Writes one interpolation figure for a model: a panel per finger with a sample of the
/// flexion (solid) and extension curves, their means (thick) and the ideal `s·k` (dashed).
pub fn interpolation_png(
    path: &Path,
    title: &str,
    levels: &[f64],
    curves: &[InterpolationCurve],
) -> Result<(), EvalError> {
    ensure_font().map_err(|e| plot_err(path, e))?;
    let root = BitMapBackend::new(path, (1500, 420)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| plot_err(path, e))?;
    let root = root
        .titled(title, ("sans-serif", 22))
        .map_err(|e| plot_err(path, e))?;
    let (lo, hi) = curves
        .iter()
        .flat_map(|c| c.outputs.iter())
        .fold((-1.2f64, 1.2f64), |(lo, hi), &v| (lo.min(v), hi.max(v)));
    let panels = root.split_evenly((1, N_FINGERS));
    for (f, panel) in panels.iter().enumerate() {
        let mut chart = ChartBuilder::on(panel)
            .caption(FINGER_NAMES[f], ("sans-serif", 18))
            .margin(8)
            .x_label_area_size(32)
            .y_label_area_size(42)
            .build_cartesian_2d(0f64..1f64, lo..hi)
            .map_err(|e| plot_err(path, e))?;
        chart
            .configure_mesh()
            .x_desc("effort k")
            .y_desc("output")
            .max_light_lines(2)
            .draw()
            .map_err(|e| plot_err(path, e))?;
        for sign in [1.0, -1.0] {
            let colour = if sign > 0.0 { COLOURS[0] } else { COLOURS[1] };
            let mine: Vec<&InterpolationCurve> = curves
                .iter()
                .filter(|c| c.finger == f && c.sign == sign)
                .collect();
            chart
                .draw_series(DashedLineSeries::new(
                    levels.iter().map(|&k| (k, sign * k)),
                    5,
                    4,
                    BLACK.mix(0.6).into(),
                ))
                .map_err(|e| plot_err(path, e))?;
            if mine.is_empty() {
                continue;
            }
            let stride = mine.len().div_ceil(MAX_CURVES_DRAWN).max(1);
            for c in mine.iter().step_by(stride) {
                let style = if c.failed {
                    RED.mix(0.5).stroke_width(1)
                } else {
                    colour.mix(0.25).stroke_width(1)
                };
                chart
                    .draw_series(LineSeries::new(
                        levels.iter().copied().zip(c.outputs.iter().copied()),
                        style,
                    ))
                    .map_err(|e| plot_err(path, e))?;
            }
            let mean: Vec<(f64, f64)> = levels
                .iter()
                .enumerate()
                .map(|(i, &k)| {
                    (
                        k,
                        mine.iter().map(|c| c.outputs[i]).sum::<f64>() / mine.len() as f64,
                    )
                })
                .collect();
            chart
                .draw_series(LineSeries::new(mean, colour.stroke_width(3)))
                .map_err(|e| plot_err(path, e))?;
        }
    }
    root.present().map_err(|e| plot_err(path, e))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::eval::interpolation::judge_curve;

    fn png_ok(path: &Path) {
        let bytes = std::fs::read(path).unwrap();
        assert!(
            bytes.len() > 1000,
            "{} is only {} bytes",
            path.display(),
            bytes.len()
        );
        assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
    }

    #[test]
    fn writes_real_png_files() {
        let dir = std::env::temp_dir().join(format!("handstack-plot-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let roc = [
            RocPoint { fpr: 0.0, tpr: 0.0 },
            RocPoint { fpr: 0.1, tpr: 0.8 },
            RocPoint { fpr: 1.0, tpr: 1.0 },
        ];
        let p = dir.join("roc.png");
        roc_png(
            &p,
            "ROC test",
            &[Some((&roc, 0.85)), None, Some((&roc, 0.85)), None, None],
        )
        .unwrap();
        png_ok(&p);
        let levels: Vec<f64> = (0..=20).map(|i| i as f64 * 0.05).collect();
        let mut curves = Vec::new();
        for f in 0..5 {
            for s in [1.0, -1.0] {
                let out: Vec<f64> = levels
                    .iter()
                    .map(|k| s * k * (1.0 + 0.1 * f as f64))
                    .collect();
                curves.push(judge_curve(f, s, &levels, out, 0.01).unwrap());
            }
        }
        let p = dir.join("interp.png");
        interpolation_png(&p, "interpolation test", &levels, &curves).unwrap();
        png_ok(&p);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn unwritable_path_is_an_error() {
        let p = Path::new("/nonexistent-dir-handstack/x.png");
        assert!(matches!(roc_png(p, "x", &[]), Err(EvalError::Plot { .. })));
    }
}
