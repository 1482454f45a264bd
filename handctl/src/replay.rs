//! `handctl replay`: a tape handd recorded (`handd --tape FILE`) through a fresh engine, built
//! from the run's config and model, every tick compared with what handd computed, bit for bit
//! (`driver::tape`). Exit 0 when every round matches, 1 when one differs (each listed).

use crate::args::ReplayArgs;
use crate::error::CliError;

/// Runs the command.
pub fn run(a: &ReplayArgs) -> Result<(), CliError> {
    let config = driver::Config::load(&a.config)?;
    let model = a.model.clone().unwrap_or_else(|| config.model.clone());
    let loaded = driver::startup::load_model(&model, config.mains_hz)?;
    let entries = driver::tape::read(&a.tape)?;
    let settings = driver::startup::engine_settings(&config, loaded.model_id);
    let r = driver::tape::replay(
        &entries,
        &loaded.chain,
        Some(loaded.model.predictor()),
        settings,
    )?;
    println!(
        "{}: {} entries, {} ticks; {} rounds of frames bit for bit, {} differ",
        a.tape.display(),
        entries.len(),
        r.ticks,
        r.matched,
        r.differing
    );
    match r.end {
        driver::tape::End::Tape => {}
        driver::tape::End::Swap { at_us } => {
            println!("stopped at a model swap at {at_us} us: the new model is not on the tape")
        }
        driver::tape::End::Lost { entries } => println!(
            "stopped where the recorder lost {entries} entries (its queue was full): what \
             follows does not replay"
        ),
    }
    for d in &r.differences {
        println!("differs at {} us:", d.at_us);
        println!("  handd:  {}", frames(&d.recorded));
        println!("  replay: {}", frames(&d.replayed));
    }
    if r.differing > 0 {
        return Err(CliError::ReplayDiffers(r.differing));
    }
    Ok(())
}

fn frames(f: &[hand_dbc::CanFrame]) -> String {
    f.iter()
        .map(|f| f.to_string())
        .collect::<Vec<_>>()
        .join(" ")
}
