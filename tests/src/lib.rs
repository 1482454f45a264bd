//! Workspace-level integration tests: the whole stack over the in-memory bus always, and over a
//! real SocketCAN vcan bus where one exists.
//!
//! [`vcan`] holds what the vcan suite (`tests/tests/vcan/main.rs`, feature `vcan`, run by
//! `scripts/vm/run`) needs: the environment, the project's binaries as child processes, a bus
//! monitor with kernel timestamps, and the analysis of what it saw.

pub mod vcan;
