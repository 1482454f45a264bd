//! `handctl import-3dc` and `handctl import`.

use decoder::dsp::FrontEnd;
use decoder::session::{import_3dc, import_table, SamplesSource, SessionError, Split, TableImport};

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

/// `handctl import`: samples plus a label table; chain defaults fitted to the rate, each
/// said in a line "chose ...".
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
    let front_end = FrontEnd {
        channels: a.channels,
        sample_rate_hz: a.rate,
        mains_hz: a.mains,
        band_low_hz: a.band_low,
        band_high_hz: a.band_high,
        window_ms: a.window_ms,
        step_ms: a.step_ms,
    };
    let chain = front_end.chain().map_err(SessionError::from)?;
    let spec = TableImport {
        samples,
        labels: a.labels.clone(),
        chain: chain.config,
        rows_are_recordings: a.rows_are_recordings,
        full_scale: a.full_scale,
        onset_skip_ms: a.onset_skip_ms,
        reference: a.reference.clone(),
        ignore_columns: a.ignore_columns.clone(),
    };
    let meta = import_table(&spec, &a.output)?;
    for choice in &chain.choices {
        println!("chose {choice}");
    }
    let c = &meta.chain;
    println!(
        "wrote {}/session.toml: {} trials, {} channels at {} Hz (band-pass {}-{} Hz, window {} ms, step {} ms){}",
        a.output.display(),
        meta.trials.len(),
        c.channels,
        c.sample_rate_hz,
        c.band_low_hz,
        c.band_high_hz,
        c.window_ms,
        c.step_ms,
        meta.reference
            .as_ref()
            .map_or(String::new(), |r| format!(", reference \"{}\"", r.name))
    );
    Ok(())
}
