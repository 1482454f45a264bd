//! `handctl`: the technician's command line for the hand (calibration training, evaluation,
//! importing recordings). See `handctl --help`.

// The CLI lives in driver/src/cli so that later subcommands (status, tune, arm, stop, demo)
// get a module each beside the existing ones.
#[path = "../cli/mod.rs"]
mod cli;

fn main() -> std::process::ExitCode {
    cli::run()
}
