//! `handctl import-3dc`.

use decoder::dsp::ChainConfig;
use decoder::session::{import_3dc, import_table, SamplesSource, Split, TableImport};

use super::args::{Import3dcArgs, ImportArgs};
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

/// `handctl import`: samples plus a label table.
pub fn run_table(a: &ImportArgs) -> Result<(), CliError> {
    let ext = a
        .samples
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    let samples = match ext.as_deref() {
        Some("npy") => SamplesSource::Npy(a.samples.clone()),
        Some("csv") => SamplesSource::Csv(a.samples.clone()),
        _ => {
            return Err(CliError::Usage(format!(
                "{}: samples must be a .npy or .csv file",
                a.samples.display()
            )))
        }
    };
    let spec = TableImport {
        samples,
        labels: a.labels.clone(),
        chain: ChainConfig {
            channels: a.channels,
            sample_rate_hz: a.rate,
            mains_hz: a.mains,
            ..ChainConfig::default()
        },
        rows_are_recordings: a.rows_are_recordings,
        full_scale: a.full_scale,
        onset_skip_ms: a.onset_skip_ms,
    };
    let meta = import_table(&spec, &a.output)?;
    println!(
        "wrote {}/session.toml: {} trials, {} channels at {} Hz",
        a.output.display(),
        meta.trials.len(),
        meta.chain.channels,
        meta.chain.sample_rate_hz
    );
    Ok(())
}
