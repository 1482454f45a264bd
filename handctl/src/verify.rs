//! `handctl verify`: along the effort ray of every calibration window (the window's signal
//! scaled down to effort `k` in `[0, 1]`), does each finger follow the effort without going
//! back? Exact for ResDD and LN, sampled for MLP and CNN (the report says which). Then the same
//! rays out to effort [`BEYOND_EFFORT`] through the calibration envelope's clipping (issue 25):
//! a stronger grip than the calibration's must not turn a finger back either. Also the check
//! `handctl train` makes before it writes a model ([`certify`]): it refuses a model that
//! reverses on `[0, 1]` and warns about one that reverses only beyond full effort (the model
//! file records the `[0, 1]` verification, the one `deploy` gates on).

use decoder::model::verify::{
    describe_verification, verify_beyond, verify_windows, BeyondReport, RayVerifier,
    VerificationRecord, VerifyReport, BEYOND_EFFORT,
};
use decoder::model::TrainedModel;
use decoder::session::{LabelledWindows, Session, WindowOptions};

use super::args::VerifyArgs;
use super::error::CliError;

/// Verifies `model` on `windows` of `session`: on `[0, 1]`, and on `[0, BEYOND_EFFORT]`.
pub(super) fn report(
    model: &TrainedModel,
    session: &Session,
    windows: &LabelledWindows,
    tolerance: f64,
) -> Result<(VerifyReport, BeyondReport), CliError> {
    let mut verifier = RayVerifier::new(model);
    let trials = &session.meta.trials;
    let unit = verify_windows(&mut verifier, windows, trials, tolerance)?;
    let beyond = verify_beyond(&mut verifier, windows, trials, tolerance, BEYOND_EFFORT)?;
    Ok((unit, beyond))
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
    let (r, beyond) = report(&model, &session, &windows, a.tolerance)?;
    print!("{r}");
    print!("{beyond}");
    if !r.passed() {
        Err(CliError::Reversals(r.reversing()))
    } else if !beyond.passed() {
        Err(CliError::ReversalsBeyond {
            reversing: beyond.reversing(),
            overshooting: beyond.overshooting(),
            k_max: beyond.k_max,
        })
    } else {
        Ok(())
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
    let (r, beyond) = report(&model, session, windows, tolerance)?;
    let record = VerificationRecord::from_report(&r, force);
    println!("effort rays of the calibration: {record}");
    if !beyond.passed() {
        eprint!("WARNING: {beyond}");
        eprintln!(
            "WARNING: written all the same: the model file records the verification on \
             efforts [0, 1], the one deploy gates on; `handctl verify` exits non-zero on it"
        );
    }
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
