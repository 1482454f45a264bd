//! The daemon on `hand-model`'s in-memory bus (feature `sim`): the demo and the simulator
//! tests run the real control loop in one process, with the bus's per-frame receive times.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use hand_clock::Clock;
use hand_dbc::CanFrame;
use hand_model::{MemBusError, MemEndpoint};

use crate::transport::{Timestamped, Transport, TransportError};

/// The in-memory bus: receive times come from the bus's clock, or from `clock` if it has none.
///
/// Its link can be taken down and brought back ([`MemTransport::link`]), as an interface that
/// is down (`ip link set down`, a controller not yet configured at boot): while down every
/// receive, send and reopen fails, and a reopen after it drops what was received meanwhile,
/// as a new socket would never have seen it.
pub struct MemTransport<K: Clock> {
    endpoint: MemEndpoint<CanFrame>,
    clock: K,
    up: Arc<AtomicBool>,
    was_down: bool,
}

impl<K: Clock> MemTransport<K> {
    /// Wraps an endpoint, link up.
    pub fn new(endpoint: MemEndpoint<CanFrame>, clock: K) -> Self {
        Self {
            endpoint,
            clock,
            up: Arc::new(AtomicBool::new(true)),
            was_down: false,
        }
    }

    /// The link's switch: store false to take the interface down, true to bring it back.
    pub fn link(&self) -> Arc<AtomicBool> {
        Arc::clone(&self.up)
    }

    fn check_up(&mut self) -> Result<(), TransportError> {
        if self.up.load(Ordering::Acquire) {
            Ok(())
        } else {
            self.was_down = true;
            Err(TransportError::Down("the in-memory link is down".into()))
        }
    }

    /// Frames received and not read yet.
    pub fn pending(&self) -> usize {
        self.endpoint.pending()
    }

    /// Frames dropped because the receive queue was full (the bus's lost frames).
    pub fn overflows(&self) -> u64 {
        self.endpoint.overflows()
    }
}

impl<K: Clock> Transport for MemTransport<K> {
    fn try_recv(&mut self) -> Result<Option<Timestamped>, TransportError> {
        self.check_up()?;
        Ok(self
            .endpoint
            .receive_timestamped()
            .map(|r| (r.frame, r.time_us.unwrap_or_else(|| self.clock.now_us()))))
    }

    fn send(&mut self, frame: &CanFrame) -> Result<(), TransportError> {
        self.check_up()?;
        self.endpoint.send(frame).map_err(|e| match e {
            MemBusError::BusOff => TransportError::BusOff,
            other => TransportError::Down(other.to_string()),
        })
    }

    fn drop_queued(&mut self) {
        // The in-memory bus delivers at once: nothing is ever queued for sending.
    }

    fn reopen(&mut self) -> Result<(), TransportError> {
        self.check_up()?;
        // As SocketCAN's reopen checks the carrier: a controller still bus-off has none.
        if self.endpoint.bus().is_bus_off() {
            return Err(TransportError::Down(
                "the in-memory bus is bus-off: no carrier".into(),
            ));
        }
        if std::mem::take(&mut self.was_down) {
            while self.endpoint.receive_timestamped().is_some() {}
        }
        Ok(())
    }
}
