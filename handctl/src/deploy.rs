//! `handctl deploy` and `handctl rollback`: swap a model into the running `handd` (checked by
//! the daemon, swapped at a tick boundary, the config updated) or swap the previous one back.
//!
//! Before a deploy handd checks the model without installing it (`check_only`: a model it
//! would refuse is refused first), and the model's provenance (patient, session, calibration date, gates bypassed)
//! is shown beside the running model's, from `handd`'s status. When the patients differ (or
//! either is unknown) the technician is asked; `--yes` answers for a script, and without
//! `--yes` and without a terminal on stdin the deploy fails at once ([`CliError::Unconfirmed`],
//! exit code 5) instead of waiting for an answer. `handd` refuses such a deploy unless the
//! request says it was confirmed, so a hand-written request cannot skip the question.

use std::io::{BufRead, IsTerminal, Write};
use std::path::Path;

use decoder::model::provenance::describe_provenance;
use decoder::model::TrainedModel;
use driver::deploy::patient_change;
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

/// How a patient change is settled: `--yes`, or the answer read from a terminal.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Asker {
    /// `--yes`: confirmed without a question.
    Yes,
    /// stdin is a terminal: ask there.
    Terminal,
    /// Neither: fail, saying to pass --yes.
    NoTerminal,
}

/// Whether the deploy goes on after `change` (the two patients in words): `--yes` confirms,
/// a terminal is asked (y or yes confirms, anything else declines), and without either the
/// deploy fails at once with [`CliError::Unconfirmed`].
pub(crate) fn settle(
    change: &str,
    asker: Asker,
    answer: &mut dyn BufRead,
) -> Result<bool, CliError> {
    match asker {
        Asker::Yes => {
            println!("{change}: confirmed by --yes");
            Ok(true)
        }
        Asker::NoTerminal => Err(CliError::Unconfirmed {
            change: change.to_owned(),
        }),
        Asker::Terminal => {
            print!("{change}.\nDeploy it over the running model? [y/N] ");
            std::io::stdout().flush().ok();
            let mut line = String::new();
            answer.read_line(&mut line).map_err(|e| CliError::Io {
                path: "stdin".into(),
                source: e,
            })?;
            let yes = matches!(line.trim().to_ascii_lowercase().as_str(), "y" | "yes");
            if yes {
                Ok(true)
            } else {
                Err(CliError::Usage(format!(
                    "not deployed: {change}, and the answer was not yes"
                )))
            }
        }
    }
}

/// `handctl deploy MODEL`: the path goes to the daemon absolute (it does not share our
/// working directory). The model's provenance is shown beside the running model's, and a
/// change of patient is confirmed first (see the module docs).
pub fn deploy(a: &DeployArgs) -> Result<(), CliError> {
    let path = std::path::absolute(&a.model)
        .map_err(|e| CliError::Usage(format!("{}: {e}", a.model.display())))?;
    let text = path_text(&path)?;
    // A file that does not load here is sent anyway: handd refuses it with the reason.
    let model = TrainedModel::load(&path, None).ok();
    let patient = model
        .as_ref()
        .and_then(|m| m.provenance())
        .and_then(|p| p.patient.clone());
    if let Some(m) = &model {
        println!(
            "model {}: {}",
            path.display(),
            describe_provenance(m.provenance())
        );
    }
    let running = done(ask(&a.daemon, &Request::Status)?)?.and_then(|s| s.model);
    if let Some(r) = &running {
        let origin = if r.provenance.is_empty() {
            "unknown patient (this handd does not report provenance)"
        } else {
            &r.provenance
        };
        println!("running model {} (id {}): {origin}", r.path, r.id);
    }
    // handd's own checks first, so a model it would refuse anyway is refused before the
    // question about the patient.
    done(ask(
        &a.daemon,
        &Request::Deploy {
            path: text.clone(),
            force: a.force,
            confirmed: false,
            check_only: true,
        },
    )?)?;
    let confirmed = match (&model, patient_change(patient.as_deref(), running.as_ref())) {
        (Some(_), Some(change)) => {
            let asker = if a.yes {
                Asker::Yes
            } else if std::io::stdin().is_terminal() {
                Asker::Terminal
            } else {
                Asker::NoTerminal
            };
            settle(&change, asker, &mut std::io::stdin().lock())?
        }
        _ => false,
    };
    report(ask(
        &a.daemon,
        &Request::Deploy {
            path: text,
            force: a.force,
            confirmed,
            check_only: false,
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_patient_change_is_confirmed_by_yes_or_the_terminal_and_never_waits_without_one() {
        let change = "this model is for patient P-002, the running model (id 0badf00d) for \
                      patient P-001";
        let mut nothing: &[u8] = b"";
        assert!(settle(change, Asker::Yes, &mut nothing).unwrap());
        let e = settle(change, Asker::NoTerminal, &mut nothing).unwrap_err();
        assert_eq!(e.exit_code(), 5);
        let text = e.to_string();
        assert!(
            text.contains("patient P-002") && text.contains("pass --yes"),
            "{text}"
        );
        let mut yes: &[u8] = b"y\n";
        assert!(settle(change, Asker::Terminal, &mut yes).unwrap());
        for no in [&b"n\n"[..], b"\n", b""] {
            let mut answer = no;
            let e = settle(change, Asker::Terminal, &mut answer).unwrap_err();
            assert!(e.to_string().contains("not deployed"), "{e}");
        }
    }
}
