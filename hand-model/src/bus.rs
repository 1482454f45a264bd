//! An in-memory CAN bus, so the daemon and the simulated nodes can talk without a kernel.
//!
//! [`MemBus`] is a broadcast medium: every frame one [`MemEndpoint`] transmits is queued, in
//! transmission order, at every *other* endpoint (like SocketCAN without `recv_own_msgs`).
//! There is no arbitration and no bit time: a transmit is delivered at once. Each endpoint has a
//! bounded receive queue; when it is full the newest frame is dropped and the endpoint's overflow
//! counter goes up, as a CAN controller's RX overrun does, so a stalled reader is visible rather
//! than an unbounded memory leak. If the bus was given a [`Clock`], every queued frame carries the
//! receive time in µs ([`MemEndpoint::receive_timestamped`]).
//!
//! Endpoints implement `embedded_can::nb::Can` (receive returns `WouldBlock` when the queue is
//! empty) and `embedded_can::blocking::Can` (receive waits for a frame from another thread, and
//! fails with [`MemBusError::NoPeers`] rather than wait forever when no other endpoint exists).

use std::collections::VecDeque;
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::time::Duration;

use crate::dbc::CanFrame;

use crate::clock::Clock;

/// Default receive-queue depth of an endpoint: one second of the amplifier's 3,000 frames/s with
/// room to spare.
pub const DEFAULT_QUEUE_CAPACITY: usize = 4096;

/// What can go wrong on the in-memory bus.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum MemBusError {
    /// The bus was switched to bus-off ([`MemBus::set_bus_off`]); nothing can be sent.
    #[error("the in-memory bus is bus-off")]
    BusOff,
    /// A blocking receive found an empty queue and no other endpoint that could ever send.
    #[error("blocking receive on a bus with no other endpoint would wait forever")]
    NoPeers,
}

impl embedded_can::Error for MemBusError {
    fn kind(&self) -> embedded_can::ErrorKind {
        embedded_can::ErrorKind::Other
    }
}

/// A frame as it arrived at an endpoint.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Received<F = CanFrame> {
    /// The frame.
    pub frame: F,
    /// Receive time from the bus clock, if the bus has one.
    pub time_us: Option<u64>,
}

struct Queue<F> {
    frames: VecDeque<Received<F>>,
    overflows: u64,
}

struct Shared<F> {
    queues: Vec<Option<Queue<F>>>,
    capacity: usize,
    clock: Option<Arc<dyn Clock + Send + Sync>>,
    bus_off: bool,
    frames_sent: u64,
}

impl<F> Shared<F> {
    fn live_endpoints(&self) -> usize {
        self.queues.iter().filter(|q| q.is_some()).count()
    }
}

type Inner<F> = Arc<(Mutex<Shared<F>>, Condvar)>;

fn lock<F>(inner: &Inner<F>) -> MutexGuard<'_, Shared<F>> {
    // A panic in another test thread must not turn every later bus access into a second panic.
    inner.0.lock().unwrap_or_else(|e| e.into_inner())
}

/// An in-memory broadcast CAN bus. Cloning gives another handle to the same bus.
pub struct MemBus<F = CanFrame> {
    inner: Inner<F>,
}

impl<F> Clone for MemBus<F> {
    fn clone(&self) -> Self {
        Self {
            inner: Arc::clone(&self.inner),
        }
    }
}

impl<F> std::fmt::Debug for MemBus<F> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let s = lock(&self.inner);
        f.debug_struct("MemBus")
            .field("endpoints", &s.live_endpoints())
            .field("capacity", &s.capacity)
            .field("frames_sent", &s.frames_sent)
            .field("bus_off", &s.bus_off)
            .finish()
    }
}

impl Default for MemBus<CanFrame> {
    fn default() -> Self {
        Self::new()
    }
}

// Constructors live on `MemBus<CanFrame>` (as `HashMap::new` lives on the default hasher), so
// `MemBus::new()` needs no type annotation; other frame types use `for_frames`.
impl MemBus<CanFrame> {
    /// A bus without clock (frames carry no receive time) and the default queue depth.
    pub fn new() -> Self {
        Self::for_frames(None)
    }

    /// A bus whose endpoints stamp every received frame with `clock`'s time.
    pub fn with_clock(clock: impl Clock + Send + Sync + 'static) -> Self {
        Self::for_frames(Some(Arc::new(clock)))
    }
}

impl<F: Clone> MemBus<F> {
    /// A bus carrying frames of type `F`, optionally with a receive clock.
    pub fn for_frames(clock: Option<Arc<dyn Clock + Send + Sync>>) -> Self {
        Self::build(DEFAULT_QUEUE_CAPACITY, clock)
    }

    /// Sets the receive-queue depth of endpoints created from now on (at least 1).
    pub fn with_capacity(self, capacity: usize) -> Self {
        lock(&self.inner).capacity = capacity.max(1);
        self
    }

    fn build(capacity: usize, clock: Option<Arc<dyn Clock + Send + Sync>>) -> Self {
        Self {
            inner: Arc::new((
                Mutex::new(Shared {
                    queues: Vec::new(),
                    capacity: capacity.max(1),
                    clock,
                    bus_off: false,
                    frames_sent: 0,
                }),
                Condvar::new(),
            )),
        }
    }

    /// Attaches a new node to the bus. It receives every frame transmitted from now on by any
    /// other endpoint.
    pub fn endpoint(&self) -> MemEndpoint<F> {
        let mut s = lock(&self.inner);
        let capacity = s.capacity;
        let q = Queue {
            frames: VecDeque::with_capacity(capacity),
            overflows: 0,
        };
        // Reuse the slot of a dropped endpoint so a long test that opens and closes endpoints
        // does not grow the table.
        let index = match s.queues.iter().position(Option::is_none) {
            Some(i) => {
                s.queues[i] = Some(q);
                i
            }
            None => {
                s.queues.push(Some(q));
                s.queues.len() - 1
            }
        };
        MemEndpoint {
            inner: Arc::clone(&self.inner),
            index,
        }
    }

    /// Frames transmitted on this bus so far (each counted once, however many receivers).
    pub fn frames_sent(&self) -> u64 {
        lock(&self.inner).frames_sent
    }

    /// Switches bus-off on or off: while on, every transmit fails with [`MemBusError::BusOff`].
    pub fn set_bus_off(&self, on: bool) {
        lock(&self.inner).bus_off = on;
    }

    /// Whether the bus is bus-off now (a controller without carrier).
    pub fn is_bus_off(&self) -> bool {
        lock(&self.inner).bus_off
    }

    /// Endpoints currently attached.
    pub fn endpoints(&self) -> usize {
        lock(&self.inner).live_endpoints()
    }
}

/// One node's attachment to a [`MemBus`].
pub struct MemEndpoint<F = CanFrame> {
    inner: Inner<F>,
    index: usize,
}

impl<F> std::fmt::Debug for MemEndpoint<F> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("MemEndpoint")
            .field("index", &self.index)
            .finish()
    }
}

impl<F> Drop for MemEndpoint<F> {
    fn drop(&mut self) {
        let mut s = lock(&self.inner);
        if let Some(slot) = s.queues.get_mut(self.index) {
            *slot = None;
        }
        drop(s);
        // A blocking reader elsewhere may now have no peer left.
        self.inner.1.notify_all();
    }
}

impl<F: Clone> MemEndpoint<F> {
    /// Another endpoint on the same bus.
    pub fn bus(&self) -> MemBus<F> {
        MemBus {
            inner: Arc::clone(&self.inner),
        }
    }

    /// Queues `frame` at every other endpoint. Never blocks: a full receiver drops it and counts
    /// an overflow.
    pub fn send(&mut self, frame: &F) -> Result<(), MemBusError> {
        let mut s = lock(&self.inner);
        if s.bus_off {
            return Err(MemBusError::BusOff);
        }
        let time_us = s.clock.as_ref().map(|c| c.now_us());
        let capacity = s.capacity;
        s.frames_sent += 1;
        for (i, q) in s.queues.iter_mut().enumerate() {
            let Some(q) = q else { continue };
            if i == self.index {
                continue;
            }
            if q.frames.len() >= capacity {
                q.overflows += 1;
            } else {
                q.frames.push_back(Received {
                    frame: frame.clone(),
                    time_us,
                });
            }
        }
        drop(s);
        self.inner.1.notify_all();
        Ok(())
    }

    /// The oldest frame waiting at this endpoint, with its receive time, or `None`.
    pub fn receive_timestamped(&mut self) -> Option<Received<F>> {
        let mut s = lock(&self.inner);
        s.queues[self.index].as_mut()?.frames.pop_front()
    }

    /// Waits up to `timeout` for a frame (for threaded tests and the blocking API).
    pub fn receive_timeout(
        &mut self,
        timeout: Duration,
    ) -> Result<Option<Received<F>>, MemBusError> {
        let deadline = std::time::Instant::now() + timeout;
        let mut s = lock(&self.inner);
        loop {
            if let Some(r) = s.queues[self.index]
                .as_mut()
                .and_then(|q| q.frames.pop_front())
            {
                return Ok(Some(r));
            }
            if s.live_endpoints() <= 1 {
                return Err(MemBusError::NoPeers);
            }
            let now = std::time::Instant::now();
            if now >= deadline {
                return Ok(None);
            }
            s = self
                .inner
                .1
                .wait_timeout(s, deadline - now)
                .unwrap_or_else(|e| e.into_inner())
                .0;
        }
    }

    /// Frames waiting at this endpoint.
    pub fn pending(&self) -> usize {
        let s = lock(&self.inner);
        s.queues[self.index].as_ref().map_or(0, |q| q.frames.len())
    }

    /// Frames this endpoint lost because its queue was full.
    pub fn overflows(&self) -> u64 {
        let s = lock(&self.inner);
        s.queues[self.index].as_ref().map_or(0, |q| q.overflows)
    }

    /// Discards every waiting frame (e.g. a node that just attached and wants only new traffic).
    pub fn clear(&mut self) {
        let mut s = lock(&self.inner);
        if let Some(q) = s.queues[self.index].as_mut() {
            q.frames.clear();
        }
    }
}

impl<F: embedded_can::Frame + Clone> embedded_can::nb::Can for MemEndpoint<F> {
    type Frame = F;
    type Error = MemBusError;

    fn transmit(&mut self, frame: &F) -> nb::Result<Option<F>, MemBusError> {
        self.send(frame).map_err(nb::Error::Other)?;
        Ok(None)
    }

    fn receive(&mut self) -> nb::Result<F, MemBusError> {
        self.receive_timestamped()
            .map(|r| r.frame)
            .ok_or(nb::Error::WouldBlock)
    }
}

impl<F: embedded_can::Frame + Clone> embedded_can::blocking::Can for MemEndpoint<F> {
    type Frame = F;
    type Error = MemBusError;

    fn transmit(&mut self, frame: &F) -> Result<(), MemBusError> {
        self.send(frame)
    }

    fn receive(&mut self) -> Result<F, MemBusError> {
        loop {
            if let Some(r) = self.receive_timeout(Duration::from_secs(3600))? {
                return Ok(r.frame);
            }
        }
    }
}
