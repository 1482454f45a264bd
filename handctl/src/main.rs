//! `handctl`, the technician's command line for the hand: calibration training, evaluation,
//! importing recordings, decoding them, the running daemon's status, live tuning, arm and stop,
//! the live monitor, and the demo
//! (with the `sim` feature). One module per subcommand, the argument structures in `args`.
//!
//! A crate of its own, beside the daemon's (`driver`): what only the technician's tool needs
//! (the terminal UI, plotting) never enters `handd`'s build.
//!
//! `handctl demo` always parses; it runs only in a build with the `sim` feature (the
//! simulator), and otherwise fails saying how to build it. `handctl eval --plots` draws PNG
//! figures with the `plots` feature, and writes the curves as CSV without it.

mod args;
mod calibrate;
mod daemon;
mod decode;
#[cfg(feature = "sim")]
mod demo;
mod deploy;
mod docs;
mod error;
mod eval;
mod import;
mod listen;
mod monitor;
mod progress;
mod record;
mod replay;
mod train;
mod verify;

use std::process::ExitCode;

use clap::Parser;

use args::{Cli, Command};

/// Parses the command line, runs the command, prints an error and returns the exit code
/// (0 success, 1 failure, 2 usage error from clap, 3 quality gates refused the session, 4 the
/// trained model reverses on a calibration ray and was not written, 5 a deploy to another
/// patient was not confirmed).
fn main() -> ExitCode {
    quiet_on_a_closed_pipe();
    let cli = Cli::parse();
    let result = match &cli.command {
        Command::Train(a) => train::run(a),
        Command::Eval(a) => eval::run(a),
        Command::Import3dc(a) => import::run_3dc(a),
        Command::Check(a) => train::run_check(a),
        Command::Verify(a) => verify::run(a),
        Command::Import(a) => import::run_table(a),
        Command::Decode(a) => decode::run(a),
        Command::Status(a) => daemon::status(&a.daemon, a.json),
        Command::Tune(a) => daemon::tune(a),
        Command::Arm(a) => daemon::arm(a),
        Command::Stop(o) => daemon::stop(o),
        Command::Deploy(a) => deploy::deploy(a),
        Command::Rollback(o) => deploy::rollback(o),
        Command::Monitor(a) => monitor::run(a),
        Command::Record(a) => record::run(a),
        Command::Replay(a) => replay::run(a),
        Command::Calibrate(a) => calibrate::run(a),
        Command::Demo(a) => run_demo(a),
        Command::Completions(a) => docs::completions(a),
        Command::Man(a) => docs::man(a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("handctl: error: {e}");
            ExitCode::from(e.exit_code())
        }
    }
}

/// How to build a handctl with the demo.
#[cfg(not(feature = "sim"))]
const DEMO_BUILD: &str = "cargo run --release -p handctl --features sim -- demo";

#[cfg(feature = "sim")]
fn run_demo(a: &args::DemoArgs) -> Result<(), error::CliError> {
    demo::run(a)
}

#[cfg(not(feature = "sim"))]
fn run_demo(_: &args::DemoArgs) -> Result<(), error::CliError> {
    Err(error::CliError::NotBuilt {
        what: "the demo (it runs on the simulator, the `sim` feature)",
        build: DEMO_BUILD,
    })
}

/// `handctl status | head` and the like: when the reader of stdout goes away, Rust's runtime
/// (which ignores SIGPIPE) makes `println!` (and the completion writer's `expect`) panic on
/// EPIPE. Such a panic ends handctl quietly with the shell's code for a process killed by
/// SIGPIPE (141), as a C tool ends; every other panic is reported as before.
fn quiet_on_a_closed_pipe() {
    let report = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let message = info
            .payload()
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| info.payload().downcast_ref::<&str>().copied())
            .unwrap_or("");
        if message.contains("Broken pipe") {
            std::process::exit(141);
        }
        report(info);
    }));
}
