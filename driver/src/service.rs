//! The daemon's side of the technicians' protocol: answers `status`, applies `tune` (checked,
//! persisted atomically, audited, then handed to the loop for the next tick), `arm` and `stop`
//! (both audited; `stop` answers once its latch is saved for a restart, or says it is not).
//! Every request is checked completely before anything is applied. Commands reach the loop
//! through a bounded queue ([`COMMAND_QUEUE`]); the tick takes at most
//! [`crate::daemon::MAX_COMMANDS_PER_TICK`] per tick, so a flood of commands waits here (the
//! sender blocks) rather than lengthening a tick.

use std::path::PathBuf;
use std::sync::mpsc::SyncSender;

use decoder::dsp::ChainConfig;

use crate::config::Config;
use crate::control::Peer;
use crate::daemon::SharedSnapshot;
use crate::deploy::audit;
use crate::engine::{Command, Hold, ModelSwap};
use crate::persist::{LatchStore, STOP_SAVE_WAIT};
use crate::protocol::{FingerStatus, ModelStatus, Reply, Request, Status};
use crate::safety::Fault;
use crate::tuning::{commit_tune, plan_tune, user_name};
use crate::units::{FINGER_NAMES, N_FINGERS};

/// What the rest check before `arm` found: for the audit line and for the reply.
struct RestOutcome {
    audit: String,
    said: String,
}

/// Commands waiting for the loop at most; make the channel with
/// `std::sync::mpsc::sync_channel(COMMAND_QUEUE)`.
pub const COMMAND_QUEUE: usize = 16;

/// Handles control requests for a running loop.
pub struct ControlHandler {
    pub(crate) config: Config,
    pub(crate) config_path: PathBuf,
    snapshot: SharedSnapshot,
    commands: SyncSender<Command>,
    pub(crate) model: Option<ModelStatus>,
    /// The chain the loop runs: a deployed model must have the same.
    pub(crate) chain: ChainConfig,
    /// The model the last deploy or rollback replaced, with its status, for `rollback`.
    pub(crate) previous: Option<(Box<ModelSwap>, ModelStatus)>,
    /// The calibrating hold, as the loop has it (every change goes through here).
    pub(crate) hold: Hold,
    /// Whether the loop runs without a model (until a deploy).
    pub(crate) no_model: bool,
    /// The live feed's model, replaced on every deploy and rollback.
    pub(crate) live_model: Option<crate::control::SharedLiveModel>,
    /// The latch file's writer, when latches are kept (`stop` waits for its latch there).
    latches: Option<LatchStore>,
    /// How long a deploy or rollback waits for the loop to take the model.
    pub(crate) swap_wait: std::time::Duration,
    /// The running model's calibration rest level per channel (µV), when its file keeps it:
    /// `arm` compares the live rest pattern with it ([`crate::rest_check`]).
    pub(crate) model_rest: Option<Vec<f64>>,
}

impl ControlHandler {
    /// A handler for the loop behind `snapshot` and `commands`; `config` is what `config_path`
    /// holds now.
    pub fn new(
        config: Config,
        config_path: PathBuf,
        snapshot: SharedSnapshot,
        commands: SyncSender<Command>,
    ) -> Self {
        let chain = ChainConfig {
            mains_hz: config.mains_hz,
            ..ChainConfig::default()
        };
        Self {
            config,
            config_path,
            snapshot,
            commands,
            model: None,
            chain,
            previous: None,
            hold: Hold::Free,
            no_model: false,
            live_model: None,
            latches: None,
            swap_wait: crate::model_service::SWAP_WAIT,
            model_rest: None,
        }
    }

    /// The handler, for a running model whose file keeps these calibration rest levels (see
    /// [`decoder::model::TrainedModel::rest_rms_uv`]); `arm` compares the live ones with them.
    pub fn with_rest_levels(mut self, levels: Option<Vec<f64>>) -> Self {
        self.model_rest = levels;
        self
    }

    /// The handler, for a loop whose latches are kept by `store` (`crate::persist`), starting
    /// with the calibrating hold `hold` restored from it.
    pub fn with_latches(mut self, store: LatchStore, hold: Hold) -> Self {
        self.latches = Some(store);
        self.hold = hold;
        self
    }

    /// The handler, waiting `wait` (instead of [`crate::model_service::SWAP_WAIT`]) for the
    /// loop to take a deployed model; a test's loop that never takes it fails faster.
    pub fn with_swap_wait(mut self, wait: std::time::Duration) -> Self {
        self.swap_wait = wait;
        self
    }

    /// The handler, keeping the live feed's model (`LiveFeed::model`) up to date on deploy and
    /// rollback.
    pub fn with_live_model(mut self, live: crate::control::SharedLiveModel) -> Self {
        self.live_model = Some(live);
        self
    }

    /// The handler, for a loop running the chain `chain` (a deployed model must match it; the
    /// default chain at the config's mains frequency otherwise).
    pub fn with_chain(mut self, chain: ChainConfig) -> Self {
        self.chain = chain;
        self
    }

    /// The handler, for a loop started without a model: `arm` is refused until a deploy.
    pub fn without_model(mut self) -> Self {
        self.no_model = true;
        self
    }

    /// The handler, telling `status` which model runs.
    pub fn with_model(mut self, model: ModelStatus) -> Self {
        self.model = Some(model);
        self
    }

    /// The status as `handctl status` shows it.
    pub fn status(&self) -> Status {
        let s = *self.snapshot.lock().unwrap_or_else(|e| e.into_inner());
        Status {
            state: s.state.to_string(),
            faults: s.faults.to_string(),
            window: s.window.map(|w| w.to_string()),
            ticks: s.counters.ticks,
            deadline_misses: s.counters.deadline_misses,
            samples_lost: s.counters.samples_lost,
            bad_frames: s.counters.bad_frames,
            beyond_calibration: s.counters.beyond_calibration,
            implausible: s.counters.implausible,
            latency: s.latency,
            compute: s.compute,
            lateness: s.lateness,
            fingers: (0..N_FINGERS)
                .map(|f| FingerStatus {
                    label: s.setpoints[f].label,
                    force_n: s.setpoints[f].force.0,
                    velocity_rad_s: s.setpoints[f].velocity.0,
                    reported_force_n: s.reported_force[f],
                    disabled: s.disabled[f],
                    kf: s.gains[f].kf,
                    kalpha: s.gains[f].kalpha,
                })
                .collect(),
            model: self.model.clone(),
            bus: crate::protocol::BusStatus {
                controller: s.bus.state.name().into(),
                counters: s.bus.counters,
            },
            drives: crate::protocol::drive_lines(&s.drives, s.t_us),
            late_ticks: s.late_ticks().collect(),
        }
    }

    /// Hands `cmd` to the loop, waiting while its queue is full (a tick or two at most: the
    /// loop takes several per tick); fails only when the loop is gone.
    pub(crate) fn send(&self, cmd: Command) -> Result<(), Box<Reply>> {
        self.commands.send(cmd).map_err(|_| {
            Box::new(Reply::Refused {
                reason: "the control loop is not running; nothing changed".into(),
            })
        })
    }

    /// Answer one request from `peer`.
    pub fn handle(&mut self, req: Request, peer: Peer) -> Reply {
        let user = user_name(peer.uid);
        match req {
            Request::Status => Reply::Ok {
                message: "status".into(),
                status: Some(self.status()),
            },
            Request::Tune { finger, kf, kalpha } => self.tune(&finger, kf, kalpha, &user),
            Request::Calibrating => self.calibrating(peer, &user),
            Request::Deploy {
                path,
                force,
                check_only: true,
                ..
            } => self.check_deploy(&path, force),
            Request::Deploy {
                path,
                force,
                confirmed,
                check_only: false,
            } => self.deploy(&path, force, confirmed, peer, &user),
            Request::Rollback => self.rollback(peer, &user),
            Request::Arm {
                force_rest_mismatch,
            } => self.arm(peer, &user, force_rest_mismatch),
            Request::Subscribe { .. } => Reply::Refused {
                reason: "subscribe is served by the control socket, not by this handler".into(),
            },
            Request::Stop => self.stop(peer, &user),
        }
    }

    /// `stop`: handed to the loop, audited, and answered once the latch is on disk (so a
    /// restart keeps it), or with a plain warning that it could not be confirmed there.
    fn stop(&mut self, peer: Peer, user: &str) -> Reply {
        if let Err(r) = self.send(Command::Stop) {
            return *r;
        }
        audit(&self.config.control.audit_log, user, peer, "stop");
        tracing::warn!(user, "stopped by a technician");
        let saved = match &self.latches {
            None => String::new(),
            Some(store) => {
                if store.wait_written(|l| l.faults.contains(Fault::StopRequested), STOP_SAVE_WAIT) {
                    format!(
                        "; saved in {}: a restart of handd keeps it",
                        store.path().display()
                    )
                } else {
                    tracing::error!(path = %store.path().display(), "stop: the latch was not saved within {} s", STOP_SAVE_WAIT.as_secs());
                    format!(
                        "; WARNING: the stop was NOT confirmed saved in {} within {} s (see                          handd's log): a restart of handd may not keep it",
                        store.path().display(),
                        STOP_SAVE_WAIT.as_secs()
                    )
                }
            }
        };
        Reply::Ok {
            message: format!("stopped: every finger safe-stopped until `handctl arm`{saved}"),
            status: None,
        }
    }

    /// `arm`, refused while calibrating (until a deploy or rollback) and without a model, and
    /// refused when the live rest pattern differs from the running model's calibration unless
    /// `force_rest_mismatch` (audited).
    fn arm(&mut self, peer: Peer, user: &str, force_rest_mismatch: bool) -> Reply {
        let refused = match (self.hold, self.no_model) {
            (Hold::Calibrating, _) => Some(crate::safety::ArmError::Calibrating),
            (_, true) => Some(crate::safety::ArmError::NoModel),
            _ => None,
        };
        if let Some(e) = refused {
            return Reply::Refused {
                reason: e.to_string(),
            };
        }
        let rest = match self.rest_check(force_rest_mismatch) {
            Ok(r) => r,
            Err(reason) => {
                tracing::warn!(user, "arm refused: {reason}");
                return Reply::Refused { reason };
            }
        };
        match self.send(Command::Arm) {
            Ok(()) => {
                self.hold = Hold::Free;
                audit(
                    &self.config.control.audit_log,
                    user,
                    peer,
                    &format!("arm {}", rest.audit),
                );
                tracing::warn!(user, rest = %rest.audit, "armed by a technician");
                Reply::Ok {
                    message: format!(
                        "armed: latched faults cleared; the hand moves after 500 ms of good \
                         signal; {}",
                        rest.said
                    ),
                    status: None,
                }
            }
            Err(r) => *r,
        }
    }

    /// The rest check before `arm` ([`crate::rest_check`]) on the loop's last second: what to
    /// audit and say when the hand may be armed, the refusal otherwise.
    fn rest_check(&self, force: bool) -> Result<RestOutcome, String> {
        use crate::rest_check::{compare, live_levels};
        let Some(file) = &self.model_rest else {
            return Ok(RestOutcome {
                audit: "rest=unchecked".into(),
                said: "the running model's file keeps no rest levels: the live signal was not \
                       compared with its calibration"
                    .into(),
            });
        };
        let override_hint = "; nothing changed. Check the electrodes and that the patient is \
                             at rest, then arm again; `handctl arm --force-rest-mismatch` \
                             arms anyway (audited)";
        let snap = *self.snapshot.lock().unwrap_or_else(|e| e.into_inner());
        let checked = live_levels(&snap).and_then(|live| compare(file, &live));
        let c = match checked {
            Ok(c) => c,
            Err(e) if force => {
                return Ok(RestOutcome {
                    audit: "rest=FORCED-unchecked".into(),
                    said: format!("WARNING: armed without the rest check ({e})"),
                })
            }
            Err(e) => return Err(format!("rest check: {e}{override_hint}")),
        };
        if c.matches() {
            return Ok(RestOutcome {
                audit: format!("rest=match level={:.2}", c.level),
                said: format!(
                    "the live rest pattern matches the calibration ({})",
                    c.summary()
                ),
            });
        }
        let channels: Vec<String> = c.differing.iter().map(usize::to_string).collect();
        let channels = if channels.is_empty() {
            "pattern".to_owned()
        } else {
            channels.join(",")
        };
        if force {
            return Ok(RestOutcome {
                audit: format!(
                    "rest=MISMATCH-forced channels={channels} level={:.2}",
                    c.level
                ),
                said: format!(
                    "WARNING: armed although the live rest pattern differs from the \
                     calibration: {} ({})",
                    c.differences(),
                    c.summary()
                ),
            });
        }
        Err(format!(
            "the live rest pattern differs from the running model's calibration: {} ({}). \
             Swapped or shifted electrodes, or a model from another fitting, look like this; so \
             does a patient who is not at rest (arm compares the second before it was asked: \
             the patient must be relaxed){override_hint}",
            c.differences(),
            c.summary()
        ))
    }

    /// `tune`: checked completely, saved, then handed to the loop; refused with nothing
    /// changed on any failure.
    fn tune(&mut self, finger: &str, kf: Option<f64>, kalpha: Option<f64>, user: &str) -> Reply {
        let change = match plan_tune(&self.config, finger, kf, kalpha) {
            Ok(c) => c,
            Err(reason) => return Reply::Refused { reason },
        };
        let next = match commit_tune(&self.config, &change, &self.config_path, user) {
            Ok(n) => n,
            Err(reason) => return Reply::Refused { reason },
        };
        if let Err(r) = self.send(Command::SetGains(change.finger, change.new.gains())) {
            // Nothing partly applied: the loop never saw it, so the file goes back.
            if let Err(e) = self.config.save_atomic(&self.config_path) {
                tracing::error!(error = %e, "tune: the config could not be restored");
            }
            return *r;
        }
        self.config = next;
        tracing::info!(
            user,
            finger = FINGER_NAMES[change.finger],
            old_kf = change.old.kf,
            new_kf = change.new.kf,
            old_kalpha = change.old.kalpha,
            new_kalpha = change.new.kalpha,
            "tuned"
        );
        Reply::Ok {
            message: format!(
                "{}: kf {} -> {} N, kalpha {} -> {} rad/s²; takes effect at the next tick; saved to {}",
                FINGER_NAMES[change.finger],
                change.old.kf,
                change.new.kf,
                change.old.kalpha,
                change.new.kalpha,
                self.config_path.display()
            ),
            status: None,
        }
    }
}
