//! `handctl verify`: along the effort ray of every calibration window (the window's signal
//! scaled down to effort `k` in `[0, 1]`), does each finger follow the effort without going
//! back? Exact for ResDD and LN, sampled for MLP and CNN (the report says which).

use decoder::model::verify::{verify_windows, Method, RayVerifier, VerifyReport};
use decoder::model::TrainedModel;
use decoder::session::{LabelledWindows, Session, WindowOptions};

use super::args::VerifyArgs;
use super::error::CliError;

/// Verifies `model` on `windows` of `session`.
fn report(
    model: &TrainedModel,
    session: &Session,
    windows: &LabelledWindows,
    tolerance: f64,
) -> Result<VerifyReport, CliError> {
    let mut verifier = RayVerifier::new(model);
    Ok(verify_windows(
        &mut verifier,
        windows,
        &session.meta.trials,
        tolerance,
    )?)
}

/// `handctl verify`.
pub fn run(a: &VerifyArgs) -> Result<(), CliError> {
    let session = Session::open_spec(&a.session)?;
    let model = TrainedModel::load(&a.model, Some(&session.meta.chain))?;
    let windows = session.windows(&WindowOptions::default())?;
    let r = report(&model, &session, &windows, a.tolerance)?;
    print!("{r}");
    if r.passed() {
        Ok(())
    } else {
        Err(CliError::Reversals(r.reversing()))
    }
}

/// The verification summary `handctl train` prints after training: exact models only (a
/// sampled check of every window would take longer than the training; `handctl verify` does
/// it on request).
pub(super) fn after_training(
    model: &TrainedModel,
    session: &Session,
    windows: &LabelledWindows,
    tolerance: f64,
) -> Result<String, CliError> {
    if RayVerifier::new(model).method() != Method::Exact {
        return Ok(format!(
            "effort rays: a {} model is checked by sampling only; run handctl verify",
            model.summary().kind
        ));
    }
    let r = report(model, session, windows, tolerance)?;
    let worst = r.worst().map_or(0.0, |e| e.worst.amount);
    Ok(format!(
        "effort rays (exact): {} of {} training rays reverse by more than {tolerance} \
         (worst {worst:.4}){}",
        r.reversing(),
        r.rays(),
        if r.passed() {
            ""
        } else {
            "; handctl verify lists them"
        }
    ))
}
