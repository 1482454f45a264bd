//! The `handctl` commands: one module per subcommand, the argument structures in `args`.

mod args;
mod daemon;
mod demo;
mod error;
mod eval;
mod import;
mod progress;
mod record;
mod train;

use std::process::ExitCode;

use clap::Parser;

use args::{Cli, Command};

/// Parses the command line, runs the command, prints an error and returns the exit code
/// (0 success, 1 failure, 2 usage error from clap, 3 quality gates refused the session).
pub fn run() -> ExitCode {
    let cli = Cli::parse();
    let result = match &cli.command {
        Command::Train(a) => train::run(a),
        Command::Eval(a) => eval::run(a),
        Command::Import3dc(a) => import::run_3dc(a),
        Command::Check(a) => train::run_check(a),
        Command::Import(a) => import::run_table(a),
        Command::Status(a) => daemon::status(&a.daemon, a.json),
        Command::Tune(a) => daemon::tune(a),
        Command::Arm(o) => daemon::arm(o),
        Command::Stop(o) => daemon::stop(o),
        Command::Record(a) => record::run(a),
        Command::Demo(a) => demo::run(a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("handctl: error: {e}");
            ExitCode::from(e.exit_code())
        }
    }
}
