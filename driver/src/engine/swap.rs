//! Models swapped in at a tick boundary, and the calibrating hold.
//!
//! One rule for every model change (a deploy, a rollback, `--force` included): the new model
//! never takes over a moving hand. The swap latches [`Fault::ModelSwapped`]: SAFE at once,
//! safe stops to every finger (a new epoch, so nothing of the old model's setpoints survives),
//! every conditioner back to rest, and the hand moves again only after `arm`, when each finger
//! starts from rest with its gains ramping in. From the patient's side: a new model is a new
//! map from effort to motion, and the first motion under it should come when the patient and the
//! technician expect it, not in the middle of a grip at whatever velocity the old model had
//! wound up. The cost is one `handctl arm` after a deploy, in the technician's presence anyway.
//!
//! A deploy prepares the model off the loop (file read, checks, the predictor's buffers all
//! allocated by the control thread) and hands it over boxed in a [`Command::Swap`]; the tick
//! that takes the command swaps the predictor and the model id by moving them, and sends the
//! box, now holding the model that ran until then, back to the sender (a bounded channel's
//! `try_send`: no allocation, no waiting). The chain and its filter state stay, so the new
//! model runs on the very next tick's window and no tick is skipped.
//!
//! A deploy whose reply timed out must not swap later behind the technician's back: every swap
//! carries a [`SwapTicket`] that either the loop takes (and swaps) or the control side cancels
//! (and the loop then sends the box back unswapped), never both.
//!
//! The calibrating hold ([`Command::Calibrating`]) latches [`Fault::Calibrating`]: the state is
//! SAFE and every finger gets SAFE_STOP setpoints (zero force, zero velocity, brake), the same
//! frames every other stop sends. `arm` is refused until a model has been swapped in after the
//! hold began (a deploy, a rollback, or redeploying the running model after an aborted
//! calibration); the `arm` that follows clears the hold.

use std::sync::atomic::{AtomicU8, Ordering};
use std::sync::mpsc::SyncSender;
use std::sync::Arc;

use decoder::model::Predictor;

use super::{Command, Engine};
use crate::safety::{ArmError, Fault};

/// A prepared model on its way to the loop, and the way back for the model it replaces.
#[derive(Debug, Clone)]
pub struct ModelSwap {
    /// The model's predictor (None only for the "no model" a daemon may start with).
    pub predictor: Option<Predictor>,
    /// Its identity for HAND_HEARTBEAT.
    pub model_id: u32,
    /// Where the box goes back after the swap, holding the model replaced.
    pub back: Option<SyncSender<Box<ModelSwap>>>,
    /// Set by the loop when it swapped (false: the predictor did not fit, or the swap was
    /// cancelled; nothing changed).
    pub swapped: bool,
    /// Taken by the loop or cancelled by the sender, whichever comes first.
    pub ticket: SwapTicket,
}

/// Who decides a swap: the loop takes the ticket before it swaps, the sender cancels it when
/// it gives up waiting; one compare-and-swap each, so exactly one of them wins.
#[derive(Debug, Clone, Default)]
pub struct SwapTicket(Arc<AtomicU8>);

const PENDING: u8 = 0;
const TAKEN: u8 = 1;
const CANCELLED: u8 = 2;

impl SwapTicket {
    /// A new, pending ticket.
    pub fn new() -> Self {
        Self::default()
    }

    /// The loop's side: true if the swap may go ahead (and then it can no longer be
    /// cancelled). No allocation.
    pub fn take(&self) -> bool {
        self.0
            .compare_exchange(PENDING, TAKEN, Ordering::AcqRel, Ordering::Acquire)
            .is_ok()
    }

    /// The sender's side: true if the swap is cancelled (the loop will not swap); false if the
    /// loop has taken it already (the swap happened or is happening: its reply is coming).
    pub fn cancel(&self) -> bool {
        self.0
            .compare_exchange(PENDING, CANCELLED, Ordering::AcqRel, Ordering::Acquire)
            .is_ok()
    }
}

/// Where the calibrating hold stands.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Hold {
    /// No hold.
    #[default]
    Free,
    /// Calibrating: `arm` is refused until a model is swapped in.
    Calibrating,
    /// A model was swapped in since the hold began: the next `arm` releases the hand.
    Deployed,
}

impl Engine {
    /// The calibrating hold now.
    pub fn hold(&self) -> Hold {
        self.hold
    }

    /// Whether a model runs (a daemon may start without one).
    pub fn has_model(&self) -> bool {
        self.predictor.is_some()
    }

    /// The model id HAND_HEARTBEAT carries now.
    pub fn model_id(&self) -> u32 {
        self.settings.model_id
    }

    /// Begins the calibrating hold: SAFE, safe stops, `arm` refused until a model is swapped in.
    pub(super) fn begin_hold(&mut self, now_us: u64) {
        self.hold = Hold::Calibrating;
        self.fault(now_us, Fault::Calibrating);
    }

    /// `arm`, refused during the calibrating hold and without a model.
    pub(super) fn arm(&mut self, now_us: u64) -> Result<(), ArmError> {
        if self.hold == Hold::Calibrating {
            return Err(ArmError::Calibrating);
        }
        if self.predictor.is_none() {
            return Err(ArmError::NoModel);
        }
        self.safety.arm(now_us)?;
        self.hold = Hold::Free;
        // Every CiA 402 drive with a latched fault starts again from scratch.
        if let Some(d) = &mut self.drives {
            d.arm();
        }
        Ok(())
    }

    /// Swaps in the model in `m` by moving it (no allocation) and sends the box back with the
    /// model replaced. The hand goes SAFE with [`Fault::ModelSwapped`] latched, every finger
    /// from rest, until `arm`: see the module docs. A predictor that does not take the chain's
    /// features (the control side checks this first) is sent back unswapped: its id comes back
    /// unchanged.
    /// Whether it was swapped in.
    pub(super) fn swap_model(&mut self, now_us: u64, mut m: Box<ModelSwap>) -> bool {
        let fits = m
            .predictor
            .as_ref()
            .is_some_and(|p| p.n_inputs() == self.emg.chain.settings().n_features())
            // Last: a ticket taken must be swapped (its sender then waits for the reply).
            && m.ticket.take();
        m.swapped = fits;
        if fits {
            if let Some(p) = &mut m.predictor {
                p.set_plausible_spread(self.settings.plausible_spread);
                p.set_pattern_margin(self.settings.pattern_margin);
            }
            std::mem::swap(&mut self.predictor, &mut m.predictor);
            std::mem::swap(&mut self.settings.model_id, &mut m.model_id);
            if self.hold == Hold::Calibrating {
                self.hold = Hold::Deployed;
            }
            // The new model never takes over a moving hand: SAFE (safe stops, every finger's
            // conditioner back to rest) until `arm`. A daemon that had no model never moved
            // the hand and refused `arm` until now: its first model needs no second `arm`.
            if m.predictor.is_some() {
                self.fault(now_us, Fault::ModelSwapped);
            }
            for c in &mut self.conditioners {
                c.reset();
            }
            self.labels = [0.0; crate::units::N_FINGERS];
        }
        if let Some(back) = m.back.take() {
            // A sender that gave up waiting has dropped its end: the box is dropped here then.
            let _ = back.try_send(m);
        }
        fits
    }
}

impl Command {
    /// A swap to `predictor` with id `model_id`, whose replaced model comes back on `back`.
    pub fn swap(predictor: Predictor, model_id: u32, back: SyncSender<Box<ModelSwap>>) -> Self {
        Command::Swap(Box::new(ModelSwap {
            predictor: Some(predictor),
            model_id,
            back: Some(back),
            swapped: false,
            ticket: SwapTicket::new(),
        }))
    }
}

#[cfg(test)]
mod tests {
    use decoder::dsp::ChainConfig;

    use super::*;
    use crate::engine::EngineSettings;
    use crate::safety::DaemonState;

    fn predictor() -> Predictor {
        crate::engine::test_support::random_predictor(3)
    }

    #[test]
    fn without_a_model_the_engine_is_safe_and_refuses_arm_until_a_swap() {
        let chain = ChainConfig::default().validate().expect("chain");
        let mut e = Engine::without_model(&chain, EngineSettings::default(), 0);
        e.validated(0);
        assert_eq!(e.state(), DaemonState::Safe);
        assert!(e.faults().contains(Fault::NoModel));
        assert_eq!(e.command(10, Command::Arm), Err(ArmError::NoModel));
        e.command(20, Command::Calibrating).expect("hold");
        let (tx, rx) = std::sync::mpsc::sync_channel(1);
        e.command(30, Command::swap(predictor(), 0xabcd, tx))
            .expect("swap");
        let old = rx.try_recv().expect("the replaced model comes back");
        assert!(old.swapped && old.predictor.is_none() && old.model_id == 0);
        assert_eq!((e.model_id(), e.hold()), (0xabcd, Hold::Deployed));
        e.command(40, Command::Arm).expect("arm after the swap");
        assert!(e.faults().is_empty() && e.hold() == Hold::Free);
    }

    #[test]
    fn a_swap_over_a_running_model_latches_safe_until_arm() {
        let chain = ChainConfig::default().validate().expect("chain");
        let mut e = Engine::new(&chain, predictor(), EngineSettings::default(), 0);
        e.validated(0);
        let (tx, rx) = std::sync::mpsc::sync_channel(1);
        e.command(30, Command::swap(predictor(), 0xbeef, tx))
            .expect("swap");
        assert!(rx.try_recv().expect("back").swapped);
        assert_eq!(e.state(), DaemonState::Safe);
        assert!(e.faults().contains(Fault::ModelSwapped), "{:?}", e.faults());
        assert_eq!(e.labels, [0.0; crate::units::N_FINGERS]);
        e.command(40, Command::Arm).expect("arm");
        assert!(!e.faults().contains(Fault::ModelSwapped));
    }

    #[test]
    fn a_cancelled_swap_comes_back_unswapped_and_a_taken_one_cannot_be_cancelled() {
        let chain = ChainConfig::default().validate().expect("chain");
        let mut e = Engine::new(&chain, predictor(), EngineSettings::default(), 0);
        e.validated(0);
        let id = e.model_id();
        let (tx, rx) = std::sync::mpsc::sync_channel(1);
        let cmd = Command::swap(predictor(), 0xbeef, tx);
        let Command::Swap(b) = &cmd else {
            unreachable!("a swap")
        };
        assert!(b.ticket.cancel(), "pending: the sender may cancel");
        e.command(30, cmd).expect("swap");
        let back = rx.try_recv().expect("sent back");
        assert!(!back.swapped && back.model_id == 0xbeef && back.predictor.is_some());
        assert_eq!(e.model_id(), id, "the running model did not change");
        assert!(!e.faults().contains(Fault::ModelSwapped));
        let t = SwapTicket::new();
        assert!(t.take() && !t.cancel() && !t.take(), "one winner");
    }

    #[test]
    fn a_predictor_that_does_not_fit_the_chain_comes_back_unswapped() {
        let chain = ChainConfig {
            channels: 10,
            ..ChainConfig::default()
        };
        let mut e = Engine::without_model(
            &chain.validate().expect("chain"),
            EngineSettings::default(),
            0,
        );
        let (tx, rx) = std::sync::mpsc::sync_channel(1);
        e.command(0, Command::swap(predictor(), 7, tx))
            .expect("swap");
        let back = rx.try_recv().expect("sent back");
        assert!(!back.swapped && back.model_id == 7 && back.predictor.is_some());
        assert!(!e.has_model());
    }
}
