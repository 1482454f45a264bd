//! The checked constructor `new`, and the field initialisation it shares with
//! `from_signals`.

use super::{doc, initial, join};
use crate::model::{Group, Kind};

/// `new(instance?, every non-E2E signal)`: each value goes through its checked setter.
pub(super) fn render(g: &Group) -> String {
    let m = g.first();
    let args: Vec<_> = m.signals.iter().filter(|s| !m.is_e2e_signal(s)).collect();
    let mut text =
        String::from("Builds the message from physical values, each checked against hand.dbc.");
    if m.e2e.is_some() {
        text += " Crc and Counter start at 0: an [`crate::e2e::E2eProtector`] fills them when \
                 sending.";
    }
    let allow = if args.len() + usize::from(g.is_family()) > 7 {
        "#[allow(clippy::too_many_arguments, reason = \"one argument per DBC signal\")]\n"
    } else {
        ""
    };
    let instance = if g.is_family() {
        "instance: usize, "
    } else {
        ""
    };
    let params = join(&args, ", ", |s| format!("{}: {}", s.field, s.api_ty()));
    let sets = join(&args, "", |s| match s.kind {
        Kind::Enum(_) => format!("msg.set_{0}({0});\n", s.field),
        _ => format!("msg.set_{0}({0})?;\n", s.field),
    });
    format!(
        "{}{allow}pub fn new({instance}{params}) -> Result<Self, CodecError> {{
{}{}{sets}Ok(msg)
}}

",
        doc(&text),
        instance_check(g),
        initial_fields(g)
    )
}

/// Refuses an instance index past the family (nothing for a single message).
pub(super) fn instance_check(g: &Group) -> String {
    if !g.is_family() {
        return String::new();
    }
    let n = g.messages.len();
    format!(
        "if instance >= {n} {{ return Err(CodecError::InstanceOutOfRange {{ message: Self::NAME, \
         instance, count: {n} }}); }}\n"
    )
}

/// `let mut msg = Self { .. };` with every field at its initial value.
pub(super) fn initial_fields(g: &Group) -> String {
    let instance = if g.is_family() {
        "instance: instance as u8,\n"
    } else {
        ""
    };
    let fields = join(&g.first().signals, "", |s| {
        format!("{}: {},\n", s.field, initial(s))
    });
    format!("let mut msg = Self {{\n{instance}{fields}}};\n")
}
