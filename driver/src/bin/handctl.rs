//! `handctl`: the technician's command line for the hand: calibration training, evaluation,
//! importing recordings, the running daemon's status, live tuning, arm and stop, and the demo.
//! See `handctl --help`.

// The CLI lives in driver/src/cli, one module per subcommand.
#[path = "../cli/mod.rs"]
mod cli;

fn main() -> std::process::ExitCode {
    cli::run()
}
