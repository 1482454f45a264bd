//! `handctl completions SHELL` and the manual page: both generated from the clap definitions
//! in `args`, so they cannot drift from the command line (scripts/package installs them).

use std::fs;
use std::path::Path;

use clap::CommandFactory;

use crate::args::{Cli, CompletionsArgs, ManArgs};
use crate::error::CliError;

/// Prints the completion script for `a.shell` to stdout.
pub fn completions(a: &CompletionsArgs) -> Result<(), CliError> {
    let mut cmd = Cli::command();
    clap_complete::generate(a.shell, &mut cmd, "handctl", &mut std::io::stdout());
    Ok(())
}

/// Writes handctl's manual pages into `a.dir`: `handctl.1`, and `handctl-NAME.1` for every
/// subcommand (hidden ones too: the page of `man` says what it does).
pub fn man(a: &ManArgs) -> Result<(), CliError> {
    let io = |path: &Path| {
        let path = path.display().to_string();
        move |source| CliError::Io { path, source }
    };
    fs::create_dir_all(&a.dir).map_err(io(&a.dir))?;
    let cmd = Cli::command();
    let mut pages = vec![("handctl".to_string(), cmd.clone())];
    for sub in cmd.get_subcommands() {
        let name = format!("handctl-{}", sub.get_name());
        let page = sub
            .clone()
            .display_name(name.clone())
            .bin_name(format!("handctl {}", sub.get_name()));
        pages.push((name, page));
    }
    for (name, page) in pages {
        let path = a.dir.join(format!("{name}.1"));
        let mut out = Vec::new();
        clap_mangen::Man::new(page)
            .render(&mut out)
            .map_err(io(&path))?;
        fs::write(&path, out).map_err(io(&path))?;
    }
    Ok(())
}
