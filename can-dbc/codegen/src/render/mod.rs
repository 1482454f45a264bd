//! Rust source from the validated model: one file per kind of output. Each renderer returns a
//! small template filled with `format!`; layout is left to rustfmt (see [`crate::format`]).

mod accessors;
mod by_name;
mod codec;
mod constructor;
mod consts;
mod dispatch;
mod enums;
mod frames;
mod identity;
mod info;
mod range;
mod structure;

use crate::model::{Bus, Group, Kind, Signal};

/// What the generated module needs from its parent (`hand_dbc_core::messages`) and the crate.
const PRELUDE: &str = "\
use super::{round, standard_data_frame, to_can_frame, whole};
use crate::e2e::E2eProfile;
use crate::error::CodecError;
use crate::frame::CanFrame;
use crate::info::{MessageInfo, SignalInfo};

";

/// The generated module's items (unformatted): enums, one type per group, the dispatcher and
/// the message table.
pub fn render(bus: &Bus) -> String {
    let mut out = String::from(PRELUDE);
    for e in &bus.enums {
        out += &enums::render(e);
    }
    for g in &bus.groups {
        out += &group(g);
    }
    out += &dispatch::render(&bus.groups);
    out += &info::render(&bus.groups);
    out
}

/// A message type: struct, inherent impl, and the E2E trait impl for protected messages.
fn group(g: &Group) -> String {
    [
        structure::render(g),
        format!("impl {} {{\n", g.ty),
        consts::render(g),
        constructor::render(g),
        identity::render(g),
        accessors::render(g),
        codec::render(g),
        frames::methods(g),
        by_name::render(g),
        "}\n\n".to_string(),
        frames::protected_impl(g),
    ]
    .concat()
}

/// `///` lines for a (possibly multi-line) text.
fn doc(text: &str) -> String {
    text.lines()
        .map(|l| {
            if l.is_empty() {
                "///\n".to_string()
            } else {
                format!("/// {l}\n")
            }
        })
        .collect()
}

/// A Rust float literal that reads back as exactly `v`.
fn flit(v: f64) -> String {
    let s = format!("{v:?}");
    if s.contains('.') || s.contains('e') || s.contains("inf") || s.contains("NaN") {
        s
    } else {
        format!("{s}.0")
    }
}

/// Items rendered by `f`, joined with `sep`.
fn join<T>(items: &[T], sep: &str, f: impl Fn(&T) -> String) -> String {
    items.iter().map(f).collect::<Vec<_>>().join(sep)
}

/// The expression naming the message in errors raised by methods on `self`.
fn self_name(g: &Group) -> &'static str {
    if g.is_family() {
        "Self::NAMES[usize::from(self.instance)]"
    } else {
        "Self::NAME"
    }
}

/// A field's value before the checked setters run: the first enum value, or 0 (the raw
/// minimum when 0 lies outside the range).
fn initial(s: &Signal) -> String {
    match &s.kind {
        Kind::Enum(e) => format!("{e}::ALL[0]"),
        _ if s.raw_min <= 0 && 0 <= s.raw_max => "0".to_string(),
        _ => s.raw_min.to_string(),
    }
}
