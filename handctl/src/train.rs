//! `handctl train` and `handctl check`.

use decoder::model::provenance::{describe_provenance, utc_now};
use decoder::model::{train, Dataset, ModelKind, ModelSpec, Provenance, TrainConfig, TrainedModel};
use decoder::session::{
    check_gates, GateConfig, GateReport, LabelledWindows, Session, WindowOptions,
};

use super::args::{CheckArgs, TrainArgs, TrainingOpts};
use super::error::CliError;
use super::progress::Progress;

/// Runs the quality gates, printing the report to stderr; an error when they fail and the
/// user did not say to go on anyway. Returns the findings bypassed (`--ignore-gates`), for the
/// model file's provenance.
pub(super) fn gate(session: &Session, opts: &TrainingOpts) -> Result<Vec<String>, CliError> {
    let report = check_gates(session, &GateConfig::default())?;
    if report.passed() {
        for n in &report.notes {
            eprintln!("{}: note: {n}", session.name.display());
        }
        return Ok(Vec::new());
    }
    eprint!("{}: quality gates:\n{report}", session.name.display());
    overrule(&report, opts)
}

/// Whether training may go on despite the gates' `report` (which did not pass): only with
/// `--ignore-gates`, and a finger moved in one direction only also needs
/// `--allow-one-direction` (see [`decoder::session::GateKind::can_be_ignored`]). Returns the
/// findings bypassed, for the model file's provenance.
pub(crate) fn overrule(report: &GateReport, opts: &TrainingOpts) -> Result<Vec<String>, CliError> {
    let binding = report.binding().count();
    if binding > 0 && !opts.allow_one_direction {
        return Err(CliError::OneDirection(binding));
    }
    if binding > 0 {
        eprintln!("--allow-one-direction: {binding} finger(s) trained in one direction only");
    }
    if report.issues.len() == binding {
        // Nothing `--ignore-gates` bypassed (the file records no gate bypass).
        return Ok(Vec::new());
    }
    if opts.ignore_gates {
        eprintln!("--ignore-gates: training anyway (the model file records the findings bypassed)");
        Ok(report.issues.iter().map(|i| i.message.clone()).collect())
    } else {
        Err(CliError::Gates(report.issues.len() - binding))
    }
}

/// The session's id for the model file: the session directory's name, or the spec as given
/// for a session that is not a directory (`3dc:DIR:train`), at most
/// [`decoder::model::provenance::MAX_SESSION_ID`] characters.
pub(super) fn session_id(spec: &str) -> String {
    std::fs::canonicalize(spec)
        .ok()
        .filter(|d| d.is_dir())
        .and_then(|d| d.file_name().map(|n| n.to_string_lossy().into_owned()))
        .unwrap_or_else(|| spec.to_owned())
        .chars()
        .filter(|c| !c.is_control())
        .take(decoder::model::provenance::MAX_SESSION_ID)
        .collect()
}

/// The provenance recorded in the model file: `patient` (from `--patient`), the session's id,
/// the calibration date (when the session was recorded, `recorded`; now when the session
/// records none, as an imported recording does: said on stderr), and the gate findings
/// training went past. Says on stderr when no patient is recorded.
pub(super) fn provenance(
    patient: Option<&str>,
    session: String,
    recorded: Option<&str>,
    opts: &TrainingOpts,
    gates_bypassed: Vec<String>,
) -> Provenance {
    let calibrated_utc = recorded.map_or_else(
        || {
            eprintln!(
                "the session records no date (session.toml's recorded_utc): the model file \
                 gives today's as the calibration date"
            );
            utc_now()
        },
        str::to_owned,
    );
    if patient.is_none() {
        eprintln!(
            "no --patient: the model file records no patient id (\"unknown patient\"); \
             handctl deploy asks before it replaces a running model with it"
        );
    }
    Provenance {
        patient: patient.map(str::to_owned),
        session,
        calibrated_utc,
        ignore_gates: opts.ignore_gates,
        gates_bypassed,
    }
}

/// How the training windows are labelled, from the CLI's flags.
pub(super) fn window_options(opts: &TrainingOpts) -> WindowOptions {
    WindowOptions {
        two_point: opts.two_point,
        mask_others: opts.paper_masks,
    }
}

/// Trains one model with the CLI's settings, showing progress on a terminal.
pub(super) fn fit(
    kind: ModelKind,
    data: &Dataset,
    opts: &TrainingOpts,
) -> Result<TrainedModel, CliError> {
    let base = if opts.plain {
        TrainConfig::plain()
    } else {
        TrainConfig::default()
    };
    let cfg = TrainConfig {
        max_epochs: opts.epochs,
        seed: opts.seed,
        split: opts.validation.unwrap_or(base.split),
        rest: if opts.no_rest_stage { None } else { base.rest },
        ..base
    };
    let mut progress = Progress::new(kind.name());
    let model = train(kind, &ModelSpec::default(), data, &cfg, &mut |r| {
        progress.epoch(&r)
    });
    progress.finish();
    Ok(model?)
}

/// One line on what training did.
pub(super) fn describe(model: &TrainedModel) -> String {
    let s = model.summary();
    let val = s
        .best_val_loss
        .map_or("no held-out windows".to_string(), |v| {
            format!("held-out loss {v:.5}")
        });
    format!(
        "{}: {} epochs (best {}{}), train loss {:.5}, {val}; {} windows from {} trials; {:.2} s",
        s.kind,
        s.epochs_run,
        s.best_epoch,
        if s.stopped_early {
            ", stopped early"
        } else {
            ""
        },
        s.final_train_loss,
        s.n_train_windows,
        s.n_train_trials,
        s.duration_ms as f64 / 1000.0
    )
}

/// The session's rest level per channel (see [`TrainedModel::rest_rms_uv`]): from the
/// training windows, or for a two-point calibration (which trains without rest) from the rest
/// windows it left out.
fn rest_level(
    session: &Session,
    windows: &LabelledWindows,
    two_point: bool,
) -> Result<Option<Vec<f64>>, CliError> {
    Ok(if two_point {
        session
            .windows(&WindowOptions::default())?
            .rest_rms(&session.meta.trials)
    } else {
        windows.rest_rms(&session.meta.trials)
    })
}

/// `handctl train`: train, verify every calibration ray, and write the model only if it
/// passes (or with `--force`, recorded as forced); a refused model leaves no file behind.
pub fn run(a: &TrainArgs) -> Result<(), CliError> {
    let session = Session::open_spec(&a.session)?;
    let bypassed = gate(&session, &a.training)?;
    let record = provenance(
        a.patient.as_deref(),
        session_id(&a.session),
        session.meta.recorded_utc.as_deref(),
        &a.training,
        bypassed,
    );
    let windows = session.windows(&window_options(&a.training))?;
    let data = windows.to_dataset(&session.meta.chain)?;
    let model = fit(a.model, &data, &a.training)?;
    println!("{}", describe(&model));
    let model = super::verify::certify(model, &session, &windows, a.tolerance, a.force)?;
    let model = match rest_level(&session, &windows, a.training.two_point)? {
        Some(levels) => model.with_rest_rms_uv(levels)?,
        None => model,
    };
    let model = model.with_provenance(record)?;
    model.save(&a.output)?;
    println!("wrote {}", a.output.display());
    println!("{}", describe_provenance(model.provenance()));
    Ok(())
}

/// `handctl check`.
pub fn run_check(a: &CheckArgs) -> Result<(), CliError> {
    let session = Session::open_spec(&a.session)?;
    let report = check_gates(&session, &GateConfig::default())?;
    print!("{report}");
    if report.passed() {
        Ok(())
    } else {
        Err(CliError::Gates(report.issues.len()))
    }
}
