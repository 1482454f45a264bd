//! `handctl import-3dc`.

use decoder::session::{import_3dc, Split};

use super::args::Import3dcArgs;
use super::error::CliError;

/// Writes the session directory and says what is in it.
pub fn run_3dc(a: &Import3dcArgs) -> Result<(), CliError> {
    let split: Split = a.split.parse()?;
    let meta = import_3dc(&a.dir, split, &a.output)?;
    println!(
        "wrote {}/session.toml: {} trials, {} channels at {} Hz, samples read from {}",
        a.output.display(),
        meta.trials.len(),
        meta.chain.channels,
        meta.chain.sample_rate_hz,
        meta.recording.file.display()
    );
    Ok(())
}
