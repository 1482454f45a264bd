//! Access by DBC signal name (tools, the cantools cross-check): `for_each_signal` and
//! `from_signals`.

use super::constructor::{initial_fields, instance_check};
use super::join;
use super::range::raw_to_f64;
use crate::model::{Group, Kind, Signal};

/// `for_each_signal` then `from_signals`.
pub(super) fn render(g: &Group) -> String {
    for_each_signal(g) + &from_signals(g)
}

fn for_each_signal(g: &Group) -> String {
    let calls = join(&g.first().signals, "", |s| {
        let v = match &s.kind {
            Kind::Enum(_) => format!("f64::from(self.{}.raw())", s.field),
            Kind::Int => raw_to_f64(s, &format!("self.{}", s.field)),
            Kind::Scaled => format!("self.{}()", s.field),
        };
        format!("f({:?}, {v});\n", s.name)
    });
    format!(
        "/// Calls `f` with each signal's DBC name and physical value (enums as their raw value).
pub fn for_each_signal(&self, f: &mut dyn FnMut(&'static str, f64)) {{
{calls}}}

"
    )
}

/// Every signal, E2E ones included, looked up by name and set through its checked setter.
fn from_signals(g: &Group) -> String {
    let head = if g.is_family() {
        "pub fn from_signals(instance: usize, get: &mut dyn FnMut(&str) -> Option<f64>) -> \
         Result<Self, CodecError> {\n"
    } else {
        "pub fn from_signals(get: &mut dyn FnMut(&str) -> Option<f64>) -> Result<Self, \
         CodecError> {\n"
    };
    let message = if g.is_family() {
        "Self::NAMES[instance]"
    } else {
        "Self::NAME"
    };
    format!(
        "/// Builds the message from physical values looked up by DBC signal name (enums by raw \
         value), each checked; E2E signals included.
{head}{}let message = {message};
{}{}Ok(msg)
}}
",
        instance_check(g),
        initial_fields(g),
        join(&g.first().signals, "", set_by_name)
    )
}

fn set_by_name(s: &Signal) -> String {
    let (f, name) = (&s.field, &s.name);
    let get = format!(
        "let v = get({name:?}).ok_or(CodecError::MissingSignal {{ message, signal: {name:?} }})?;\n"
    );
    let set = match &s.kind {
        Kind::Enum(e) => format!(
            "let raw = whole(message, {name:?}, v)?;
msg.{f} = {e}::from_raw(raw).ok_or(CodecError::UnknownValue {{ message, signal: {name:?}, raw }})?;
"
        ),
        Kind::Int => format!(
            "let raw = whole(message, {name:?}, v)?;
let raw = {}::try_from(raw).map_err(|_| CodecError::RawOutOfRange {{ message, signal: {name:?}, \
             raw, min: {}, max: {} }})?;
msg.set_{f}(raw)?;
",
            s.raw_ty.name(),
            s.raw_min,
            s.raw_max
        ),
        Kind::Scaled => format!("msg.set_{f}(v)?;\n"),
    };
    get + &set
}
