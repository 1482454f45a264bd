//! Layout of the generated code: piped through `rustfmt` with the repository's
//! `rustfmt.toml`, so the checked-in file passes `cargo fmt --all -- --check` and the same
//! input always gives the same bytes.

use std::io::{Read, Write};
use std::path::Path;
use std::process::{Command, Stdio};

use crate::GenError;

/// `code` formatted by rustfmt (`$RUSTFMT` or `rustfmt` on the `PATH`), edition 2021, with
/// the settings in `config` (the workspace's `rustfmt.toml`).
pub fn rustfmt(code: &str, config: &Path) -> Result<String, GenError> {
    let program = std::env::var_os("RUSTFMT").unwrap_or_else(|| "rustfmt".into());
    let mut child = Command::new(&program)
        .args(["--edition", "2021", "--config-path"])
        .arg(config)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|e| GenError::Rustfmt(format!("cannot run {}: {e}", program.to_string_lossy())))?;
    let mut stdin = child
        .stdin
        .take()
        .ok_or(GenError::Rustfmt("no stdin".into()))?;
    let mut stdout = child
        .stdout
        .take()
        .ok_or(GenError::Rustfmt("no stdout".into()))?;
    // Write from a second thread: the output is larger than a pipe buffer.
    let (written, formatted) = std::thread::scope(|scope| {
        let writer = scope.spawn(move || stdin.write_all(code.as_bytes()));
        let mut formatted = String::new();
        let read = stdout.read_to_string(&mut formatted);
        (writer.join(), read.map(|_| formatted))
    });
    let output = child
        .wait_with_output()
        .map_err(|e| GenError::Rustfmt(e.to_string()))?;
    if !output.status.success() {
        let stderr = String::from_utf8_lossy(&output.stderr);
        return Err(GenError::Rustfmt(format!("{}: {stderr}", output.status)));
    }
    match (written, formatted) {
        (Ok(Ok(())), Ok(formatted)) => Ok(formatted),
        (Ok(Err(e)), _) | (_, Err(e)) => Err(GenError::Rustfmt(e.to_string())),
        (Err(_), _) => Err(GenError::Rustfmt("the writer thread panicked".into())),
    }
}
