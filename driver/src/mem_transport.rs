//! The daemon on `hand-model`'s in-memory bus (feature `sim`): the demo and the simulator
//! tests run the real control loop in one process, with the bus's per-frame receive times.

use hand_clock::Clock;
use hand_dbc::CanFrame;
use hand_model::{MemBusError, MemEndpoint};

use crate::transport::{Timestamped, Transport, TransportError};

/// The in-memory bus: receive times come from the bus's clock, or from `clock` if it has none.
pub struct MemTransport<K: Clock> {
    endpoint: MemEndpoint<CanFrame>,
    clock: K,
}

impl<K: Clock> MemTransport<K> {
    /// Wraps an endpoint.
    pub fn new(endpoint: MemEndpoint<CanFrame>, clock: K) -> Self {
        Self { endpoint, clock }
    }

    /// Frames dropped because the receive queue was full (the bus's lost frames).
    pub fn overflows(&self) -> u64 {
        self.endpoint.overflows()
    }
}

impl<K: Clock> Transport for MemTransport<K> {
    fn try_recv(&mut self) -> Result<Option<Timestamped>, TransportError> {
        Ok(self
            .endpoint
            .receive_timestamped()
            .map(|r| (r.frame, r.time_us.unwrap_or_else(|| self.clock.now_us()))))
    }

    fn send(&mut self, frame: &CanFrame) -> Result<(), TransportError> {
        self.endpoint.send(frame).map_err(|e| match e {
            MemBusError::BusOff => TransportError::BusOff,
            other => TransportError::Down(other.to_string()),
        })
    }

    fn drop_queued(&mut self) {
        // The in-memory bus delivers at once: nothing is ever queued for sending.
    }

    fn reopen(&mut self) -> Result<(), TransportError> {
        Ok(())
    }
}
