//! Associated consts: names, ids, DLC, cycle time, E2E profiles and each signal's range and
//! scaling.

use super::{flit, join};
use crate::model::{Group, Kind, Message, Signal};

/// Every associated const of a message type.
pub(super) fn render(g: &Group) -> String {
    let m = g.first();
    let mut out = if g.is_family() { family(g) } else { single(m) };
    out += &format!(
        "/// Payload length in bytes.
pub const DLC: usize = {};
/// Send period from `GenMsgCycleTime` (ms).
pub const CYCLE_TIME_MS: u32 = {};
",
        m.dlc, m.cycle_ms
    );
    out += &e2e(g);
    for s in &m.signals {
        out += &signal(s);
    }
    out + "\n"
}

fn family(g: &Group) -> String {
    let n = g.messages.len();
    let names = join(&g.messages, ", ", |m| format!("{:?}", m.name));
    let ids = join(&g.messages, ", ", |m| format!("{:#05x}", m.id));
    format!(
        "/// Number of instances (e.g. one per finger).
pub const INSTANCES: usize = {n};
/// Family name in hand.dbc (member names add `_<instance>`).
pub const NAME: &'static str = {:?};
/// DBC name of each instance.
pub const NAMES: [&'static str; {n}] = [{names}];
/// CAN id of each instance.
pub const IDS: [u32; {n}] = [{ids}];
",
        g.name
    )
}

fn single(m: &Message) -> String {
    format!(
        "/// Name in hand.dbc.
pub const NAME: &'static str = {:?};
/// CAN id (11-bit).
pub const ID: u32 = {:#05x};
",
        m.name, m.id
    )
}

/// `E2E`: one profile, or one per instance.
fn e2e(g: &Group) -> String {
    if g.first().e2e.is_none() {
        return String::new();
    }
    // Family members are all protected or all not (checked in the model).
    let profiles: Vec<String> = g
        .messages
        .iter()
        .filter_map(|m| m.e2e.map(|e| profile(e.data_id, e.counter_bits, m.dlc)))
        .collect();
    let profiles = profiles.join(", ");
    if g.is_family() {
        let n = g.messages.len();
        format!(
            "/// E2E profile of each instance.\npub const E2E: [E2eProfile; {n}] = [{profiles}];\n"
        )
    } else {
        format!("/// E2E profile.\npub const E2E: E2eProfile = {profiles};\n")
    }
}

/// The `E2eProfile` expression for a protected message.
pub(super) fn profile(data_id: u16, counter_bits: u32, dlc: u32) -> String {
    format!("E2eProfile::from_dbc({data_id:#06x}, {counter_bits}, {dlc})")
}

/// `_MIN`/`_MAX` (physical for scaled signals, raw otherwise; none for enums), and for scaled
/// signals `_FACTOR`, `_OFFSET` and the raw range `_RAW_MIN`/`_RAW_MAX`.
fn signal(s: &Signal) -> String {
    let (name, unit, up, raw_ty) = (&s.name, &s.unit, s.upper(), s.raw_ty.name());
    let (ty, lo, hi) = match s.kind {
        Kind::Enum(_) => return String::new(),
        Kind::Int => (raw_ty, s.raw_min.to_string(), s.raw_max.to_string()),
        Kind::Scaled => ("f64", flit(s.min), flit(s.max)),
    };
    let range = format!(
        "/// Smallest allowed `{name}` ({unit}).
pub const {up}_MIN: {ty} = {lo};
/// Largest allowed `{name}` ({unit}).
pub const {up}_MAX: {ty} = {hi};
"
    );
    if s.kind != Kind::Scaled {
        return range;
    }
    range
        + &format!(
            "/// `{name}`: {unit} per raw step.
pub const {up}_FACTOR: f64 = {};
/// `{name}`: physical value of raw 0 ({unit}).
pub const {up}_OFFSET: f64 = {};
/// Smallest allowed raw `{name}` on the bus.
pub const {up}_RAW_MIN: {raw_ty} = {};
/// Largest allowed raw `{name}` on the bus.
pub const {up}_RAW_MAX: {raw_ty} = {};
",
            flit(s.factor),
            flit(s.offset),
            s.raw_min,
            s.raw_max
        )
}
