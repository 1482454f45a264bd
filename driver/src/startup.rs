//! What `handd` checks before it reports READY: the config, the model file and its fit to the
//! bus and the config. Each failure names what to fix; the daemon refuses to start on any.

use std::path::{Path, PathBuf};

use decoder::dsp::{ChainConfig, ChainSettings};
use decoder::model::TrainedModel;
use hand_dbc::emg::EMG_CHANNELS;

use crate::config::{Config, ConfigError};
use crate::engine::EngineSettings;
use crate::units::N_FINGERS;

/// Why the daemon will not start.
#[derive(Debug, thiserror::Error)]
pub enum StartupError {
    /// The config file.
    #[error("config: {0}")]
    Config(#[from] ConfigError),
    /// The model file could not be loaded.
    #[error("model {path}: {source}")]
    Model {
        /// The model file.
        path: PathBuf,
        /// The cause.
        #[source]
        source: decoder::model::FileError,
    },
    /// The model does not fit the bus or the config.
    #[error("model {path}: {what}")]
    ModelMismatch {
        /// The model file.
        path: PathBuf,
        /// What does not fit.
        what: String,
    },
    /// The model's chain configuration is invalid.
    #[error("model {path}: its signal chain configuration is invalid: {source}")]
    Chain {
        /// The model file.
        path: PathBuf,
        /// The cause.
        #[source]
        source: decoder::dsp::ConfigError,
    },
}

/// A model checked against the bus and the config.
pub struct LoadedModel {
    /// The model.
    pub model: TrainedModel,
    /// Its chain, designed.
    pub chain: ChainSettings,
    /// A short identity for HAND_HEARTBEAT (FNV-1a of the file).
    pub model_id: u32,
}

/// FNV-1a, 32 bits: a cheap fingerprint so the heartbeat tells which model file runs.
pub fn fingerprint(bytes: &[u8]) -> u32 {
    bytes.iter().fold(0x811c_9dc5u32, |h, &b| {
        (h ^ u32::from(b)).wrapping_mul(0x0100_0193)
    })
}

/// Load `path` and check that its chain fits the bus (12 channels at 1 kHz) and `mains_hz`.
pub fn load_model(path: &Path, mains_hz: u32) -> Result<LoadedModel, StartupError> {
    let bytes = std::fs::read(path).map_err(|e| StartupError::Model {
        path: path.to_owned(),
        source: decoder::model::FileError::Io {
            op: "read",
            path: path.to_owned(),
            source: e,
        },
    })?;
    check_model(path, &bytes, mains_hz)
}

/// Check that the chain of the model at `path` fits the bus: its EMG channels and sample rate
/// are the amplifier's. handd checks it of every model it runs or deploys
/// ([`check_model`]), and `handctl monitor --model` of the model whose chain it runs on a bus
/// or a log of it.
pub fn check_fits_bus(path: &Path, c: &ChainConfig) -> Result<(), StartupError> {
    let mismatch = |what: String| StartupError::ModelMismatch {
        path: path.to_owned(),
        what,
    };
    if c.channels != EMG_CHANNELS {
        return Err(mismatch(format!(
            "trained on {} EMG channels, the bus carries {EMG_CHANNELS}: record a calibration on this hand",
            c.channels
        )));
    }
    if c.sample_rate_hz != 1000.0 {
        return Err(mismatch(format!(
            "trained at {} Hz, the amplifier samples at 1000 Hz",
            c.sample_rate_hz
        )));
    }
    Ok(())
}

/// Parse the model file's `bytes` (read from `path`) and check that its chain fits the bus and
/// `mains_hz`, as [`load_model`] does.
pub fn check_model(path: &Path, bytes: &[u8], mains_hz: u32) -> Result<LoadedModel, StartupError> {
    let model = TrainedModel::from_bytes(bytes, None).map_err(|source| StartupError::Model {
        path: path.to_owned(),
        source,
    })?;
    let c: &ChainConfig = model.chain();
    check_fits_bus(path, c)?;
    if c.mains_hz != mains_hz {
        return Err(StartupError::ModelMismatch {
            path: path.to_owned(),
            what: format!(
                "its notch is at {} Hz but the config says mains_hz = {mains_hz}: retrain, or fix mains_hz",
                c.mains_hz
            ),
        });
    }
    let chain = c.validate().map_err(|source| StartupError::Chain {
        path: path.to_owned(),
        source,
    })?;
    Ok(LoadedModel {
        model,
        chain,
        model_id: fingerprint(bytes),
    })
}

impl LoadedModel {
    /// What `handctl status` shows of this model, loaded from `path`.
    pub fn status(&self, path: &Path) -> crate::protocol::ModelStatus {
        let v = self.model.verification();
        let (guard, unguarded) = decoder::model::Envelope::describe(self.model.envelope());
        crate::protocol::ModelStatus {
            path: path.display().to_string(),
            id: format!("{:08x}", self.model_id),
            kind: self.model.summary().kind.to_string(),
            verification: decoder::model::verify::describe_verification(v),
            unverified: !v.is_some_and(|r| r.passed()),
            patient: self.model.provenance().and_then(|p| p.patient.clone()),
            provenance: decoder::model::provenance::describe_provenance(self.model.provenance()),
            guard,
            unguarded,
        }
    }

    /// Logs the model's verification: info when it passed, a warning otherwise.
    pub fn log_verification(&self, path: &Path) {
        let s = self.status(path);
        if s.unverified {
            tracing::warn!(model = %s.path, "model {}", s.verification);
        } else {
            tracing::info!(model = %s.path, "model {}", s.verification);
        }
    }
}

/// The engine's settings from a validated config (`Config::load` and `Config::validate`
/// check the drive table; an unvalidated one with a bad table panics here, naming it).
pub fn engine_settings(config: &Config, model_id: u32) -> EngineSettings {
    EngineSettings {
        tick_us: config.tick_ms * 1000,
        emg_silence_us: config.timeouts.emg_silence_ms * 1000,
        finger_silence_us: config.timeouts.finger_silence_ms * 1000,
        recovery_us: config.timeouts.recovery_ms * 1000,
        max_gap_us: hand_dbc::emg::DEFAULT_MAX_GAP_US,
        deadline_slack_us: config.deadline_slack_ms * 1000,
        gains: std::array::from_fn::<_, N_FINGERS, _>(|f| config.fingers.get(f).gains()),
        model_id,
        plausible_spread: config.plausibility.spread,
        pattern_margin: config.plausibility.pattern_margin,
        drives: config
            .drives()
            .unwrap_or_else(|e| panic!("the config was validated before: {e}")),
    }
}

/// Removes what saves killed midway left beside `files` (the config, the model): temporary
/// files whose writer process is gone ([`decoder::fsio::remove_stale_temps`]; a live writer's
/// are kept). Each removal is logged; a failure is logged and never stops the start. Returns
/// the files removed.
pub fn remove_stale_temps(files: &[&Path]) -> Vec<PathBuf> {
    let mut removed = Vec::new();
    for file in files {
        match decoder::fsio::remove_stale_temps(file) {
            Ok(stale) => {
                for t in stale {
                    tracing::warn!(
                        path = %t.path.display(),
                        pid = t.pid,
                        "removed the temporary file of a save that was killed midway"
                    );
                    removed.push(t.path);
                }
            }
            Err(e) => tracing::warn!("temporary files beside {}: {e}", file.display()),
        }
    }
    removed
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stale_temporaries_of_the_config_and_the_model_go_a_live_writers_stay() {
        let dir = std::env::temp_dir().join(format!("handd-stale-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("scratch directory");
        let (config, model) = (dir.join("handd.toml"), dir.join("model.hsm"));
        // 2^22 + 1 is above Linux's PID_MAX_LIMIT: no process has it.
        let dead = (1u32 << 22) + 1;
        let me = std::process::id();
        let stale_config = dir.join(format!(".handd.toml.tmp.{dead}.3"));
        let stale_model = dir.join(format!(".model.hsm.tmp.{dead}.0"));
        let live = dir.join(format!(".handd.toml.tmp.{me}.1"));
        for f in [&stale_config, &stale_model, &live] {
            std::fs::write(f, b"half a save").expect("a temporary");
        }
        let mut removed = remove_stale_temps(&[&config, &model]);
        removed.sort();
        let mut expected = vec![stale_config, stale_model];
        expected.sort();
        assert_eq!(
            removed, expected,
            "the dead writers' temporaries are removed"
        );
        assert!(live.exists(), "the live writer's temporary stays");
        std::fs::remove_dir_all(&dir).expect("clean up");
    }

    #[test]
    fn fingerprint_is_fnv1a() {
        assert_eq!(fingerprint(b""), 0x811c_9dc5);
        assert_eq!(fingerprint(b"a"), 0xe40c_292c);
    }

    /// A random ResDD for the bus's 12 channels at 1 kHz, saved in `dir`, with `record`.
    fn saved_model(
        dir: &Path,
        record: Option<decoder::model::verify::VerificationRecord>,
    ) -> PathBuf {
        use decoder::model::{AnyModel, ModelKind, ModelSpec, Normalizer, TrainingSummary};
        let chain = ChainConfig::default();
        let n_in = 8 * chain.channels;
        let spec = ModelSpec::default();
        let model = AnyModel::random(ModelKind::ResDd, &spec, n_in, 5, 1).expect("model");
        let norm = Normalizer::from_scales(vec![100.0; n_in]).expect("normalizer");
        let summary = TrainingSummary::untrained(ModelKind::ResDd);
        let mut m = TrainedModel::new(model, spec, norm, chain, summary).expect("model");
        if let Some(r) = record {
            m = m.with_verification(r).expect("a consistent record");
        }
        let path = dir.join(format!("model-{}.hsm", m.verification().is_some()));
        m.save(&path).expect("saved");
        path
    }

    #[test]
    fn the_status_shows_the_model_and_what_its_file_says_of_its_verification() {
        use decoder::model::verify::{Method, VerificationRecord, WorstRay};
        let dir = std::env::temp_dir().join(format!("handd-verified-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("scratch directory");
        let record = VerificationRecord {
            method: Method::Exact,
            tolerance: 0.01,
            rays: 3375,
            reversing: 0,
            worst: Some(WorstRay {
                trial: "trial 3 (index flexion, repetition 1)".into(),
                finger: 1,
                amount: 0.002,
                from_k: 0.5,
                to_k: 0.6,
            }),
            forced: false,
        };
        let verified = saved_model(&dir, Some(record));
        let loaded = load_model(&verified, 50).expect("loads");
        let s = loaded.status(&verified);
        assert_eq!(s.kind, "resdd");
        assert_eq!(s.id, format!("{:08x}", loaded.model_id));
        assert_eq!(s.path, verified.display().to_string());
        assert_eq!(
            s.verification,
            "verified: 0 of 3375 rays reverse beyond 0.01 (exact)"
        );
        assert!(!s.unverified);
        let (tx, _rx) = std::sync::mpsc::sync_channel(crate::service::COMMAND_QUEUE);
        let handler = crate::service::ControlHandler::new(
            Config::default(),
            dir.join("handd.toml"),
            Default::default(),
            tx,
        )
        .with_model(s.clone());
        assert_eq!(handler.status().model, Some(s));

        let old = saved_model(&dir, None);
        let s = load_model(&old, 50).expect("loads").status(&old);
        assert!(s.verification.starts_with("NOT verified"), "{s:?}");
        assert!(s.unverified);
        std::fs::remove_dir_all(&dir).expect("clean up");
    }

    #[test]
    fn a_missing_model_names_the_file() {
        let e = load_model(Path::new("/nonexistent/model.hsm"), 50)
            .err()
            .unwrap();
        assert!(e.to_string().contains("/nonexistent/model.hsm"), "{e}");
    }
}
