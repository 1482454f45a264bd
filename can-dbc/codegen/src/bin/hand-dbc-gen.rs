//! `hand-dbc-gen [--check]`: regenerates `can-dbc/core/src/messages/generated.rs` from
//! `can-dbc/hand.dbc`; with `--check`, only reports whether the checked-in file is current.

use std::process::ExitCode;

use hand_dbc_codegen::files::{self, Paths};
use hand_dbc_codegen::REGENERATE;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let check = match args.as_slice() {
        [] => false,
        [flag] if flag == "--check" => true,
        _ => {
            eprintln!("usage: {REGENERATE} [-- --check]");
            return ExitCode::from(2);
        }
    };
    let paths = Paths::workspace();
    let outcome = if check {
        files::is_current(&paths)
    } else {
        files::write(&paths)
    };
    match (check, outcome) {
        (_, Err(e)) => {
            eprintln!("hand-dbc-gen: {e}");
            ExitCode::FAILURE
        }
        (true, Ok(true)) => ExitCode::SUCCESS,
        (true, Ok(false)) => {
            eprintln!(
                "{} is out of date: run `{REGENERATE}`",
                paths.output.display()
            );
            ExitCode::FAILURE
        }
        (false, Ok(changed)) => {
            let what = if changed { "wrote" } else { "unchanged:" };
            eprintln!("{what} {}", paths.output.display());
            ExitCode::SUCCESS
        }
    }
}
