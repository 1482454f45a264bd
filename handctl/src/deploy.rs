//! `handctl deploy` and `handctl rollback`: swap a model into the running `handd` (checked by
//! the daemon, swapped at a tick boundary, the config updated) or swap the previous one back.

use std::path::Path;

use driver::protocol::{Request, Status};

use super::args::{DaemonOpts, DeployArgs};
use super::daemon::{ask, done};
use super::error::CliError;

/// The model line after a swap.
fn print_model(status: Option<Status>) {
    if let Some(m) = status.and_then(|s| s.model) {
        println!("running model {} ({}, id {})", m.path, m.kind, m.id);
        println!(
            "{}{}",
            if m.unverified { "!! " } else { "" },
            m.verification
        );
    }
}

/// The message of an Ok reply, then the model that runs now.
fn report(reply: driver::protocol::Reply) -> Result<(), CliError> {
    if let driver::protocol::Reply::Ok { message, .. } = &reply {
        println!("{message}");
    }
    print_model(done(reply)?);
    Ok(())
}

/// `handctl deploy MODEL`: the path goes to the daemon absolute (it does not share our
/// working directory).
pub fn deploy(a: &DeployArgs) -> Result<(), CliError> {
    let path = std::path::absolute(&a.model)
        .map_err(|e| CliError::Usage(format!("{}: {e}", a.model.display())))?;
    let path = path_text(&path)?;
    report(ask(
        &a.daemon,
        &Request::Deploy {
            path,
            force: a.force,
        },
    )?)
}

fn path_text(p: &Path) -> Result<String, CliError> {
    p.to_str()
        .map(str::to_owned)
        .ok_or_else(|| CliError::Usage(format!("{}: not a UTF-8 path", p.display())))
}

/// `handctl rollback`.
pub fn rollback(o: &DaemonOpts) -> Result<(), CliError> {
    report(ask(o, &Request::Rollback)?)
}
