//! Models swapped in at a tick boundary, and the calibrating hold.
//!
//! A deploy prepares the model off the loop (file read, checks, the predictor's buffers all
//! allocated by the control thread) and hands it over boxed in a [`Command::Swap`]; the tick
//! that takes the command swaps the predictor and the model id by moving them, and sends the
//! box, now holding the model that ran until then, back to the sender (a bounded channel's
//! `try_send`: no allocation, no waiting). The chain and its filter state stay, so the new
//! model runs on the very next tick's window and no tick is skipped.
//!
//! The calibrating hold ([`Command::Calibrating`]) latches [`Fault::Calibrating`]: the state is
//! SAFE and every finger gets SAFE_STOP setpoints (zero force, zero velocity, brake), the same
//! frames every other stop sends. `arm` is refused until a model has been swapped in after the
//! hold began (a deploy, a rollback, or redeploying the running model after an aborted
//! calibration); the `arm` that follows clears the hold.

use std::sync::mpsc::SyncSender;

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
    /// Set by the loop when it swapped (false: the predictor did not fit, nothing changed).
    pub swapped: bool,
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
        self.raise(now_us, Fault::Calibrating);
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
        Ok(())
    }

    /// Swaps in the model in `m` by moving it (no allocation) and sends the box back with the
    /// model replaced. A predictor that does not take the chain's features (the control side
    /// checks this first) is sent back unswapped: its id comes back unchanged.
    pub(super) fn swap_model(&mut self, mut m: Box<ModelSwap>) {
        let fits = m
            .predictor
            .as_ref()
            .is_some_and(|p| p.n_inputs() == self.emg.chain.settings().n_features());
        m.swapped = fits;
        if fits {
            std::mem::swap(&mut self.predictor, &mut m.predictor);
            std::mem::swap(&mut self.settings.model_id, &mut m.model_id);
            if self.hold == Hold::Calibrating {
                self.hold = Hold::Deployed;
            }
        }
        if let Some(back) = m.back.take() {
            // A sender that gave up waiting has dropped its end: the box is dropped here then.
            let _ = back.try_send(m);
        }
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
        }))
    }
}
