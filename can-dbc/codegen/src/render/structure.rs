//! The message struct and its documentation.

use super::{doc, join};
use crate::model::{Group, Kind};

/// The struct: private fields holding raw values (enums as enums), plus the instance index of
/// a family.
pub(super) fn render(g: &Group) -> String {
    let instance = if g.is_family() { "instance: u8,\n" } else { "" };
    let fields = join(&g.first().signals, "", |s| {
        let ty = match &s.kind {
            Kind::Enum(e) => e.as_str(),
            _ => s.raw_ty.name(),
        };
        format!("{}: {ty},\n", s.field)
    });
    format!(
        "{}#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct {} {{
{instance}{fields}}}

",
        doc(&description(g)),
        g.ty
    )
}

/// Which messages, the DBC comment, timing, nodes and E2E protection.
fn description(g: &Group) -> String {
    let m = g.first();
    let what = if g.is_family() {
        let names = join(&g.messages, ", ", |m| m.name.clone());
        let ids = join(&g.messages, ", ", |m| format!("{:#05x}", m.id));
        format!(
            "Messages {names} (one per instance, ids {ids}), as one type with an instance index."
        )
    } else {
        format!("Message {} (id {:#05x}).", m.name, m.id)
    };
    let comment = m
        .comment
        .as_ref()
        .map(|c| format!("{c}\n\n"))
        .unwrap_or_default();
    let e2e = m.e2e.map(|e| {
        let which = if g.is_family() { " for instance 0" } else { "" };
        format!(
            " E2E protected: CRC-8 in byte 0, {}-bit alive counter (data id {:#06x}{which})",
            e.counter_bits, e.data_id
        )
    });
    format!(
        "{what}\n\n{comment}DLC {}, every {} ms, sent by {}, received by {}.{}",
        m.dlc,
        m.cycle_ms,
        m.senders.join(", "),
        m.receivers.join(", "),
        e2e.unwrap_or_default()
    )
}
