//! Issue 16: malformed files never panic. Property tests over arbitrary bytes and over
//! mutations of valid files, for every file and message the stack reads: candump logs,
//! `session.toml`, model files, `handd.toml` and the control protocol's request line. Each input
//! gives a value or an error naming the place (line, field, section); the regressions found by
//! these tests are kept as plain tests beside them and in the parsers' own unit tests.
//!
//! Every runner is seeded (see `mutate::seeded`), so the cases are the same on every run.

mod candump;
mod control_json;
mod handd_toml;
mod model_bytes;
mod model_file;
mod mutate;
mod session_toml;
