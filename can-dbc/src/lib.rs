//! The handstack CAN bus: `hand.dbc` is the single source of truth for every frame on the
//! prosthesis's bus, and this crate owns it: generated message types, E2E protection (alive
//! counter and CRC-8), bus-load accounting and candump log reading and writing.
