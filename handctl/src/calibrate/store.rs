//! What a calibration keeps on disk in its directory, and how `--resume` reads it back:
//!
//! - `frames.log`: the bus, as `handctl record` writes it (appended to on `--resume`);
//! - `protocol.toml`: the protocol in force, written before the first cue;
//! - `session.toml`: the trials kept so far (only passing attempts), rewritten atomically after
//!   every kept trial, so that Ctrl-C at any moment leaves a session `handctl train` and
//!   `--resume` can read. Trial ids are the protocol's trial numbers (1-based), so the kept
//!   trials are always trials 1..=n and `--resume` continues with trial n + 1.

use std::path::{Path, PathBuf};

use decoder::dsp::ChainConfig;
use decoder::session::{SessionMeta, Trial, META_FILE};
use driver::units::ADC_MAX;

use super::error::CalibrateError;
use super::protocol::Protocol;
use super::recorder::FRAMES_FILE;

/// The protocol's copy in the output directory.
pub const PROTOCOL_FILE: &str = "protocol.toml";

/// The calibration's directory and the session kept so far.
#[derive(Debug, Clone)]
pub struct Store {
    dir: PathBuf,
    /// The session's metadata with the trials kept so far.
    pub meta: SessionMeta,
}

impl Store {
    /// A new calibration in `dir`: writes the protocol; refuses a directory that already holds
    /// a session (use `--resume`, or another directory).
    pub fn create(
        dir: &Path,
        chain: ChainConfig,
        protocol: &Protocol,
    ) -> Result<Self, CalibrateError> {
        if dir.join(META_FILE).exists() {
            return Err(CalibrateError::Resume(format!(
                "{} already holds a session: pass --resume to continue it, or choose another --out",
                dir.display()
            )));
        }
        std::fs::create_dir_all(dir).map_err(CalibrateError::io(dir))?;
        let p = dir.join(PROTOCOL_FILE);
        std::fs::write(&p, protocol.to_toml()).map_err(CalibrateError::io(&p))?;
        Ok(Store {
            dir: dir.to_path_buf(),
            meta: SessionMeta::candump(chain, FRAMES_FILE, f64::from(ADC_MAX), Vec::new())
                .recorded_now(),
        })
    }

    /// Reopens a calibration in `dir` for `--resume`: its protocol (a `--protocol` given must
    /// be the same) and its kept trials.
    pub fn resume(
        dir: &Path,
        chain: ChainConfig,
        given: Option<&Protocol>,
    ) -> Result<(Self, Protocol), CalibrateError> {
        let p = dir.join(PROTOCOL_FILE);
        if !p.exists() {
            return Err(CalibrateError::Resume(format!(
                "{} has no {PROTOCOL_FILE}: nothing to resume there",
                dir.display()
            )));
        }
        let protocol = Protocol::load(&p)?;
        if given.is_some_and(|g| *g != protocol) {
            return Err(CalibrateError::Resume(format!(
                "--protocol differs from the one the calibration in {} started with ({}); \
                 resume without --protocol",
                dir.display(),
                p.display()
            )));
        }
        let mut meta = SessionMeta::candump(chain, FRAMES_FILE, f64::from(ADC_MAX), Vec::new());
        if dir.join(META_FILE).exists() {
            let old = SessionMeta::read(dir)?;
            if old.chain != meta.chain {
                return Err(CalibrateError::Resume(
                    "the session's [chain] differs from this run's (--mains?)".into(),
                ));
            }
            meta.trials = old.trials;
            // The calibration's date is when it began, not when it was resumed.
            meta.recorded_utc = old.recorded_utc;
        }
        for (i, t) in meta.trials.iter().enumerate() {
            if t.id as usize != i + 1 {
                return Err(CalibrateError::Resume(format!(
                    "the session's trial {} is not trial {} of the protocol: not a session \
                     this command wrote",
                    t.id,
                    i + 1
                )));
            }
        }
        let store = Store {
            dir: dir.to_path_buf(),
            meta,
        };
        Ok((store, protocol))
    }

    /// The directory.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Trials kept.
    pub fn kept(&self) -> usize {
        self.meta.trials.len()
    }

    /// Keeps a passing trial (replacing a kept one of the same id: a redone trial) and
    /// rewrites `session.toml` atomically.
    pub fn keep(&mut self, trial: Trial) -> Result<(), CalibrateError> {
        match self.meta.trials.iter_mut().find(|t| t.id == trial.id) {
            Some(old) => *old = trial,
            None => self.meta.trials.push(trial),
        }
        self.meta.write(&self.dir)?;
        Ok(())
    }
}
