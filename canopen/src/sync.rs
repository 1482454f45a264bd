//! SYNC produced by the caller's control loop: no timer lives here, the loop passes its own
//! `now` and sends the frame when [`SyncProducer::poll`] returns it, so SYNC stops when the
//! loop stops. Its COB-ID is CiA 301's 0x080 unless set: on a bus whose 0x080 is taken (hand.dbc's
//! HAND_ESTOP) the start-up writes another to each drive's 0x1005 and the producer sends on it.

use crate::frame::CanFrame;
use crate::ids::CobId;
use thiserror::Error;

/// The SYNC frame on CiA 301's default COB-ID 0x080, no data (no counter).
pub fn sync_frame() -> CanFrame {
    sync_frame_on(CobId::SYNC)
}

/// The SYNC frame on `cob`, no data.
pub fn sync_frame_on(cob: CobId) -> CanFrame {
    CanFrame::from_parts(cob.raw(), 0, [0; 8])
}

/// Whether `f` is a SYNC frame on 0x080 (with or without the optional counter byte).
pub fn is_sync(f: &CanFrame) -> bool {
    is_sync_on(f, CobId::SYNC)
}

/// Whether `f` is a SYNC frame on `cob` (a node's 0x1005).
pub fn is_sync_on(f: &CanFrame, cob: CobId) -> bool {
    f.cob_id() == cob.raw() && f.payload().len() <= 1
}

/// A SYNC period of zero.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Error)]
#[error("SYNC period must be > 0 us")]
pub struct ZeroPeriod;

/// Emits SYNC once per period of the caller's clock.
#[derive(Clone, Debug)]
pub struct SyncProducer {
    period_us: u64,
    next_us: Option<u64>,
    cob: CobId,
}

impl SyncProducer {
    /// A producer with `period_us` > 0.
    pub fn try_new(period_us: u64) -> Result<Self, ZeroPeriod> {
        if period_us == 0 {
            return Err(ZeroPeriod);
        }
        Ok(Self {
            period_us,
            next_us: None,
            cob: CobId::SYNC,
        })
    }

    /// The same producer sending on `cob` (the drives' 0x1005) instead of 0x080.
    pub fn on_cob_id(self, cob: CobId) -> Self {
        Self { cob, ..self }
    }

    /// The period.
    pub fn period_us(&self) -> u64 {
        self.period_us
    }

    /// The SYNC frame if one is due at `now` (the first call always sends). A late call
    /// sends one SYNC, never a burst to catch up.
    pub fn poll(&mut self, now_us: u64) -> Option<CanFrame> {
        match self.next_us {
            Some(next) if now_us < next => None,
            _ => {
                self.next_us = Some(now_us.saturating_add(self.period_us));
                Some(sync_frame_on(self.cob))
            }
        }
    }
}
