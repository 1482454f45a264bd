//! `handctl`: the technician's command line for the hand: calibration training, evaluation,
//! importing recordings, the running daemon's status, live tuning, arm and stop, and the demo
//! (with the `sim` feature). See `handctl --help`; the commands are in [`driver::cli`].

fn main() -> std::process::ExitCode {
    driver::cli::run()
}
