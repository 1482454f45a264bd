//! `handctl verify`: along the effort ray of every calibration window (the window's signal
//! scaled down to effort `k` in `[0, 1]`), does each finger follow the effort without going
//! back? Exact for ResDD and LN, sampled for MLP and CNN (the report says which). Also the
//! check `handctl train` makes before it writes a model ([`certify`]).

use decoder::model::verify::{
    describe_verification, verify_windows, RayVerifier, VerificationRecord, VerifyReport,
};
use decoder::model::TrainedModel;
use decoder::session::{LabelledWindows, Session, WindowOptions};

use super::args::VerifyArgs;
use super::error::CliError;

/// Verifies `model` on `windows` of `session`.
pub(super) fn report(
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
    println!(
        "{}: {}",
        a.model.display(),
        describe_verification(model.verification())
    );
    let windows = session.windows(&WindowOptions::default())?;
    let r = report(&model, &session, &windows, a.tolerance)?;
    print!("{r}");
    if r.passed() {
        Ok(())
    } else {
        Err(CliError::Reversals(r.reversing()))
    }
}

/// What `handctl train` does after training: verifies every calibration ray of `windows`
/// (exactly for ResDD and LN, by sampling for MLP and CNN), prints the outcome, and returns
/// the model with the verification recorded, or refuses one that reverses beyond `tolerance`
/// unless `force` (then the record says FORCED).
pub(super) fn certify(
    model: TrainedModel,
    session: &Session,
    windows: &LabelledWindows,
    tolerance: f64,
    force: bool,
) -> Result<TrainedModel, CliError> {
    let r = report(&model, session, windows, tolerance)?;
    let record = VerificationRecord::from_report(&r, force);
    println!("effort rays of the calibration: {record}");
    if !r.passed() {
        eprint!("{r}");
        if !force {
            return Err(CliError::Refused {
                verdict: format!("the {} model {record}", r.kind),
            });
        }
        eprintln!("--force: writing it anyway; the model file records it as FORCED");
    }
    Ok(model.with_verification(record)?)
}
