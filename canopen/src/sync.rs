//! SYNC (COB-ID 0x080) produced by the caller's control loop: no timer lives here, the loop
//! passes its own `now` and sends the frame when [`SyncProducer::poll`] returns it, so SYNC
//! stops when the loop stops.

use crate::frame::CanFrame;
use thiserror::Error;

/// The SYNC frame: COB-ID 0x080, no data (no counter).
pub fn sync_frame() -> CanFrame {
    CanFrame::from_parts(0x080, 0, [0; 8])
}

/// Whether `f` is a SYNC frame (with or without the optional counter byte).
pub fn is_sync(f: &CanFrame) -> bool {
    f.cob_id() == 0x080 && f.payload().len() <= 1
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
        })
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
                Some(sync_frame())
            }
        }
    }
}
