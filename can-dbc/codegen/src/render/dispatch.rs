//! The `Message` enum of every type, and dispatch by CAN id: `decode`, `decode_frame`,
//! `from_signals`.

use super::join;
use crate::model::Group;

/// The enum, the three free functions and `impl Message`.
pub(super) fn render(groups: &[Group]) -> String {
    let variants = join(groups, "", |g| {
        format!("/// {}\n{}({}),\n", g.name, g.ty, g.ty)
    });
    format!(
        "/// Any message of hand.dbc, as decoded by [`decode`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Message {{
{variants}}}

{}{}",
        by_id(groups),
        message_impl(groups)
    )
}

/// `decode`, `decode_frame` and `from_signals`: one match arm per type, on its ids.
fn by_id(groups: &[Group]) -> String {
    let decode_arms = join(groups, "", |g| {
        let args = if g.is_family() { "id, data" } else { "data" };
        let (ids, ty) = (id_pattern(g), &g.ty);
        format!("{ids} => {ty}::decode({args}).map(Message::{ty}),\n")
    });
    let from_signals_arms = join(groups, "", |g| {
        let instance = if g.is_family() {
            format!("{}::instance_of(id).unwrap_or(usize::MAX), ", g.ty)
        } else {
            String::new()
        };
        let (ids, ty) = (id_pattern(g), &g.ty);
        format!("{ids} => {ty}::from_signals({instance}get).map(Message::{ty}),\n")
    });
    format!(
        "/// Decodes a payload by CAN id into the matching message; refuses unknown ids, wrong lengths, \
         out-of-range raw values and unnamed enum values. Never panics.
pub fn decode(id: u32, data: &[u8]) -> Result<Message, CodecError> {{
match id {{
{decode_arms}_ => Err(CodecError::UnknownId {{ id }}),
}}
}}

/// Decodes any [`embedded_can::Frame`]; refuses remote frames and extended ids.
pub fn decode_frame<F: embedded_can::Frame>(frame: &F) -> Result<Message, CodecError> {{
let id = standard_data_frame(frame)?;
decode(id, frame.data())
}}

/// Builds a message from physical values looked up by DBC signal name (see each type's \
         `from_signals`).
pub fn from_signals(id: u32, get: &mut dyn FnMut(&str) -> Option<f64>) -> Result<Message, \
         CodecError> {{
match id {{
{from_signals_arms}_ => Err(CodecError::UnknownId {{ id }}),
}}
}}

"
    )
}

/// `impl Message`: each method matches on the variant and delegates.
fn message_impl(groups: &[Group]) -> String {
    let delegate = |doc: &str, sig: &str, body: &str| {
        let arms = join(groups, "", |g| format!("Message::{}(m) => {body},\n", g.ty));
        format!("/// {doc}\npub fn {sig} {{\nmatch self {{\n{arms}}}\n}}\n\n")
    };
    let e2e_arms = join(groups, "", |g| match g.first().e2e {
        Some(_) => format!("Message::{}(m) => Some(m.e2e()),\n", g.ty),
        None => format!("Message::{}(_) => None,\n", g.ty),
    });
    [
        "impl Message {\n".to_string(),
        delegate("CAN id.", "id(&self) -> u32", "m.id()"),
        delegate(
            "DBC message name.",
            "name(&self) -> &'static str",
            "m.name()",
        ),
        delegate(
            "The message as a [`CanFrame`].",
            "to_frame(&self) -> CanFrame",
            "m.to_frame()",
        ),
        delegate(
            "Calls `f` with each signal's DBC name and physical value.",
            "for_each_signal(&self, f: &mut dyn FnMut(&'static str, f64))",
            "m.for_each_signal(f)",
        ),
        format!(
            "/// E2E profile, `None` for unprotected messages.\npub fn e2e(&self) -> \
             Option<E2eProfile> {{\nmatch self {{\n{e2e_arms}}}\n}}\n}}\n\n"
        ),
    ]
    .concat()
}

/// Match pattern for a group's ids: a range when there are more than two consecutive ids.
fn id_pattern(g: &Group) -> String {
    let ids: Vec<u32> = g.messages.iter().map(|m| m.id).collect();
    let consecutive = ids.windows(2).all(|w| w[1] == w[0] + 1);
    if ids.len() > 2 && consecutive {
        format!("{:#05x}..={:#05x}", ids[0], ids[ids.len() - 1])
    } else {
        join(&ids, " | ", |i| format!("{i:#05x}"))
    }
}
