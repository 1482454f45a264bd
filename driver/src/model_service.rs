//! The control side of `calibrating`, `deploy` and `rollback`: the checks and the file work run
//! here, on the control thread; the loop only moves the prepared model in at a tick boundary
//! and sends the one it replaced back ([`crate::engine::ModelSwap`]), which is kept for
//! `rollback`. Every action is audited with who asked (user, uid, pid).

use std::sync::mpsc::sync_channel;
use std::time::Duration;

use crate::control::Peer;
use crate::deploy::{audit, install, point_config, prepare, DeployError};
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

    /// `deploy`: checked, installed, swapped in; refused with nothing changed otherwise.
    pub(crate) fn deploy(&mut self, path: &str, force: bool, peer: Peer, user: &str) -> Reply {
        let prepared = match prepare(path, &self.chain, &self.config.deploy, force) {
            Ok(p) => p,
            Err(e) => return refused(e),
        };
        let (next, target) = match install(&prepared, &self.config, &self.config_path) {
            Ok(x) => x,
            Err(e) => return refused(e),
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
                return refused(e);
            }
        };
        self.config = next;
        let replaced = self.model.replace(status.clone());
        let previous = replaced.as_ref().map_or("none".into(), |s| s.id.clone());
        self.previous = match (old.predictor.is_some(), replaced) {
            (true, Some(s)) => Some((old, s)),
            _ => None,
        };
        self.after_swap("deploy", &status, &previous, path, peer, user, force)
    }

    /// `rollback`: the model the last deploy or rollback replaced comes back (so a second
    /// rollback undoes the first).
    pub(crate) fn rollback(&mut self, peer: Peer, user: &str) -> Reply {
        let Some((mut back, status)) = self.previous.take() else {
            return refused(DeployError::NoPrevious);
        };
        let next = match point_config(
            &self.config,
            std::path::Path::new(&status.path),
            &self.config_path,
        ) {
            Ok(n) => n,
            Err(e) => {
                self.previous = Some((back, status));
                return refused(e);
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
                return refused(e);
            }
        };
        self.config = next;
        let replaced = self.model.replace(status.clone());
        let previous = replaced.as_ref().map_or("none".into(), |s| s.id.clone());
        self.previous = replaced.map(|s| (old, s));
        let path = status.path.clone();
        self.after_swap("rollback", &status, &previous, &path, peer, user, false)
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

    /// Audit, log, release the calibrating hold's first condition, and the reply; `previous` is
    /// the id of the model replaced ("none" when there was none).
    #[allow(clippy::too_many_arguments, reason = "one audit line's fields")]
    fn after_swap(
        &mut self,
        action: &str,
        status: &ModelStatus,
        previous: &str,
        source: &str,
        peer: Peer,
        user: &str,
        force: bool,
    ) -> Reply {
        self.no_model = false;
        self.tell_live(status);
        if self.hold == Hold::Calibrating {
            self.hold = Hold::Deployed;
        }
        let what = format!(
            "{action} path={source} installed={} id={} previous={previous} force={force}",
            status.path, status.id
        );
        audit(&self.config.control.audit_log, user, peer, &what);
        tracing::warn!(user, uid = peer.uid, pid = peer.pid, model = %status.path, id = %status.id, "{action}");
        let arm = if self.hold == Hold::Deployed {
            "; the hand stays held until `handctl arm`"
        } else {
            ""
        };
        Reply::Ok {
            message: format!(
                "{action}: model {} (id {}) runs from this tick on; the config names it{arm}",
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
                id: "0000abcd".into(),
                kind: "resdd".into(),
                verification: "verified".into(),
                unverified: false,
            });
        let reply = handler.handle(
            Request::Deploy {
                path: model.display().to_string(),
                force: true,
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
                && lines[0].contains(&format!(" id={new_id} previous=0000abcd ")),
            "{}",
            lines[0]
        );
        assert!(
            lines[1].contains(" rollback ")
                && lines[1].contains(&format!(" id=0000abcd previous={new_id} ")),
            "{}",
            lines[1]
        );
        drop(handler);
        looper.join().expect("loop");
        std::fs::remove_dir_all(&dir).expect("clean up");
    }
}
