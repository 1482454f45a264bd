//! `handctl eval`: train every named model on one session, score all on held-out data, print
//! the paper's tables and write the curves as CSV, and as PNG figures with the `plots` feature
//! (the daemon's build links no plotting stack). With `--model FILE`, no training: the saved
//! model is scored on every window of the session named, by the same code, and its effort rays
//! on that session are verified.

use std::path::Path;

use decoder::eval::{
    direction_table, evaluate_model, interpolation_csv, interpolation_table, roc_csv, stress,
    stress_table, stress_transients, write_csv, InterpolationConfig, ModelEvaluation, StressReport,
    StressRow, TRANSIENT_GAIN, TRANSIENT_MS,
};
use decoder::model::verify::{describe_verification, DEFAULT_TOLERANCE};
use decoder::model::TrainedModel;
use decoder::session::{LabelledWindows, Session, WindowOptions};

use super::args::EvalArgs;
use super::error::CliError;
use super::train::{describe, fit, gate, window_options};

/// Train and test windows: a separate test session, or the held-out last repetitions.
fn split(
    a: &EvalArgs,
    session: &Session,
    opts: &WindowOptions,
) -> Result<(LabelledWindows, LabelledWindows, String), CliError> {
    let all = session.windows(opts)?;
    match &a.test {
        Some(spec) => {
            let test = Session::open_spec(spec)?;
            if test.meta.chain != session.meta.chain {
                return Err(CliError::Usage(format!(
                    "{spec}: its [chain] differs from the training session's; features would not be comparable"
                )));
            }
            // Testing always includes rest (to measure rest drift) even for a two-point model.
            let test_windows = test.windows(&WindowOptions::default())?;
            Ok((
                all,
                test_windows,
                format!("trained on {}, tested on {spec}", a.session),
            ))
        }
        None => {
            let held = session.holdout_last_repetition();
            if !held.iter().any(|&h| h) {
                return Err(CliError::Usage(format!(
                    "{}: no trial kind has two repetitions to hold one out; pass --test SESSION",
                    a.session
                )));
            }
            let train = all.filter_trials(|t| !held[t]);
            let test = session
                .windows(&WindowOptions::default())?
                .filter_trials(|t| held[t]);
            Ok((
                train,
                test,
                format!(
                    "{}: trained on the first repetitions, tested on the last",
                    a.session
                ),
            ))
        }
    }
}

/// Creates the `--plots` directory, if one was asked for.
fn plots_dir(a: &EvalArgs) -> Result<(), CliError> {
    if let Some(dir) = &a.plots {
        std::fs::create_dir_all(dir).map_err(|source| CliError::Io {
            path: dir.display().to_string(),
            source,
        })?;
    }
    Ok(())
}

/// Scores `model` on `test`, writing its curves with `--plots`: the one scoring path of both
/// forms of `handctl eval`.
fn score(
    a: &EvalArgs,
    model: &TrainedModel,
    test: &LabelledWindows,
    icfg: &InterpolationConfig,
) -> Result<ModelEvaluation, CliError> {
    let e = evaluate_model(model, test, icfg)?;
    if let Some(dir) = &a.plots {
        write_plots(dir, &e)?;
    }
    Ok(e)
}

/// Tables 3 and 4 of `evals`, and where the curves went.
fn print_tables(a: &EvalArgs, evals: &[ModelEvaluation], icfg: &InterpolationConfig) {
    println!();
    print!("{}", direction_table(evals));
    println!();
    print!("{}", interpolation_table(evals, icfg.tolerance));
    if let Some(dir) = &a.plots {
        println!("\n{} in {}", FIGURES, dir.display());
    }
}

/// `handctl eval --model FILE SESSION`: the saved model scored on every window of SESSION
/// (rest included), nothing trained; then its effort rays on SESSION verified.
fn run_saved(a: &EvalArgs, path: &Path) -> Result<(), CliError> {
    let session = Session::open_spec(&a.session)?;
    gate(&session, &a.training)?;
    let model = TrainedModel::load(path, Some(&session.meta.chain))?;
    plots_dir(a)?;
    let test = session.windows(&WindowOptions::default())?;
    println!(
        "{} model {} scored on all {} windows of {}, nothing trained",
        model.summary().kind,
        path.display(),
        test.len(),
        a.session
    );
    println!(
        "its file records: {}",
        describe_verification(model.verification())
    );
    let icfg = InterpolationConfig::default();
    let e = score(a, &model, &test, &icfg)?;
    let reports = vec![(
        model.summary().kind.name().to_string(),
        stress(&model, &test),
    )];
    let transients = if a.stress {
        vec![stress_transients(&model, &session)?]
    } else {
        Vec::new()
    };
    print_tables(a, &[e], &icfg);
    print_robustness(a, &reports, &transients);
    let (r, beyond) = super::verify::report(&model, &session, &test, DEFAULT_TOLERANCE)?;
    println!("\nEffort rays of {}:", a.session);
    print!("{r}");
    print!("{beyond}");
    Ok(())
}

/// `handctl eval`.
pub fn run(a: &EvalArgs) -> Result<(), CliError> {
    if let Some(path) = &a.model {
        return run_saved(a, path);
    }
    let session = Session::open_spec(&a.session)?;
    gate(&session, &a.training)?;
    let opts = window_options(&a.training);
    let (train_w, test_w, what) = split(a, &session, &opts)?;
    let data = train_w.to_dataset(&session.meta.chain)?;
    plots_dir(a)?;
    println!(
        "{what}; {} training windows, {} test windows{}",
        train_w.len(),
        test_w.len(),
        if a.training.two_point {
            "; two-point calibration (no rest)"
        } else {
            ""
        }
    );
    let icfg = InterpolationConfig::default();
    // The transients go into a test recording's signal: a separate test session only.
    let test_session = match (&a.test, a.stress) {
        (Some(spec), true) => Some(Session::open_spec(spec)?),
        _ => None,
    };
    let mut evals: Vec<ModelEvaluation> = Vec::new();
    let mut reports = Vec::new();
    let mut transients = Vec::new();
    for &kind in &a.models {
        let model = fit(kind, &data, &a.training)?;
        println!("trained {}", describe(&model));
        evals.push(score(a, &model, &test_w, &icfg)?);
        reports.push((kind.name().to_string(), stress(&model, &test_w)));
        if let Some(ts) = &test_session {
            transients.push(stress_transients(&model, ts)?);
        }
    }
    print_tables(a, &evals, &icfg);
    print_robustness(a, &reports, &transients);
    if a.stress && test_session.is_none() {
        println!("(transients in the signal need a test session: --test)");
    }
    Ok(())
}

/// Beyond the calibration (issue 25): per model, the test windows the envelope moved back or
/// found implausible and the raw output's range; with `--stress`, the stress table.
fn print_robustness(a: &EvalArgs, reports: &[(String, StressReport)], transients: &[StressRow]) {
    println!("\nBeyond the calibration, on the test windows as recorded:");
    for (name, r) in reports {
        let x1 = &r.gains[0];
        println!(
            "  {name}: {} of {} windows beyond the calibration's envelope (moved back), {} \
             implausible (rest); raw output in [{:.3}, {:.3}]",
            x1.beyond, x1.windows, x1.implausible, x1.range.0, x1.range.1
        );
    }
    if a.stress {
        println!();
        print!("{}", stress_table(reports));
    }
    if !transients.is_empty() {
        println!(
            "\nTransients in the signal: one channel at x{TRANSIENT_GAIN} for {TRANSIENT_MS} ms in \
             the middle of every movement trial, the windows overlapping one (worst channel):"
        );
    }
    for ((name, _), r) in reports.iter().zip(transients) {
        println!(
            "  {name}: {:.2}% of {} movement finger-windows the wrong way, |y| up to {:.3}, {} \
             of {} windows implausible (rest); {}",
            r.wrong_percent(),
            r.movement,
            r.max_abs,
            r.implausible,
            r.windows,
            r.condition
        );
    }
}

/// What `--plots` writes in this build.
#[cfg(feature = "plots")]
const FIGURES: &str = "curves (CSV) and figures (PNG)";
#[cfg(not(feature = "plots"))]
const FIGURES: &str = "curves as CSV (PNG figures need handctl built with --features plots)";

/// The curves as CSV always; the PNG figures with the `plots` feature.
fn write_plots(dir: &Path, e: &ModelEvaluation) -> Result<(), CliError> {
    let name = e.kind.name();
    let roc: Vec<_> = e
        .direction
        .iter()
        .map(|d| d.as_ref().map(|d| (d.roc.as_slice(), d.auc)))
        .collect();
    write_csv(&dir.join(format!("roc_{name}.csv")), &roc_csv(&roc))?;
    write_csv(
        &dir.join(format!("interpolation_{name}.csv")),
        &interpolation_csv(&e.levels, &e.curves),
    )?;
    #[cfg(feature = "plots")]
    {
        decoder::eval::roc_png(
            &dir.join(format!("roc_{name}.png")),
            &format!("{name}: direction ROC per finger"),
            &roc,
        )?;
        decoder::eval::interpolation_png(
            &dir.join(format!("interpolation_{name}.png")),
            &format!("{name}: output against effort k (dashed: ideal s·k; red: failed curves)"),
            &e.levels,
            &e.curves,
        )?;
    }
    Ok(())
}
