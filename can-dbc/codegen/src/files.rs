//! Where the generator reads and writes in the workspace, and the write and check steps of
//! `hand-dbc-gen`.

use std::path::{Path, PathBuf};

use crate::{format, generate, GenError};

/// The files the generator uses.
#[derive(Debug, Clone)]
pub struct Paths {
    /// The bus definition (`can-dbc/hand.dbc`).
    pub dbc: PathBuf,
    /// The checked-in codec (`can-dbc/core/src/messages/generated.rs`).
    pub output: PathBuf,
    /// The workspace's `rustfmt.toml`.
    pub rustfmt_config: PathBuf,
}

impl Paths {
    /// The paths in the workspace this crate was built in.
    pub fn workspace() -> Self {
        let can_dbc = Path::new(env!("CARGO_MANIFEST_DIR"))
            .parent()
            .expect("the codegen crate lives in can-dbc/codegen");
        Self {
            dbc: can_dbc.join("hand.dbc"),
            output: can_dbc.join("core/src/messages/generated.rs"),
            rustfmt_config: can_dbc.join("../rustfmt.toml"),
        }
    }
}

/// The formatted generated file for the current DBC.
pub fn regenerate(paths: &Paths) -> Result<String, GenError> {
    let dbc = read(&paths.dbc)?;
    format::rustfmt(&generate(&dbc)?, &paths.rustfmt_config)
}

/// Regenerates and writes the output; `true` if its content changed.
pub fn write(paths: &Paths) -> Result<bool, GenError> {
    let code = regenerate(paths)?;
    if read(&paths.output).is_ok_and(|old| old == code) {
        return Ok(false);
    }
    std::fs::write(&paths.output, code).map_err(|source| GenError::Io {
        path: paths.output.clone(),
        source,
    })?;
    Ok(true)
}

/// Whether the checked-in output is what the DBC generates now.
pub fn is_current(paths: &Paths) -> Result<bool, GenError> {
    Ok(read(&paths.output)? == regenerate(paths)?)
}

fn read(path: &Path) -> Result<String, GenError> {
    std::fs::read_to_string(path).map_err(|source| GenError::Io {
        path: path.to_path_buf(),
        source,
    })
}
