//! After the last trial: the whole session through the quality gates, training (the progress
//! bar of `handctl train`), the verification of every calibration ray (a model that reverses
//! is refused, as by `handctl train`), the model written to `DIR/model.hsm`, and a short
//! evaluation on the calibration windows for the per-finger summary ([`super::summary`]).

use std::path::{Path, PathBuf};

use decoder::model::verify::{VerificationRecord, VerifyReport};
use decoder::model::{ModelKind, TrainedModel};
use decoder::session::{check_gates, GateConfig, LabelledWindows, Session, WindowOptions};

use crate::args::TrainingOpts;
use crate::error::CliError;
use crate::train::{describe, fit, provenance, window_options};

/// The model file inside the output directory.
pub const MODEL_FILE: &str = "model.hsm";

/// A trained, verified and written model with what the summary needs.
pub struct Trained {
    /// Where it was written.
    pub path: PathBuf,
    /// The model.
    pub model: TrainedModel,
    /// Its verification on every calibration window.
    pub report: VerifyReport,
    /// The session.
    pub session: Session,
    /// Every labelled window of the session (rest included).
    pub windows: LabelledWindows,
    /// One line on the training.
    pub description: String,
}

/// Gates, training, verification and the model file (see the module docs); the file records
/// `patient`, the session (the directory's name), the date and any gate findings bypassed.
pub fn train_session(
    dir: &Path,
    opts: &TrainingOpts,
    tolerance: f64,
    patient: Option<&str>,
) -> Result<Trained, CliError> {
    let session = Session::open(dir)?;
    let gates = check_gates(&session, &GateConfig::default())?;
    if !gates.passed() {
        eprint!("{}: quality gates:\n{gates}", dir.display());
        crate::train::overrule(&gates, opts)?;
    }
    // The findings `--ignore-gates` went past (a one-direction finger allowed alone is not a
    // gate bypass).
    let bypassed = if opts.ignore_gates && !gates.passed() {
        gates.issues.iter().map(|i| i.message.clone()).collect()
    } else {
        Vec::new()
    };
    let origin = provenance(
        patient,
        crate::train::session_id(&dir.display().to_string()),
        session.meta.recorded_utc.as_deref(),
        opts,
        bypassed,
    );
    let train_windows = session.windows(&window_options(opts))?;
    let data = train_windows.to_dataset(&session.meta.chain)?;
    let model = fit(ModelKind::ResDd, &data, opts)?;
    let description = describe(&model);
    let windows = session.windows(&WindowOptions::default())?;
    let (report, beyond) = crate::verify::report(&model, &session, &windows, tolerance)?;
    let record = VerificationRecord::from_report(&report, false);
    if !beyond.passed() {
        eprint!("WARNING: {beyond}");
    }
    if !report.passed() {
        eprint!("{report}");
        return Err(CliError::Refused {
            verdict: format!("the {} model {record}", report.kind),
        });
    }
    let mut model = model.with_verification(record)?.with_provenance(origin)?;
    if let Some(levels) = windows.rest_rms(&session.meta.trials) {
        model = model.with_rest_rms_uv(levels)?;
    }
    let path = dir.join(MODEL_FILE);
    model.save(&path)?;
    Ok(Trained {
        path,
        model,
        report,
        session,
        windows,
        description,
    })
}
