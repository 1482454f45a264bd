//! Time for handstack: the daemon and the simulator read "now" from a [`Clock`].
//!
//! Every node is stepped with an explicit `now_us`, and whoever drives the nodes reads it from a
//! [`Clock`]: a [`VirtualClock`] in tests (advanced explicitly, so a minute of bus traffic runs in
//! well under a second and never depends on the machine's speed), a [`SystemClock`] in the daemon
//! and beside it on a real bus.

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use std::time::Instant;

/// A monotonic source of time in microseconds.
pub trait Clock {
    /// Microseconds since this clock's epoch; never decreases.
    fn now_us(&self) -> u64;
}

/// A shared clock that only moves when told to.
///
/// Clones share the same time, so the test loop, the bus (for receive timestamps) and the
/// nodes all agree on "now". Backed by an atomic so it can also be handed to threads.
#[derive(Debug, Clone, Default)]
pub struct VirtualClock {
    now: Arc<AtomicU64>,
}

impl VirtualClock {
    /// A clock at time 0.
    pub fn new() -> Self {
        Self::default()
    }

    /// A clock starting at `start_us`.
    pub fn starting_at(start_us: u64) -> Self {
        let c = Self::new();
        c.now.store(start_us, Ordering::SeqCst);
        c
    }

    /// Moves time forward by `dt_us` and returns the new time.
    pub fn advance_us(&self, dt_us: u64) -> u64 {
        self.now.fetch_add(dt_us, Ordering::SeqCst) + dt_us
    }

    /// Sets the time to `t_us`; a `t_us` in the past is ignored so time stays monotonic.
    /// Returns the time now in force.
    pub fn set_us(&self, t_us: u64) -> u64 {
        self.now.fetch_max(t_us, Ordering::SeqCst).max(t_us)
    }
}

impl Clock for VirtualClock {
    fn now_us(&self) -> u64 {
        self.now.load(Ordering::SeqCst)
    }
}

/// The machine's monotonic clock, counted from the moment this value was created.
#[derive(Debug, Clone, Copy)]
pub struct SystemClock {
    epoch: Instant,
}

impl SystemClock {
    /// A clock whose time 0 is now.
    pub fn new() -> Self {
        Self {
            epoch: Instant::now(),
        }
    }
}

impl Default for SystemClock {
    fn default() -> Self {
        Self::new()
    }
}

impl Clock for SystemClock {
    fn now_us(&self) -> u64 {
        // u64 microseconds last 584,000 years: the truncation from u128 cannot bite.
        self.epoch.elapsed().as_micros() as u64
    }
}

impl<C: Clock + ?Sized> Clock for &C {
    fn now_us(&self) -> u64 {
        (**self).now_us()
    }
}

impl<C: Clock + ?Sized> Clock for Arc<C> {
    fn now_us(&self) -> u64 {
        (**self).now_us()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn virtual_clock_is_shared_and_monotonic() {
        let a = VirtualClock::new();
        let b = a.clone();
        assert_eq!(a.advance_us(1500), 1500);
        assert_eq!(b.now_us(), 1500);
        assert_eq!(
            b.set_us(1000),
            1500,
            "setting the past must not move time back"
        );
        assert_eq!(b.set_us(4000), 4000);
        assert_eq!(a.now_us(), 4000);
    }

    #[test]
    fn system_clock_does_not_go_back() {
        let c = SystemClock::new();
        let t0 = c.now_us();
        let t1 = c.now_us();
        assert!(t1 >= t0);
    }
}
