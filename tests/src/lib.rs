//! Workspace-level integration tests: the whole stack over the in-memory bus always, and over a
//! real SocketCAN vcan bus where one exists.
