//! The control side of `calibrating`, `deploy` and `rollback`: the checks and the file work run
//! here, on the control thread; the loop only moves the prepared model in at a tick boundary
//! and sends the one it replaced back ([`crate::engine::ModelSwap`]), which is kept for
//! `rollback`. Every action is audited with who asked (user, uid, pid).

use std::sync::mpsc::sync_channel;
use std::time::Duration;

use crate::control::Peer;
use crate::deploy::{
    audit, check_fingerprint, install, installed_path, patient_change, point_config, prepare,
    try_audit, DeployError,
};
use crate::engine::{Command, Hold, ModelSwap};
use crate::protocol::{ModelStatus, Reply};
use crate::service::ControlHandler;

/// How long a deploy waits for the loop to take the model (a tick or two normally).
pub const SWAP_WAIT: Duration = Duration::from_secs(2);

fn refused(e: DeployError) -> Reply {
    Reply::Refused {
        reason: e.to_string(),
    }
}

impl ControlHandler {
    /// `calibrating`: the loop holds the hand in safe stop until a deploy or rollback and an
    /// explicit `arm`.
    pub(crate) fn calibrating(&mut self, peer: Peer, user: &str) -> Reply {
        if let Err(r) = self.send(Command::Calibrating) {
            return *r;
        }
        self.hold = Hold::Calibrating;
        audit(&self.config.control.audit_log, user, peer, "calibrating");
        tracing::warn!(user, "calibrating: the hand is held in safe stop");
        Reply::Ok {
            message: "calibrating: the hand is held in safe stop until a model is deployed \
                      (`handctl deploy MODEL`) or rolled back (`handctl rollback`) and then \
                      `handctl arm`"
                .into(),
            status: Some(self.status()),
        }
    }

    /// Hands `swap` to the loop and waits for the model it replaced; None if the loop did not
    /// take it (gone, or not within [`SWAP_WAIT`]).
    fn swap_in(
        &self,
        swap: Command,
        rx: &std::sync::mpsc::Receiver<Box<ModelSwap>>,
    ) -> Result<Box<ModelSwap>, DeployError> {
        let ticket = match &swap {
            Command::Swap(b) => b.ticket.clone(),
            _ => unreachable!("swap_in is given a swap"),
        };
        self.send(swap)
            .map_err(|_| DeployError::Loop("the control loop is not running".into()))?;
        let reply = match rx.recv_timeout(self.swap_wait) {
            // Too late: cancel, so the swap still queued is never applied behind the reply.
            Err(_) if ticket.cancel() => {
                return Err(DeployError::Loop(format!(
                    "the control loop did not take the model within {:.1} s; the swap is cancelled",
                    self.swap_wait.as_secs_f64()
                )))
            }
            // The loop took it just now: the swap happened, and its reply is on the way.
            Err(_) => rx.recv_timeout(self.swap_wait).map_err(|_| {
                DeployError::Loop(
                    "the control loop took the model but did not answer; see handd's log".into(),
                )
            })?,
            Ok(b) => b,
        };
        if reply.swapped {
            Ok(reply)
        } else {
            Err(DeployError::Loop(
                "the loop refused the model: its inputs do not fit the chain".into(),
            ))
        }
    }

    /// `deploy` with `check_only`: the checks of [`prepare`], nothing installed, swapped or
    /// audited; the answer names the model. The patient is not checked here: `handctl deploy`
    /// shows both and asks, then sends the deploy itself, which checks it.
    pub(crate) fn check_deploy(&self, path: &str, force: bool) -> Reply {
        match prepare(path, &self.chain, &self.config.deploy, force) {
            Ok(p) => Reply::Ok {
                message: format!(
                    "checked: model {} (id {:08x}) passes handd's checks; nothing changed",
                    path, p.loaded.model_id
                ),
                status: None,
            },
            Err(e) => refused(e),
        }
    }

    /// `deploy`: checked (a model for another or an unknown patient than the running one's
    /// only when `confirmed`), audited, installed, swapped in; refused with nothing changed
    /// otherwise (an audit line that cannot be written included).
    pub(crate) fn deploy(
        &mut self,
        path: &str,
        force: bool,
        confirmed: bool,
        peer: Peer,
        user: &str,
    ) -> Reply {
        let prepared = match prepare(path, &self.chain, &self.config.deploy, force) {
            Ok(p) => p,
            Err(e) => return refused(e),
        };
        let patient = prepared
            .loaded
            .model
            .provenance()
            .and_then(|p| p.patient.clone());
        if let (Some(change), false) = (
            patient_change(patient.as_deref(), self.model.as_ref()),
            confirmed,
        ) {
            return refused(DeployError::PatientDiffers {
                path: prepared.source,
                change,
            });
        }
        let id = format!("{:08x}", prepared.loaded.model_id);
        let what = format!(
            "deploy path={path} installed={} id={id} previous={} force={force} patient={} \
             confirmed={confirmed}",
            installed_path(&self.config.model, prepared.loaded.model_id).display(),
            self.running_id(),
            patient.as_deref().unwrap_or("?"),
        );
        if let Err(e) = try_audit(&self.config.control.audit_log, user, peer, &what) {
            return refused(e);
        }
        let (next, target) = match install(&prepared, &self.config, &self.config_path) {
            Ok(x) => x,
            Err(e) => return self.failed("deploy", &id, e, peer, user),
        };
        let status = prepared.loaded.status(&target);
        let (tx, rx) = sync_channel(1);
        let cmd = Command::swap(
            prepared.loaded.model.predictor(),
            prepared.loaded.model_id,
            tx,
        );
        let old = match self.swap_in(cmd, &rx) {
            Ok(old) => old,
            Err(e) => {
                self.restore_config();
                return self.failed("deploy", &id, e, peer, user);
            }
        };
        self.config = next;
        let replaced = self.model.replace(status.clone());
        self.previous = match (old.predictor.is_some(), replaced) {
            (true, Some(s)) => Some((old, s)),
            _ => None,
        };
        self.after_swap("deploy", &status, peer, user)
    }

    /// `rollback`: the model the last deploy or rollback replaced comes back (so a second
    /// rollback undoes the first), once its file is checked to still be that model and the
    /// audit line is written; refused with nothing changed otherwise.
    pub(crate) fn rollback(&mut self, peer: Peer, user: &str) -> Reply {
        let Some((mut back, status)) = self.previous.take() else {
            return refused(DeployError::NoPrevious);
        };
        let file = std::path::PathBuf::from(&status.path);
        let what = format!(
            "rollback path={} installed={} id={} previous={} force=false patient={}",
            status.path,
            status.path,
            status.id,
            self.running_id(),
            status.patient.as_deref().unwrap_or("?"),
        );
        let checked = check_fingerprint(&file, &status.id)
            .and_then(|()| try_audit(&self.config.control.audit_log, user, peer, &what));
        if let Err(e) = checked {
            self.previous = Some((back, status));
            return refused(e);
        }
        let next = match point_config(&self.config, &file, &self.config_path) {
            Ok(n) => n,
            Err(e) => {
                let id = status.id.clone();
                self.previous = Some((back, status));
                return self.failed("rollback", &id, e, peer, user);
            }
        };
        let (tx, rx) = sync_channel(1);
        back.back = Some(tx);
        back.swapped = false;
        back.ticket = crate::engine::SwapTicket::new();
        let old = match self.swap_in(Command::Swap(back), &rx) {
            Ok(old) => old,
            Err(e) => {
                // The box is lost with a loop that is gone; the config goes back.
                self.restore_config();
                return self.failed("rollback", &status.id, e, peer, user);
            }
        };
        self.config = next;
        let replaced = self.model.replace(status.clone());
        self.previous = replaced.map(|s| (old, s));
        self.after_swap("rollback", &status, peer, user)
    }

    /// The running model's id for the audit line, "none" when none runs.
    fn running_id(&self) -> String {
        self.model.as_ref().map_or("none".into(), |s| s.id.clone())
    }

    /// A deploy or rollback that failed after its audit line: a second line says so (best
    /// effort: the first one is on disk), and the refusal.
    fn failed(&self, action: &str, id: &str, e: DeployError, peer: Peer, user: &str) -> Reply {
        let what = format!("{action}-failed id={id} reason={:?}", e.to_string());
        audit(&self.config.control.audit_log, user, peer, &what);
        refused(e)
    }

    /// The running model's calibration rest levels, read from its file here on the control
    /// thread (a file that no longer reads gives none), kept for `arm`'s rest check and told
    /// to the live lines with the model's name.
    fn tell_live(&mut self, status: &ModelStatus) {
        self.model_rest = decoder::model::TrainedModel::load(&status.path, None)
            .ok()
            .and_then(|m| m.rest_rms_uv().map(<[f64]>::to_vec));
        let Some(live) = &self.live_model else {
            return;
        };
        *live.lock().unwrap_or_else(|e| e.into_inner()) = crate::control::LiveModel {
            info: crate::live::ModelInfo {
                id: status.id.clone(),
                path: status.path.clone(),
                kind: status.kind.clone(),
            },
            rest_rms_uv: self.model_rest.clone(),
        };
    }

    fn restore_config(&self) {
        if let Err(e) = self.config.save_atomic(&self.config_path) {
            tracing::error!(error = %e, "the config could not be restored");
        }
    }

    /// Log, release the calibrating hold's first condition, and the reply (the audit line is
    /// written before the swap).
    fn after_swap(&mut self, action: &str, status: &ModelStatus, peer: Peer, user: &str) -> Reply {
        self.no_model = false;
        self.tell_live(status);
        if self.hold == Hold::Calibrating {
            self.hold = Hold::Deployed;
        }
        tracing::warn!(user, uid = peer.uid, pid = peer.pid, model = %status.path, id = %status.id, "{action}");
        let arm = if self.hold == Hold::Deployed {
            "; the hand stays held until `handctl arm`"
        } else {
            ""
        };
        let origin = if status.provenance.is_empty() {
            String::new()
        } else {
            format!("; {}", status.provenance)
        };
        Reply::Ok {
            message: format!(
                "{action}: model {} (id {}{origin}) runs from this tick on; the config names \
                 it{arm}",
                status.path, status.id
            ),
            status: Some(self.status()),
        }
    }
}

#[cfg(test)]
mod tests {
    use std::path::{Path, PathBuf};
    use std::sync::mpsc::sync_channel;
    use std::time::Duration;

    use decoder::dsp::ChainConfig;
    use decoder::model::{
        AnyModel, ModelKind, ModelSpec, Normalizer, TrainedModel, TrainingSummary,
    };

    use crate::config::Config;
    use crate::control::Peer;
    use crate::engine::{Command, Engine, EngineSettings};
    use crate::persist::{self, Latches};
    use crate::protocol::{Reply, Request};
    use crate::safety::{Fault, FaultSet};
    use crate::service::{ControlHandler, COMMAND_QUEUE};

    const ROOT: Peer = Peer {
        uid: 0,
        gid: 0,
        pid: 1,
    };

    fn trained(seed: u64) -> TrainedModel {
        let chain = ChainConfig::default();
        let n_in = 8 * chain.channels;
        let spec = ModelSpec::default();
        let model = AnyModel::random(ModelKind::ResDd, &spec, n_in, 5, seed).expect("model");
        let norm = Normalizer::from_scales(vec![100.0; n_in]).expect("normalizer");
        let summary = TrainingSummary::untrained(ModelKind::ResDd);
        TrainedModel::new(model, spec, norm, chain, summary).expect("model")
    }

    /// A scratch directory with a config (model, audit log and state inside it) saved there.
    fn setup(name: &str) -> (PathBuf, Config, PathBuf) {
        let dir = std::env::temp_dir().join(format!("handd-ms-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("scratch directory");
        let mut config = Config {
            model: dir.join("model.hsm"),
            state_dir: dir.clone(),
            ..Config::default()
        };
        config.control.audit_log = dir.join("audit.log");
        let path = dir.join("handd.toml");
        config.save_atomic(&path).expect("config saved");
        (dir, config, path)
    }

    fn message(r: &Reply) -> String {
        match r {
            Reply::Ok { message, .. } => message.clone(),
            Reply::Refused { reason } => format!("refused: {reason}"),
        }
    }

    #[test]
    fn a_deploy_that_times_out_is_cancelled_and_never_swapped_later() {
        let (dir, config, config_path) = setup("timeout");
        let model = dir.join("new.hsm");
        trained(5).save(&model).expect("model saved");
        let (tx, rx) = sync_channel(COMMAND_QUEUE);
        let mut handler =
            ControlHandler::new(config.clone(), config_path.clone(), Default::default(), tx)
                .with_swap_wait(Duration::from_millis(100));
        // No loop takes the command in time.
        let reply = handler.handle(
            Request::Deploy {
                path: model.display().to_string(),
                force: true,
                confirmed: true,
                check_only: false,
            },
            ROOT,
        );
        let m = message(&reply);
        assert!(m.starts_with("refused:") && m.contains("cancelled"), "{m}");
        assert_eq!(
            Config::load(&config_path).expect("config").model,
            config.model,
            "the config is restored"
        );
        assert_eq!(handler.status().model, None, "status names no new model");
        // The loop comes back and takes the queued swap: it is not applied.
        let chain = ChainConfig::default().validate().expect("chain");
        let mut engine = Engine::new(&chain, trained(3).predictor(), EngineSettings::default(), 0);
        engine.validated(0);
        let id = engine.model_id();
        let cmd = rx.try_recv().expect("the swap was queued");
        assert!(matches!(cmd, Command::Swap(_)));
        engine.command(10, cmd).expect("applied");
        assert_eq!(engine.model_id(), id, "the running model is unchanged");
        assert!(!engine.faults().contains(Fault::ModelSwapped));
        std::fs::remove_dir_all(&dir).expect("clean up");
    }

    /// A stand-in loop: applies each command to nothing but publishes the latches a `stop`
    /// or an `arm` leaves, like the real loop's tick.
    fn fake_loop(
        rx: std::sync::mpsc::Receiver<Command>,
        mut publisher: persist::LatchPublisher,
    ) -> std::thread::JoinHandle<()> {
        std::thread::spawn(move || {
            while let Ok(cmd) = rx.recv() {
                let mut faults = FaultSet::default();
                if matches!(cmd, Command::Stop) {
                    faults.insert(Fault::StopRequested);
                }
                publisher.publish(Latches::of(faults, crate::engine::Hold::Free));
            }
        })
    }

    fn audit_lines(p: &Path) -> Vec<String> {
        std::fs::read_to_string(p)
            .expect("audit log")
            .lines()
            .map(str::to_owned)
            .collect()
    }

    #[test]
    fn stop_answers_once_its_latch_is_saved_and_stop_and_arm_are_audited() {
        let (dir, config, config_path) = setup("stop");
        let file = persist::latch_path(&dir);
        let (publisher, store) = persist::spawn_writer(file.clone(), None).expect("writer");
        let (tx, rx) = sync_channel(COMMAND_QUEUE);
        let looper = fake_loop(rx, publisher);
        let mut handler = ControlHandler::new(config.clone(), config_path, Default::default(), tx)
            .with_model(crate::protocol::ModelStatus {
                path: "/m.hsm".into(),
                id: "00000001".into(),
                kind: "resdd".into(),
                verification: "verified".into(),
                unverified: false,
                ..Default::default()
            })
            .with_latches(store, crate::engine::Hold::Free);
        let m = message(&handler.handle(Request::Stop, ROOT));
        assert!(
            m.contains("saved in") && m.contains("a restart of handd keeps it"),
            "{m}"
        );
        assert_eq!(
            persist::load(&file)
                .on_disk()
                .map(|l| l.faults.contains(Fault::StopRequested)),
            Some(true),
            "on disk when stop answers"
        );
        let m = message(&handler.handle(
            Request::Arm {
                force_rest_mismatch: false,
            },
            ROOT,
        ));
        assert!(m.starts_with("armed"), "{m}");
        let lines = audit_lines(&config.control.audit_log);
        assert_eq!(lines.len(), 2, "{lines:?}");
        for (line, action) in lines.iter().zip(["stop", "arm rest=unchecked"]) {
            assert!(
                line.starts_with("time=") && line.contains(" mono=") && line.ends_with(action),
                "{line}"
            );
        }
        drop(handler);
        looper.join().expect("loop");
        // The writer thread may still be saving the last set: a best-effort clean-up.
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn a_stop_whose_latch_is_not_saved_says_so() {
        let (dir, config, config_path) = setup("unsaved");
        // The state directory's place is taken by a file: nothing can be saved there.
        let blocked = dir.join("blocked");
        std::fs::write(&blocked, "not a directory").expect("file");
        let (publisher, store) =
            persist::spawn_writer(persist::latch_path(&blocked), None).expect("writer");
        let (tx, rx) = sync_channel(COMMAND_QUEUE);
        let looper = fake_loop(rx, publisher);
        let mut handler = ControlHandler::new(config, config_path, Default::default(), tx)
            .with_latches(store, crate::engine::Hold::Free);
        let m = message(&handler.handle(Request::Stop, ROOT));
        assert!(
            m.starts_with("stopped") && m.contains("NOT confirmed saved"),
            "{m}"
        );
        drop(handler);
        looper.join().expect("loop");
        // The writer thread may still be saving the last set: a best-effort clean-up.
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn deploy_and_rollback_audit_the_model_they_replace() {
        let (dir, config, config_path) = setup("previous");
        let model = dir.join("new.hsm");
        trained(6).save(&model).expect("model saved");
        // The running model's file, there for the rollback to find it unchanged.
        trained(4).save(&config.model).expect("model saved");
        let running_id = format!(
            "{:08x}",
            crate::startup::fingerprint(&std::fs::read(&config.model).expect("read"))
        );
        let (tx, rx) = sync_channel::<Command>(COMMAND_QUEUE);
        // A stand-in loop that swaps every model it is given.
        let looper = std::thread::spawn(move || {
            while let Ok(cmd) = rx.recv() {
                if let Command::Swap(mut m) = cmd {
                    assert!(m.ticket.take(), "a pending ticket");
                    m.swapped = true;
                    let back = m.back.take().expect("a way back");
                    back.send(m).expect("the sender waits");
                }
            }
        });
        let mut handler = ControlHandler::new(config.clone(), config_path, Default::default(), tx)
            .with_model(crate::protocol::ModelStatus {
                path: config.model.display().to_string(),
                id: running_id.clone(),
                kind: "resdd".into(),
                verification: "verified".into(),
                unverified: false,
                ..Default::default()
            });
        let reply = handler.handle(
            Request::Deploy {
                path: model.display().to_string(),
                force: true,
                confirmed: true,
                check_only: false,
            },
            ROOT,
        );
        assert!(matches!(reply, Reply::Ok { .. }), "{}", message(&reply));
        let new_id = handler.status().model.expect("a model").id;
        let reply = handler.handle(Request::Rollback, ROOT);
        assert!(matches!(reply, Reply::Ok { .. }), "{}", message(&reply));
        let lines = audit_lines(&config.control.audit_log);
        assert_eq!(lines.len(), 2, "{lines:?}");
        assert!(
            lines[0].contains(&format!(" deploy path={}", model.display()))
                && lines[0].contains(&format!(" id={new_id} previous={running_id} ")),
            "{}",
            lines[0]
        );
        assert!(
            lines[1].contains(" rollback ")
                && lines[1].contains(&format!(" id={running_id} previous={new_id} ")),
            "{}",
            lines[1]
        );
        drop(handler);
        looper.join().expect("loop");
        std::fs::remove_dir_all(&dir).expect("clean up");
    }

    /// A stand-in loop that swaps like the real one: it keeps the running model and sends the
    /// one replaced back; `running` is the id it runs, `swaps` how many swaps it took.
    struct SwapLoop {
        running: std::sync::Arc<std::sync::Mutex<u32>>,
        swaps: std::sync::Arc<std::sync::atomic::AtomicUsize>,
        thread: std::thread::JoinHandle<()>,
    }

    fn swap_loop(
        rx: std::sync::mpsc::Receiver<Command>,
        first: &TrainedModel,
        id: u32,
    ) -> SwapLoop {
        use std::sync::atomic::{AtomicUsize, Ordering};
        use std::sync::{Arc, Mutex};
        let running = Arc::new(Mutex::new(id));
        let swaps = Arc::new(AtomicUsize::new(0));
        let (r, n) = (Arc::clone(&running), Arc::clone(&swaps));
        let mut current = (Some(first.predictor()), id);
        let thread = std::thread::spawn(move || {
            while let Ok(cmd) = rx.recv() {
                if let Command::Swap(mut m) = cmd {
                    assert!(m.ticket.take(), "a pending ticket");
                    std::mem::swap(&mut m.predictor, &mut current.0);
                    std::mem::swap(&mut m.model_id, &mut current.1);
                    *r.lock().expect("lock") = current.1;
                    n.fetch_add(1, Ordering::SeqCst);
                    m.swapped = true;
                    let back = m.back.take().expect("a way back");
                    back.send(m).expect("the sender waits");
                }
            }
        });
        SwapLoop {
            running,
            swaps,
            thread,
        }
    }

    fn with_patient(model: TrainedModel, patient: &str) -> TrainedModel {
        model
            .with_provenance(decoder::model::Provenance {
                patient: Some(patient.into()),
                session: "fitting-1".into(),
                calibrated_utc: "2026-12-02T13:15:28Z".into(),
                ignore_gates: false,
                gates_bypassed: Vec::new(),
            })
            .expect("provenance")
    }

    /// A handler over a [`swap_loop`] running the model saved at the config's model path.
    fn running(
        config: &Config,
        config_path: &Path,
        model: &TrainedModel,
    ) -> (ControlHandler, SwapLoop) {
        model.save(&config.model).expect("model saved");
        let loaded = crate::startup::load_model(&config.model, config.mains_hz).expect("loads");
        let (tx, rx) = sync_channel::<Command>(COMMAND_QUEUE);
        let looper = swap_loop(rx, model, loaded.model_id);
        let handler = ControlHandler::new(
            config.clone(),
            config_path.to_owned(),
            Default::default(),
            tx,
        )
        .with_model(loaded.status(&config.model));
        (handler, looper)
    }

    fn deploy(h: &mut ControlHandler, path: &Path, confirmed: bool) -> Reply {
        h.handle(
            Request::Deploy {
                path: path.display().to_string(),
                force: true,
                confirmed,
                check_only: false,
            },
            ROOT,
        )
    }

    fn id_of(path: &Path) -> u32 {
        crate::startup::fingerprint(&std::fs::read(path).expect("model file"))
    }

    #[test]
    fn a_model_for_another_patient_needs_the_confirmation() {
        use std::sync::atomic::Ordering;
        let (dir, config, config_path) = setup("patient");
        let first = with_patient(trained(1), "P-001");
        let (mut handler, looper) = running(&config, &config_path, &first);
        let id_a = id_of(&config.model);
        let other = dir.join("other.hsm");
        with_patient(trained(2), "P-002")
            .save(&other)
            .expect("saved");
        let unknown = dir.join("unknown.hsm");
        trained(3).save(&unknown).expect("saved");
        // Another patient, and an unknown one: refused, nothing changed.
        for (file, words) in [(&other, "patient P-002"), (&unknown, "unknown patient")] {
            let m = message(&deploy(&mut handler, file, false));
            assert!(
                m.starts_with("refused:")
                    && m.contains(&format!(
                        "this model is for {words}, the running model (id {id_a:08x}) for \
                         patient P-001"
                    ))
                    && m.contains("confirmation"),
                "{m}"
            );
            assert_eq!(looper.swaps.load(Ordering::SeqCst), 0, "nothing swapped");
            assert_eq!(*looper.running.lock().unwrap(), id_a);
            assert_eq!(
                Config::load(&config_path).expect("config").model,
                config.model
            );
            assert_eq!(
                handler.status().model.expect("model").id,
                format!("{id_a:08x}")
            );
        }
        // Only a check: passes (the patient is handctl's question), nothing changes.
        let m = message(&handler.handle(
            Request::Deploy {
                path: other.display().to_string(),
                force: true,
                confirmed: false,
                check_only: true,
            },
            ROOT,
        ));
        assert!(
            m.starts_with("checked: ") && m.ends_with("nothing changed"),
            "{m}"
        );
        assert_eq!(looper.swaps.load(Ordering::SeqCst), 0, "nothing swapped");
        assert!(!config.control.audit_log.exists(), "nothing audited");
        // The same patient needs no confirmation.
        let same = dir.join("same.hsm");
        with_patient(trained(4), "P-001")
            .save(&same)
            .expect("saved");
        let reply = deploy(&mut handler, &same, false);
        assert!(matches!(reply, Reply::Ok { .. }), "{}", message(&reply));
        assert_eq!(*looper.running.lock().unwrap(), id_of(&same));
        // Another patient, confirmed: deployed, and the audit line says so.
        let reply = deploy(&mut handler, &other, true);
        assert!(matches!(reply, Reply::Ok { .. }), "{}", message(&reply));
        let id_b = id_of(&other);
        assert_eq!(*looper.running.lock().unwrap(), id_b);
        let st = handler.status().model.expect("model");
        assert_eq!(
            (st.id, st.patient.as_deref()),
            (format!("{id_b:08x}"), Some("P-002"))
        );
        let lines = audit_lines(&config.control.audit_log);
        assert_eq!(lines.len(), 2, "{lines:?}");
        assert!(
            lines[1].contains(&format!(" id={id_b:08x} "))
                && lines[1].ends_with(" patient=P-002 confirmed=true"),
            "{}",
            lines[1]
        );
        drop(handler);
        looper.thread.join().expect("loop");
        std::fs::remove_dir_all(&dir).expect("clean up");
    }

    #[test]
    fn rollback_refuses_a_replaced_file_whose_bytes_changed() {
        let (dir, config, config_path) = setup("replaced");
        let first = trained(1);
        let (mut handler, looper) = running(&config, &config_path, &first);
        let id_a = id_of(&config.model);
        let original = std::fs::read(&config.model).expect("model A");
        let new = dir.join("new.hsm");
        trained(2).save(&new).expect("saved");
        let id_b = id_of(&new);
        let reply = deploy(&mut handler, &new, true);
        assert!(matches!(reply, Reply::Ok { .. }), "{}", message(&reply));
        let installed = Config::load(&config_path).expect("config").model;
        // Model A's file is overwritten with another model.
        trained(9).save(&config.model).expect("saved");
        let m = message(&handler.handle(Request::Rollback, ROOT));
        assert!(
            m.starts_with("refused:")
                && m.contains(&format!("{}, changed on disk", config.model.display()))
                && m.contains(&format!("the model kept in memory is {id_a:08x}")),
            "{m}"
        );
        assert_eq!(*looper.running.lock().unwrap(), id_b, "B still runs");
        assert_eq!(Config::load(&config_path).expect("config").model, installed);
        assert_eq!(
            handler.status().model.expect("model").id,
            format!("{id_b:08x}")
        );
        assert_eq!(
            audit_lines(&config.control.audit_log).len(),
            1,
            "no rollback line"
        );
        // A's bytes back: the rollback kept for later goes through.
        std::fs::write(&config.model, &original).expect("restored");
        let reply = handler.handle(Request::Rollback, ROOT);
        assert!(matches!(reply, Reply::Ok { .. }), "{}", message(&reply));
        assert_eq!(*looper.running.lock().unwrap(), id_a);
        assert_eq!(
            Config::load(&config_path).expect("config").model,
            config.model
        );
        drop(handler);
        looper.thread.join().expect("loop");
        std::fs::remove_dir_all(&dir).expect("clean up");
    }

    #[test]
    fn an_unwritable_audit_log_refuses_deploy_and_rollback_with_nothing_changed() {
        use std::sync::atomic::Ordering;
        let (dir, config, config_path) = setup("audit");
        let first = trained(1);
        let (mut handler, looper) = running(&config, &config_path, &first);
        let id_a = id_of(&config.model);
        let new = dir.join("new.hsm");
        trained(2).save(&new).expect("saved");
        let id_b = id_of(&new);
        // The audit log's place is taken by a directory: no line can be appended.
        std::fs::create_dir_all(&config.control.audit_log).expect("directory");
        let config_before = std::fs::read(&config_path).expect("config");
        let m = message(&deploy(&mut handler, &new, true));
        assert!(
            m.starts_with("refused: the audit log")
                && m.contains("could not be written")
                && m.ends_with("nothing changed"),
            "{m}"
        );
        assert_eq!(looper.swaps.load(Ordering::SeqCst), 0, "nothing swapped");
        assert_eq!(*looper.running.lock().unwrap(), id_a);
        assert_eq!(std::fs::read(&config_path).expect("config"), config_before);
        assert_eq!(
            handler.status().model.expect("model").id,
            format!("{id_a:08x}")
        );
        assert!(!crate::deploy::installed_path(&config.model, id_b).exists());
        // With the log writable the deploy goes through; then a rollback without it is
        // refused the same way.
        std::fs::remove_dir(&config.control.audit_log).expect("removed");
        let reply = deploy(&mut handler, &new, true);
        assert!(matches!(reply, Reply::Ok { .. }), "{}", message(&reply));
        std::fs::remove_file(&config.control.audit_log).expect("removed");
        std::fs::create_dir_all(&config.control.audit_log).expect("directory");
        let config_before = std::fs::read(&config_path).expect("config");
        let m = message(&handler.handle(Request::Rollback, ROOT));
        assert!(m.starts_with("refused: the audit log"), "{m}");
        assert_eq!(
            looper.swaps.load(Ordering::SeqCst),
            1,
            "only the deploy swapped"
        );
        assert_eq!(*looper.running.lock().unwrap(), id_b);
        assert_eq!(std::fs::read(&config_path).expect("config"), config_before);
        assert_eq!(
            handler.status().model.expect("model").id,
            format!("{id_b:08x}")
        );
        drop(handler);
        looper.thread.join().expect("loop");
        std::fs::remove_dir_all(&dir).expect("clean up");
    }
}
