//! The generator of hand-dbc's message codec: reads `can-dbc/hand.dbc` and writes the
//! checked-in Rust module `can-dbc/core/src/messages/generated.rs`, so the code a safety bus depends
//! on is reviewed like any other source file.
//!
//! Two steps, each in its own place:
//!
//! 1. [`Bus::from_dbc`] ([`model`]) parses the DBC and validates it once, up front. Every
//!    inconsistency (a range the bits cannot hold, overlapping signals, a value-table entry
//!    outside its range, an E2E message without the fixed CRC/counter layout, two protected
//!    messages of one length whose data ids leave the CRC register in the same state, Motorola
//!    byte order, multiplexing, ...) is a [`DbcError`] naming the message and the signal.
//! 2. [`render`] turns the model into Rust: one renderer per kind of output (enums, struct and
//!    consts, constructor, accessors, encode/decode, frames, by-name access, the `Message`
//!    dispatcher, the `MESSAGES` table). It cannot fail.
//!
//! [`generate`] does both and adds the header; [`format::rustfmt`] lays the result out like
//! the rest of the repository; [`files`] reads hand.dbc and writes or checks the output.
//! Regenerate with [`REGENERATE`] (`cargo run -p hand-dbc-codegen --bin hand-dbc-gen`); add
//! `-- --check` to only compare. `cargo test -p hand-dbc-codegen` fails while the checked-in
//! file is out of date.
//!
//! ```
//! let bus = hand_dbc_codegen::Bus::from_dbc(include_str!("../../hand.dbc"))?;
//! assert!(bus.groups.iter().any(|g| g.ty == "FingerSetpoint" && g.messages.len() == 5));
//! # Ok::<(), hand_dbc_codegen::DbcError>(())
//! ```

mod error;
pub mod files;
pub mod format;
pub mod model;
mod names;
mod render;

pub use error::{DbcError, GenError};
pub use model::Bus;
pub use render::render;

/// The command that regenerates the checked-in codec (run from the workspace).
pub const REGENERATE: &str = "cargo run -p hand-dbc-codegen --bin hand-dbc-gen";

/// The generated module for a DBC text (header and items, not yet formatted), or why the DBC
/// is refused.
pub fn generate(dbc_text: &str) -> Result<String, DbcError> {
    let bus = Bus::from_dbc(dbc_text)?;
    Ok(header() + &render(&bus))
}

/// The comment every generated file starts with.
fn header() -> String {
    format!(
        "// @generated from can-dbc/hand.dbc by `{REGENERATE}`.\n\
         // Do not edit by hand: edit hand.dbc and rerun that command. Add `-- --check` to only\n\
         // compare; `cargo test -p hand-dbc-codegen` fails while this file is out of date.\n\n"
    )
}
