//! Deploying a model to the running daemon, off the control loop: the file is read, parsed
//! (checksum, shapes, finite weights), checked against the bus, the config and the chain the
//! loop runs, and its recorded verification is checked; then it is installed (copied beside
//! the config's model path as `model-<id>.hsm`, and the config rewritten atomically to name
//! it, so a restart runs the deployed model) and handed to the loop, which swaps it in at a
//! tick boundary ([`crate::engine::ModelSwap`]). A model for another patient than the running
//! model's (or for an unknown one) is refused unless the request says the technician confirmed
//! it ([`patient_change`]). The audit line is written before anything changes: a deploy or a
//! rollback whose line cannot be written is refused ([`try_audit`]). A rollback re-reads the
//! file it points the config back at and refuses if its fingerprint is no longer the running
//! copy's ([`check_fingerprint`]). Every refusal names the reason; nothing changes on one.

use std::fs::OpenOptions;
use std::io::Write;
use std::path::{Path, PathBuf};

use decoder::dsp::ChainConfig;

use crate::config::{Config, DeployConfig};
use crate::control::Peer;
use crate::protocol::ModelStatus;
use crate::startup::{check_model, fingerprint, LoadedModel, StartupError};

/// Why a deploy or a rollback was refused.
#[derive(Debug, thiserror::Error)]
pub enum DeployError {
    /// The path is not absolute (the daemon's working directory is not the technician's).
    #[error("model path {0:?} is not absolute: give the full path")]
    NotAbsolute(String),
    /// Missing file, parse error, or a chain that does not fit the bus or the config.
    #[error(transparent)]
    Model(#[from] StartupError),
    /// The model's chain differs from the chain the loop runs.
    #[error("model {path}: its signal chain differs from the running one: {fields}; a model with another chain needs handd restarted")]
    Chain {
        /// The model file.
        path: PathBuf,
        /// Each differing field with both sides.
        fields: String,
    },
    /// The file records no verification, or a failed (possibly forced) one.
    #[error("model {path}: {verification}; refused (deploy with --force to run it anyway)")]
    Unverified {
        /// The model file.
        path: PathBuf,
        /// What the file records.
        verification: String,
    },
    /// The recorded verification passed, but looser or on fewer rays than the config demands.
    #[error("model {path}: {why}; refused (deploy with --force to run it anyway)")]
    WeakVerification {
        /// The model file.
        path: PathBuf,
        /// What falls short, with the config's figure.
        why: String,
    },
    /// The model is for another (or an unknown) patient than the running one, and the request
    /// does not say the technician confirmed it.
    #[error("model {path}: {change}; refused without the technician's confirmation (`handctl deploy` shows both and asks; --yes for scripts)")]
    PatientDiffers {
        /// The model file.
        path: PathBuf,
        /// Both patients, in words ([`patient_change`]).
        change: String,
    },
    /// The file a rollback would point the config back at is not the model kept in memory.
    #[error("the model to roll back to, {path}, {why}: refused; nothing changed (the running model and the config stay)")]
    Replaced {
        /// The file the config would name.
        path: PathBuf,
        /// What is wrong with it: unreadable, or another fingerprint.
        why: String,
    },
    /// The audit line could not be written.
    #[error("the audit log {path} could not be written ({why}): refused; nothing changed")]
    Audit {
        /// The audit log.
        path: PathBuf,
        /// What the OS said.
        why: String,
    },
    /// The model file or the config could not be written.
    #[error("could not install the model: {0}; nothing changed")]
    Install(String),
    /// Nothing to roll back to.
    #[error("nothing to roll back to: no model was deployed since handd started")]
    NoPrevious,
    /// The loop did not take the model.
    #[error("{0}; nothing changed")]
    Loop(String),
}

/// A model checked and ready for the loop, with the file's bytes (to install them).
pub struct Prepared {
    /// The model.
    pub loaded: LoadedModel,
    /// The file as read.
    pub bytes: Vec<u8>,
    /// Where it was read from.
    pub source: PathBuf,
}

/// Reads and checks the model at `path` for a loop running `chain` (see the module doc). A
/// model whose file records no verification, or one that failed, or one verified looser or on
/// fewer rays than `policy` demands, is refused unless `force`.
pub fn prepare(
    path: &str,
    chain: &ChainConfig,
    policy: &DeployConfig,
    force: bool,
) -> Result<Prepared, DeployError> {
    let source = PathBuf::from(path);
    if !source.is_absolute() {
        return Err(DeployError::NotAbsolute(path.to_owned()));
    }
    let bytes = std::fs::read(&source).map_err(|e| StartupError::Model {
        path: source.clone(),
        source: decoder::model::FileError::Io {
            op: "read",
            path: source.clone(),
            source: e,
        },
    })?;
    let loaded = check_model(&source, &bytes, chain.mains_hz)?;
    let fields = chain_differences(loaded.model.chain(), chain);
    if !fields.is_empty() {
        return Err(DeployError::Chain {
            path: source,
            fields,
        });
    }
    let status = loaded.status(&source);
    if status.unverified && !force {
        return Err(DeployError::Unverified {
            path: source,
            verification: status.verification,
        });
    }
    if let (Some(why), false) = (weak_verification(&loaded, policy), force) {
        return Err(DeployError::WeakVerification { path: source, why });
    }
    Ok(Prepared {
        loaded,
        bytes,
        source,
    })
}

/// Whether swapping in a model for `model_patient` over `running` needs the technician's
/// confirmation, and if so both patients in words: "this model is for patient B, the running
/// model (id 0badf00d) for patient A". It does unless no model runs or both files name the same
/// patient: an unknown patient (a file without provenance, or trained without `--patient`) on
/// either side is never taken for the same one.
pub fn patient_change(
    model_patient: Option<&str>,
    running: Option<&ModelStatus>,
) -> Option<String> {
    let running = running?;
    let (new, old) = (model_patient, running.patient.as_deref());
    if new.is_some() && new == old {
        return None;
    }
    let words = decoder::model::provenance::patient_words;
    Some(format!(
        "this model is for {}, the running model (id {}) for {}",
        words(new),
        running.id,
        words(old)
    ))
}

/// Checks that the file at `path` is still the model with fingerprint `id` (8 hex digits, as
/// [`ModelStatus::id`]): a rollback points the config back at it, so a restart must run the
/// model that runs now.
pub fn check_fingerprint(path: &Path, id: &str) -> Result<(), DeployError> {
    let replaced = |why: String| DeployError::Replaced {
        path: path.to_owned(),
        why,
    };
    let bytes = std::fs::read(path).map_err(|e| replaced(format!("cannot be read: {e}")))?;
    let found = format!("{:08x}", fingerprint(&bytes));
    if found == id {
        Ok(())
    } else {
        Err(replaced(format!(
            "changed on disk: its fingerprint is {found}, the model kept in memory is {id}"
        )))
    }
}

/// What a passed verification lacks against `policy`, if anything.
fn weak_verification(loaded: &LoadedModel, policy: &DeployConfig) -> Option<String> {
    let v = loaded.model.verification()?;
    let mut short = Vec::new();
    if v.tolerance > policy.max_tolerance {
        short.push(format!(
            "verified at tolerance {}, the config allows at most {} (deploy.max_tolerance)",
            v.tolerance, policy.max_tolerance
        ));
    }
    if v.rays < policy.min_rays {
        short.push(format!(
            "verified on {} rays, the config demands at least {} (deploy.min_rays)",
            v.rays, policy.min_rays
        ));
    }
    (!short.is_empty()).then(|| short.join("; "))
}

/// The fields where the model's chain and the running one differ, "field: model A, running B",
/// comma separated; empty when they agree.
pub fn chain_differences(model: &ChainConfig, running: &ChainConfig) -> String {
    let (Ok(a), Ok(b)) = (serde_json::to_value(model), serde_json::to_value(running)) else {
        return "the chain configurations cannot be compared".into();
    };
    let (Some(a), Some(b)) = (a.as_object(), b.as_object()) else {
        return String::new();
    };
    let mut out: Vec<String> = a
        .iter()
        .filter(|(k, v)| b.get(*k) != Some(*v))
        .map(|(k, v)| {
            let r = b.get(k).map_or("absent".into(), |r| r.to_string());
            format!("{k}: model {v}, running {r}")
        })
        .collect();
    out.sort();
    out.join(", ")
}

/// Where a deployed model lives: beside the config's model path, named by its id.
pub fn installed_path(config_model: &Path, model_id: u32) -> PathBuf {
    let dir = config_model.parent().unwrap_or(Path::new("/"));
    dir.join(format!("model-{model_id:08x}.hsm"))
}

/// Copies the prepared model beside the config's model path (atomically; kept as is when it
/// is already there) and returns the config naming it, saved atomically to `config_path`.
pub fn install(
    p: &Prepared,
    config: &Config,
    config_path: &Path,
) -> Result<(Config, PathBuf), DeployError> {
    let target = installed_path(&config.model, p.loaded.model_id);
    if target != p.source {
        decoder::fsio::write_atomic(&target, &p.bytes)
            .map_err(|e| DeployError::Install(format!("{}: {e}", target.display())))?;
    }
    let next = point_config(config, &target, config_path)?;
    Ok((next, target))
}

/// The config with `model` as its model file, saved atomically to `config_path`.
pub fn point_config(
    config: &Config,
    model: &Path,
    config_path: &Path,
) -> Result<Config, DeployError> {
    let mut next = config.clone();
    next.model = model.to_owned();
    next.save_atomic(config_path)
        .map_err(|e| DeployError::Install(format!("the config {}: {e}", config_path.display())))?;
    Ok(next)
}

/// The audit log's times: `time=` the wall clock (Unix seconds) and `mono=` the monotonic
/// clock (seconds since boot, CLOCK_MONOTONIC), so the order and the spacing of the lines stay
/// true when the wall clock is stepped (NTP's first sync on a board without RTC, `date -s`).
pub fn audit_times() -> String {
    let time_s = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0.0, |d| d.as_secs_f64());
    let m = rustix::time::clock_gettime(rustix::time::ClockId::Monotonic);
    let mono_s = m.tv_sec as f64 + m.tv_nsec as f64 * 1e-9;
    format!("time={time_s:.3} mono={mono_s:.3}")
}

/// Appends one line to the audit log and syncs it: times ([`audit_times`]), who (user, uid,
/// pid), what (`action` with its details). Deploy and rollback write theirs with this before
/// anything changes, and are refused when it fails.
pub fn try_audit(log: &Path, user: &str, peer: Peer, action: &str) -> Result<(), DeployError> {
    let line = format!(
        "{} user={user} uid={} pid={} {action}",
        audit_times(),
        peer.uid,
        peer.pid
    );
    let write = || -> std::io::Result<()> {
        if let Some(dir) = log.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir)?;
        }
        let mut f = OpenOptions::new().create(true).append(true).open(log)?;
        writeln!(f, "{line}")?;
        f.sync_data()
    };
    write().map_err(|e| DeployError::Audit {
        path: log.to_owned(),
        why: e.to_string(),
    })
}

/// [`try_audit`] for the actions that go on without their line (`stop`, `arm`, `tune`,
/// `calibrating`: refusing a stop would be worse): a failure is logged, never fatal.
pub fn audit(log: &Path, user: &str, peer: Peer, action: &str) {
    if let Err(e) = try_audit(log, user, peer, action) {
        tracing::warn!(error = %e, "audit log not written");
    }
}

#[cfg(test)]
mod tests {
    use decoder::model::verify::{Method, VerificationRecord, WorstRay};
    use decoder::model::{
        AnyModel, ModelKind, ModelSpec, Normalizer, TrainedModel, TrainingSummary,
    };

    use super::*;

    /// A ResDD model on the default chain whose file records `tolerance` over `rays` rays, none
    /// reversing.
    fn model_file(dir: &Path, name: &str, tolerance: f64, rays: usize) -> String {
        let chain = ChainConfig::default();
        let n_in = 8 * chain.channels;
        let spec = ModelSpec::default();
        let model = AnyModel::random(ModelKind::ResDd, &spec, n_in, 5, 3).expect("model");
        let norm = Normalizer::from_scales(vec![100.0; n_in]).expect("normalizer");
        let record = VerificationRecord {
            method: Method::Exact,
            tolerance,
            rays,
            reversing: 0,
            worst: (rays > 0).then(|| WorstRay {
                trial: "trial 1 (index flexion, repetition 1)".into(),
                finger: 1,
                amount: 0.0,
                from_k: 0.0,
                to_k: 0.0,
            }),
            forced: false,
        };
        let path = dir.join(name);
        TrainedModel::new(
            model,
            spec,
            norm,
            chain,
            TrainingSummary::untrained(ModelKind::ResDd),
        )
        .expect("trained model")
        .with_verification(record)
        .expect("record")
        .save(&path)
        .expect("save");
        path.display().to_string()
    }

    #[test]
    fn a_verification_looser_or_smaller_than_the_config_demands_is_refused_without_force() {
        let dir = std::env::temp_dir().join(format!("handd-deploy-policy-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("dir");
        let chain = ChainConfig::default();
        let policy = DeployConfig::default();
        let good = model_file(&dir, "good.hsm", 0.01, 3375);
        assert!(prepare(&good, &chain, &policy, false).is_ok());
        let loose = model_file(&dir, "loose.hsm", 1.0, 3375);
        let e = prepare(&loose, &chain, &policy, false)
            .err()
            .expect("refused");
        assert!(
            matches!(e, DeployError::WeakVerification { .. })
                && e.to_string()
                    .contains("tolerance 1, the config allows at most 0.05"),
            "{e}"
        );
        let none = model_file(&dir, "none.hsm", 0.01, 0);
        let e = prepare(&none, &chain, &policy, false)
            .err()
            .expect("refused");
        assert!(e.to_string().contains("on 0 rays"), "{e}");
        assert!(
            prepare(&none, &chain, &policy, true).is_ok(),
            "--force deploys it"
        );
        std::fs::remove_dir_all(&dir).expect("clean up");
    }
}
