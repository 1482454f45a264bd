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
        let prepared = match prepare(path, &self.chain, force) {
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

    /// The live lines name the model now running, with its file's rest levels (read here, on
    /// the control thread; a file that no longer reads gives none: they are for display only).
    fn tell_live(&self, status: &ModelStatus) {
        let Some(live) = &self.live_model else {
            return;
        };
        let rest_rms_uv = decoder::model::TrainedModel::load(&status.path, None)
            .ok()
            .and_then(|m| m.rest_rms_uv().map(<[f64]>::to_vec));
        *live.lock().unwrap_or_else(|e| e.into_inner()) = crate::control::LiveModel {
            info: crate::live::ModelInfo {
                id: status.id.clone(),
                path: status.path.clone(),
                kind: status.kind.clone(),
            },
            rest_rms_uv,
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
