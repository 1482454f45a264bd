//! `MESSAGES`: the DBC as data (bus load, tools, cross-checks), one entry per DBC message in
//! file order.
//!
//! Unlike the other renderers, this one indents: its long string literals (DBC comments) do not
//! fit rustfmt's width, so rustfmt leaves the table exactly as written.

use super::consts::profile;
use super::{flit, join};
use crate::model::{Group, Message, Signal};

/// The `MESSAGES` table.
pub(super) fn render(groups: &[Group]) -> String {
    let entries: String = groups
        .iter()
        .flat_map(|g| &g.messages)
        .map(message)
        .collect();
    format!(
        "/// Every message of hand.dbc in file order, with its signals: the DBC as data (bus \
         load, tools, cross-checks).
pub const MESSAGES: &[MessageInfo] = &[
{entries}];
"
    )
}

fn message(m: &Message) -> String {
    let e2e = match m.e2e {
        Some(e) => format!("Some({})", profile(e.data_id, e.counter_bits, m.dlc)),
        None => "None".to_string(),
    };
    format!(
        "    MessageInfo {{
        name: {:?},
        id: {:#05x},
        dlc: {},
        cycle_time_ms: {},
        senders: &[{}],
        receivers: &[{}],
        e2e: {e2e},
        comment: {:?},
        signals: &[
{}        ],
    }},
",
        m.name,
        m.id,
        m.dlc,
        m.cycle_ms,
        join(&m.senders, ", ", |s| format!("{s:?}")),
        join(&m.receivers, ", ", |s| format!("{s:?}")),
        m.comment.clone().unwrap_or_default(),
        join(&m.signals, "", signal)
    )
}

fn signal(s: &Signal) -> String {
    format!(
        "            SignalInfo {{ name: {:?}, start_bit: {}, size: {}, signed: {}, factor: {}, offset: {}, \
         min: {}, max: {}, raw_min: {}, raw_max: {}, unit: {:?}, values: &[{}], comment: {:?} }},\n",
        s.name,
        s.start,
        s.size,
        s.signed,
        flit(s.factor),
        flit(s.offset),
        flit(s.min),
        flit(s.max),
        s.raw_min,
        s.raw_max,
        s.unit,
        join(&s.values, ", ", |(v, d)| format!("({v}, {d:?})")),
        s.comment.clone().unwrap_or_default()
    )
}
