//! Value tables as Rust enums, with the raw value and the DBC name of each variant.

use super::{doc, join};
use crate::model::EnumDef;
use crate::names::camel;

/// The enum and its `ALL`, `raw`, `from_raw` and `dbc_name`.
pub(super) fn render(e: &EnumDef) -> String {
    let name = &e.name;
    let variants = join(&e.values, "", |(v, d)| {
        format!("{}{},\n", doc(&format!("`{d}` (raw {v})")), camel(d))
    });
    format!(
        "/// Value table `{name}` of hand.dbc.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum {name} {{
{variants}}}

{}",
        methods(e)
    )
}

fn methods(e: &EnumDef) -> String {
    let name = &e.name;
    let max = e.values.iter().map(|v| v.0).max().unwrap_or(0);
    let repr = if max <= i64::from(u8::MAX) {
        "u8"
    } else {
        "u32"
    };
    let n = e.values.len();
    let all = join(&e.values, ", ", |(_, d)| format!("{name}::{}", camel(d)));
    let to_raw = join(&e.values, "", |(v, d)| {
        format!("{name}::{} => {v},\n", camel(d))
    });
    let from_raw = join(&e.values, "", |(v, d)| {
        format!("{v} => Some({name}::{}),\n", camel(d))
    });
    let names = join(&e.values, "", |(_, d)| {
        format!("{name}::{} => {d:?},\n", camel(d))
    });
    format!(
        "impl {name} {{
    /// Every value, in raw order.
    pub const ALL: [{name}; {n}] = [{all}];

    /// The raw value on the bus.
    pub const fn raw(self) -> {repr} {{
        match self {{
{to_raw}        }}
    }}

    /// The value for a raw value, `None` if the table does not name it.
    pub const fn from_raw(raw: i64) -> Option<Self> {{
        match raw {{
{from_raw}            _ => None,
        }}
    }}

    /// The name hand.dbc gives this value.
    pub const fn dbc_name(self) -> &'static str {{
        match self {{
{names}        }}
    }}
}}

"
    )
}
