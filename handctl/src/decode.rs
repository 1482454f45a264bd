//! `handctl decode`: a model run over every window of a session's recording (or of a bare
//! recording file, read with the model's chain), written as CSV
//! (time and the five outputs per window, and the reference signal when the session has one);
//! with a reference, the agreement of the named finger's output (or of every finger's) with
//! it: R² as is and through the best line, RMSE and Pearson r ([`decoder::eval::agreement`]).

use decoder::eval::{agreement, decode, write_csv, Agreement, Decoded};
use decoder::model::TrainedModel;
use decoder::session::{Session, FINGER_NAMES};

use super::args::DecodeArgs;
use super::error::CliError;

/// A finger by name or index 0-4.
fn parse_finger(s: &str) -> Result<usize, CliError> {
    let key = s.trim().to_ascii_lowercase();
    key.parse::<usize>()
        .ok()
        .filter(|&f| f < FINGER_NAMES.len())
        .or_else(|| FINGER_NAMES.iter().position(|n| *n == key))
        .ok_or_else(|| {
            CliError::Usage(format!(
                "--finger {s:?}: not 0-4 or one of {}",
                FINGER_NAMES.join(", ")
            ))
        })
}

/// `handctl decode`.
pub fn run(a: &DecodeArgs) -> Result<(), CliError> {
    let finger = a.finger.as_deref().map(parse_finger).transpose()?;
    let model = TrainedModel::load(&a.model, None)?;
    let path = std::path::Path::new(&a.session);
    let session = if path.is_file() {
        Session::open_recording(path, model.chain())?
    } else {
        Session::open_spec(&a.session)?
    };
    if finger.is_some() && session.reference.is_none() {
        return Err(CliError::Usage(format!(
            "{}: --finger compares an output with the session's reference signal, and this session has none (import it with --reference COLUMN)",
            a.session
        )));
    }
    let windows = session.stream_windows()?;
    let decoded = decode(
        &model,
        &session.meta.chain,
        &windows,
        session.reference.as_ref(),
    )?;
    write_csv(&a.output, &decoded.to_csv())?;
    if !a.json {
        println!(
            "wrote {}: {} windows, {:.3} s to {:.3} s",
            a.output.display(),
            decoded.time_s.len(),
            decoded.time_s.first().copied().unwrap_or(0.0),
            decoded.time_s.last().copied().unwrap_or(0.0)
        );
        println!("{}", envelope_line(&model, &decoded));
    }
    let Some((name, reference)) = &decoded.reference else {
        return Ok(());
    };
    let fingers: Vec<usize> = match finger {
        Some(f) => vec![f],
        None => (0..FINGER_NAMES.len()).collect(),
    };
    let mut rows = Vec::new();
    for f in fingers {
        rows.push((f, agreement(&decoded.finger(f), reference)?));
    }
    if a.json {
        println!("{}", json(name, &rows, &decoded));
    } else {
        print!("{}", table(name, &rows));
    }
    Ok(())
}

/// Beyond the calibration: how many windows the envelope moved back or found implausible,
/// and the outputs' range.
fn envelope_line(model: &TrainedModel, d: &Decoded) -> String {
    let (lo, hi) = d
        .outputs
        .iter()
        .flatten()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(*v), hi.max(*v))
        });
    let range = if lo <= hi {
        format!("outputs from {lo:.3} to {hi:.3}")
    } else {
        "no outputs".into()
    };
    match model.envelope() {
        Some(e) => format!(
            "beyond the calibration: {} windows moved back into its envelope, {} implausible \
             (one channel standing alone, or a shape off the calibration's channel patterns: \
             output rest; {}; {}); {range}",
            d.beyond,
            d.implausible,
            match e.alone() {
                Some(a) => format!("the calibration's channels reached {a:.2}x the next"),
                None => "no channel ratio recorded: the alone test is off".into(),
            },
            match e.cone() {
                Some(c) if c.bar() >= 1.0 => format!(
                    "its windows fit its channel patterns only to {:.2}: the pattern test \
                     cannot fire",
                    c.worst()
                ),
                Some(c) => format!("patterns misfit above {:.3}", c.bar()),
                None => "no channel patterns recorded: the pattern test is off".into(),
            }
        ),
        None => format!(
            "this model file has no calibration envelope (older than format 2's envelope): \
             inputs beyond its calibration reach the model unbounded; {range}"
        ),
    }
}

/// The agreement per finger as text for a technician.
fn table(name: &str, rows: &[(usize, Agreement)]) -> String {
    let opt = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.4}"));
    let mut out = format!(
        "against the reference \"{name}\" (its mean over each window), {} windows:\n\
         finger  r        R² as is  RMSE as is  R² line  RMSE line  line: {name} = slope x output + intercept\n",
        rows.first().map_or(0, |(_, a)| a.n)
    );
    for (f, a) in rows {
        out.push_str(&format!(
            "{:<7} {:<8} {:<9.4} {:<11.4} {:<8} {:<10} {}\n",
            FINGER_NAMES[*f],
            opt(a.pearson),
            a.r2,
            a.rmse,
            opt(a.fit.map(|l| l.r2)),
            opt(a.fit_rmse),
            a.fit.map_or("-".to_string(), |l| format!(
                "slope {:.4}, intercept {:.4}",
                l.slope, l.intercept
            ))
        ));
    }
    out.push_str(
        "R² as is: 1 - SS_res/SS_tot of the output against the reference unscaled; \
         R² line: of the least-squares line (= r²), RMSE in the reference's units\n",
    );
    out
}

/// The agreement per finger as JSON, numbers exact.
fn json(name: &str, rows: &[(usize, Agreement)], decoded: &Decoded) -> serde_json::Value {
    let fingers: Vec<serde_json::Value> = rows
        .iter()
        .map(|(f, a)| {
            serde_json::json!({
                "finger": FINGER_NAMES[*f],
                "windows": a.n,
                "pearson_r": a.pearson,
                "r2": a.r2,
                "rmse": a.rmse,
                "r2_line": a.fit.map(|l| l.r2),
                "rmse_line": a.fit_rmse,
                "slope": a.fit.map(|l| l.slope),
                "intercept": a.fit.map(|l| l.intercept),
            })
        })
        .collect();
    serde_json::json!({
        "reference": name,
        "windows": decoded.time_s.len(),
        "beyond_calibration": decoded.beyond,
        "implausible": decoded.implausible,
        "fingers": fingers,
    })
}
