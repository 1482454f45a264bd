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
    let model = TrainedModel::from_bytes(&bytes, None).map_err(|source| StartupError::Model {
        path: path.to_owned(),
        source,
    })?;
    let c: &ChainConfig = model.chain();
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
    if c.mains_hz != mains_hz {
        return Err(mismatch(format!(
            "its notch is at {} Hz but the config says mains_hz = {mains_hz}: retrain, or fix mains_hz",
            c.mains_hz
        )));
    }
    let chain = c.validate().map_err(|source| StartupError::Chain {
        path: path.to_owned(),
        source,
    })?;
    Ok(LoadedModel {
        model,
        chain,
        model_id: fingerprint(&bytes),
    })
}

/// The engine's settings from a validated config.
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

    #[test]
    fn a_missing_model_names_the_file() {
        let e = load_model(Path::new("/nonexistent/model.hsm"), 50)
            .err()
            .unwrap();
        assert!(e.to_string().contains("/nonexistent/model.hsm"), "{e}");
    }
}
