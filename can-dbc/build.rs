//! Generates the message codec from `hand.dbc` into `$OUT_DIR/messages.rs`.
//!
//! Parsing happens here only, so the crate itself stays plain Rust (no parser in ARM builds).
//! Every inconsistency in the DBC (a range that the bits cannot hold, a value table outside the
//! range, an E2E message without the fixed CRC/counter layout, a Motorola signal) stops the
//! build with a message naming the message and signal, so a bad edit never yields a codec that
//! silently disagrees with the file.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::PathBuf;

use can_dbc::{
    AttributeValue, ByteOrder, Dbc, MessageId, MultiplexIndicator, NumericValue, ValueType,
};

type Res<T> = Result<T, String>;
/// Value table entries (raw value, name) by enum type name.
type Enums = BTreeMap<String, Vec<(i64, String)>>;

fn main() {
    let manifest = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").expect("cargo sets this"));
    let dbc_path = manifest.join("hand.dbc");
    println!("cargo:rerun-if-changed={}", dbc_path.display());
    println!("cargo:rerun-if-changed=build.rs");
    let text = std::fs::read_to_string(&dbc_path)
        .unwrap_or_else(|e| panic!("cannot read {}: {e}", dbc_path.display()));
    let code = match generate(&text) {
        Ok(code) => code,
        Err(e) => panic!("hand.dbc: {e}"),
    };
    let out = PathBuf::from(std::env::var("OUT_DIR").expect("cargo sets this")).join("messages.rs");
    std::fs::write(&out, code).unwrap_or_else(|e| panic!("cannot write {}: {e}", out.display()));
}

#[derive(Clone, Debug, PartialEq)]
enum Kind {
    /// Value table: the field is the named enum.
    Enum(String),
    /// factor 1, offset 0: the field is the integer itself.
    Int,
    /// Anything else: raw integer stored, physical f64 at the API.
    Scaled,
}

#[derive(Clone, Debug)]
struct Sig {
    name: String,
    field: String,
    start: u32,
    size: u32,
    signed: bool,
    factor: f64,
    offset: f64,
    min: f64,
    max: f64,
    raw_min: i64,
    raw_max: i64,
    raw_ty: &'static str,
    unit: String,
    comment: Option<String>,
    kind: Kind,
    values: Vec<(i64, String)>,
}

impl Sig {
    /// Same layout, scaling and values (comments and receivers may differ between instances).
    fn same_layout(&self, o: &Sig) -> bool {
        self.name == o.name
            && self.start == o.start
            && self.size == o.size
            && self.signed == o.signed
            && self.factor == o.factor
            && self.offset == o.offset
            && self.min == o.min
            && self.max == o.max
            && self.unit == o.unit
            && self.kind == o.kind
            && self.values == o.values
    }

    fn type_min(&self) -> i64 {
        match self.raw_ty {
            "u8" | "u16" | "u32" | "u64" => 0,
            "i8" => i64::from(i8::MIN),
            "i16" => i64::from(i16::MIN),
            "i32" => i64::from(i32::MIN),
            _ => i64::MIN,
        }
    }

    fn type_max(&self) -> i64 {
        match self.raw_ty {
            "u8" => i64::from(u8::MAX),
            "u16" => i64::from(u16::MAX),
            "u32" => i64::from(u32::MAX),
            "i8" => i64::from(i8::MAX),
            "i16" => i64::from(i16::MAX),
            "i32" => i64::from(i32::MAX),
            _ => i64::MAX,
        }
    }

    fn bit_min(&self) -> i64 {
        if self.signed {
            -(1i64 << (self.size - 1))
        } else {
            0
        }
    }

    fn bit_max(&self) -> i64 {
        if self.signed {
            (1i64 << (self.size - 1)) - 1
        } else {
            (1i64 << self.size) - 1
        }
    }

    fn api_ty(&self) -> String {
        match &self.kind {
            Kind::Enum(e) => e.clone(),
            Kind::Int => self.raw_ty.to_string(),
            Kind::Scaled => "f64".to_string(),
        }
    }

    fn upper(&self) -> String {
        self.field.to_uppercase()
    }
}

#[derive(Clone, Debug)]
struct Msg {
    name: String,
    id: u32,
    dlc: u32,
    cycle_ms: u32,
    senders: Vec<String>,
    receivers: Vec<String>,
    comment: Option<String>,
    sigs: Vec<Sig>,
    /// (data id, counter bits)
    e2e: Option<(u16, u32)>,
}

/// One generated type: a single message, or a family of identical per-instance messages
/// (`FINGER_SETPOINT_0..4`) that becomes one type with an instance index.
#[derive(Debug)]
struct Group {
    ty: String,
    name: String,
    msgs: Vec<Msg>,
}

impl Group {
    fn family(&self) -> bool {
        self.msgs.len() > 1
    }
    fn first(&self) -> &Msg {
        &self.msgs[0]
    }
}

fn camel(name: &str) -> String {
    let mut out = String::new();
    for part in name.split(['_', ' ', '-']) {
        let mut chars = part.chars();
        if let Some(c) = chars.next() {
            out.push(c.to_ascii_uppercase());
            let rest: String = chars.collect();
            // Keep existing CamelCase (e.g. `LeadOffMask`) but tame ALL_CAPS words.
            if part.chars().all(|c| !c.is_ascii_lowercase()) {
                out.push_str(&rest.to_ascii_lowercase());
            } else {
                out.push_str(&rest);
            }
        }
    }
    if out.starts_with(|c: char| c.is_ascii_digit()) {
        out.insert(0, 'V');
    }
    out
}

fn snake(name: &str) -> String {
    let mut out = String::new();
    let chars: Vec<char> = name.chars().collect();
    for (i, &c) in chars.iter().enumerate() {
        if c.is_ascii_uppercase() {
            let prev_lower = i > 0 && (chars[i - 1].is_ascii_lowercase());
            let prev_digit_boundary = i > 0 && chars[i - 1].is_ascii_digit();
            let next_lower = chars.get(i + 1).is_some_and(|n| n.is_ascii_lowercase());
            let prev_upper = i > 0 && chars[i - 1].is_ascii_uppercase();
            if i > 0
                && !out.ends_with('_')
                && (prev_lower || prev_digit_boundary || (prev_upper && next_lower))
            {
                out.push('_');
            }
            out.push(c.to_ascii_lowercase());
        } else if c == '-' || c == ' ' {
            out.push('_');
        } else {
            out.push(c);
        }
    }
    match out.as_str() {
        "type" | "match" | "mod" | "ref" | "self" | "fn" | "use" | "loop" | "move" => {
            format!("{out}_")
        }
        _ => out,
    }
}

fn num(v: &NumericValue) -> f64 {
    match v {
        NumericValue::Uint(u) => *u as f64,
        NumericValue::Int(i) => *i as f64,
        NumericValue::Double(d) => *d,
    }
}

fn attr_int(v: Option<&AttributeValue>) -> Option<i64> {
    match v? {
        AttributeValue::Uint(u) => i64::try_from(*u).ok(),
        AttributeValue::Int(i) => Some(*i),
        AttributeValue::Double(d) => Some(*d as i64),
        AttributeValue::String(_) => None,
    }
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

fn doc(text: &str) -> String {
    format!("#[doc = {text:?}]\n")
}

fn parse(text: &str) -> Res<(Vec<Group>, Enums)> {
    let dbc = Dbc::try_from(text).map_err(|e| format!("parse error: {e:?}"))?;
    let mut tables: BTreeMap<String, Vec<(i64, String)>> = BTreeMap::new();
    for t in &dbc.value_tables {
        let mut v: Vec<(i64, String)> = t
            .descriptions
            .iter()
            .map(|d| (d.id, d.description.clone()))
            .collect();
        v.sort();
        tables.insert(camel(&t.name), v);
    }
    let mut enums: BTreeMap<String, Vec<(i64, String)>> = BTreeMap::new();
    let mut msgs = Vec::new();
    let mut seen_ids = BTreeMap::new();
    for m in &dbc.messages {
        let id = match m.id {
            MessageId::Standard(id) => u32::from(id),
            MessageId::Extended(_) => {
                return Err(format!("{}: extended ids are not used on this bus", m.name))
            }
        };
        if id > 0x7FF {
            return Err(format!("{}: id {id:#x} exceeds 11 bits", m.name));
        }
        if let Some(other) = seen_ids.insert(id, m.name.clone()) {
            return Err(format!("{} and {other} share id {id:#x}", m.name));
        }
        let dlc = u32::try_from(m.size).map_err(|_| format!("{}: bad DLC", m.name))?;
        if dlc > 8 {
            return Err(format!("{}: DLC {dlc} > 8 (classic CAN only)", m.name));
        }
        let cycle_ms = attr_int(dbc.resolved_message_attribute(m.id, "GenMsgCycleTime"))
            .ok_or_else(|| format!("{}: no GenMsgCycleTime", m.name))?;
        let cycle_ms = u32::try_from(cycle_ms)
            .map_err(|_| format!("{}: GenMsgCycleTime {cycle_ms} out of range", m.name))?;
        let data_id = attr_int(dbc.resolved_message_attribute(m.id, "HandE2EDataId")).unwrap_or(0);
        let mut senders: Vec<String> = m.transmitter.iter().cloned().collect();
        for t in &dbc.message_transmitters {
            if t.message_id == m.id {
                for s in &t.transmitter {
                    if !senders.contains(s) {
                        senders.push(s.clone());
                    }
                }
            }
        }
        let mut receivers: Vec<String> = Vec::new();
        let mut sigs = Vec::new();
        let mut occupied = 0u64;
        let msg_ty = camel(&m.name);
        for s in &m.signals {
            let ctx = format!("{}.{}", m.name, s.name);
            if s.multiplexer_indicator != MultiplexIndicator::Plain {
                return Err(format!(
                    "{ctx}: multiplexing is not supported by the generator"
                ));
            }
            if s.byte_order != ByteOrder::LittleEndian {
                return Err(format!(
                    "{ctx}: only little-endian (@1) signals are supported"
                ));
            }
            let start = u32::try_from(s.start_bit).map_err(|_| format!("{ctx}: start bit"))?;
            let size = u32::try_from(s.size).map_err(|_| format!("{ctx}: size"))?;
            if size == 0 || size > 63 || start + size > dlc * 8 {
                return Err(format!(
                    "{ctx}: bits {start}..{} do not fit a {dlc}-byte payload (or size not 1..=63)",
                    start + size
                ));
            }
            let mask = ((1u64 << size) - 1) << start;
            if occupied & mask != 0 {
                return Err(format!("{ctx}: overlaps another signal"));
            }
            occupied |= mask;
            for r in &s.receivers {
                if r != "Vector__XXX" && !receivers.contains(r) {
                    receivers.push(r.clone());
                }
            }
            let signed = s.value_type == ValueType::Signed;
            let (factor, offset) = (s.factor, s.offset);
            if factor <= 0.0 || factor.is_nan() || !factor.is_finite() || !offset.is_finite() {
                return Err(format!("{ctx}: factor must be positive and finite"));
            }
            let (min, max) = (num(&s.min), num(&s.max));
            if min >= max || min.is_nan() || max.is_nan() {
                return Err(format!(
                    "{ctx}: give a range with min < max, got [{min}|{max}]"
                ));
            }
            let (bit_min, bit_max) = if signed {
                (-(1i64 << (size - 1)), (1i64 << (size - 1)) - 1)
            } else {
                (0, (1i64 << size) - 1)
            };
            let rmin = ((min - offset) / factor - 1e-9).ceil();
            let rmax = ((max - offset) / factor + 1e-9).floor();
            if rmin < bit_min as f64 || rmax > bit_max as f64 {
                return Err(format!(
                    "{ctx}: range [{min}|{max}] needs raw [{rmin}|{rmax}], {size} bits hold \
                     [{bit_min}|{bit_max}]"
                ));
            }
            let (raw_min, raw_max) = (rmin as i64, rmax as i64);
            let raw_ty = match (signed, size) {
                (false, 1..=8) => "u8",
                (false, 9..=16) => "u16",
                (false, 17..=32) => "u32",
                (false, _) => "u64",
                (true, 1..=8) => "i8",
                (true, 9..=16) => "i16",
                (true, 17..=32) => "i32",
                (true, _) => "i64",
            };
            let mut values: Vec<(i64, String)> = dbc
                .value_descriptions_for_signal(m.id, &s.name)
                .unwrap_or(&[])
                .iter()
                .map(|d| (d.id, d.description.clone()))
                .collect();
            values.sort();
            let is_int = factor == 1.0 && offset == 0.0;
            let kind = if !values.is_empty() {
                if !is_int {
                    return Err(format!("{ctx}: a value table needs factor 1 and offset 0"));
                }
                for (v, d) in &values {
                    if *v < raw_min || *v > raw_max {
                        return Err(format!("{ctx}: value {v} \"{d}\" is outside the range"));
                    }
                }
                let name = tables
                    .iter()
                    .find(|(_, t)| **t == values)
                    .map(|(n, _)| n.clone())
                    .unwrap_or_else(|| format!("{msg_ty}{}", camel(&s.name)));
                if let Some(prev) = enums.get(&name) {
                    if *prev != values {
                        return Err(format!("{ctx}: enum {name} defined twice differently"));
                    }
                }
                enums.insert(name.clone(), values.clone());
                Kind::Enum(name)
            } else if is_int {
                Kind::Int
            } else {
                Kind::Scaled
            };
            sigs.push(Sig {
                name: s.name.clone(),
                field: snake(&s.name),
                start,
                size,
                signed,
                factor,
                offset,
                min,
                max,
                raw_min,
                raw_max,
                raw_ty,
                unit: s.unit.clone(),
                comment: dbc.signal_comment(m.id, &s.name).map(str::to_string),
                kind,
                values,
            });
        }
        let e2e = if data_id > 0 {
            let data_id = u16::try_from(data_id)
                .map_err(|_| format!("{}: HandE2EDataId must fit 16 bits", m.name))?;
            let crc = sigs.iter().find(|s| s.name == "Crc");
            let ctr = sigs.iter().find(|s| s.name == "Counter");
            match (crc, ctr) {
                (Some(c), Some(k))
                    if c.start == 0
                        && c.size == 8
                        && k.start == 8
                        && (k.size == 4 || k.size == 8)
                        && !k.signed
                        && k.kind == Kind::Int
                        && c.kind == Kind::Int
                        && k.raw_min == 0
                        && k.raw_max == (1 << k.size) - 1
                        && c.raw_min == 0
                        && c.raw_max == 255 =>
                {
                    Some((data_id, k.size))
                }
                _ => {
                    return Err(format!(
                        "{}: E2E messages need Crc at bits 0..8 and an unsigned full-range \
                         Counter of 4 or 8 bits at bit 8",
                        m.name
                    ))
                }
            }
        } else {
            None
        };
        msgs.push(Msg {
            name: m.name.clone(),
            id,
            dlc,
            cycle_ms,
            senders,
            receivers,
            comment: dbc.message_comment(m.id).map(str::to_string),
            sigs,
            e2e,
        });
    }
    // Families: NAME_<n> for n = 0..N with identical layouts become one type.
    let mut groups: Vec<Group> = Vec::new();
    let mut families: BTreeMap<String, Vec<Msg>> = BTreeMap::new();
    let mut order: Vec<String> = Vec::new();
    for m in msgs {
        let key = match m.name.rsplit_once('_') {
            Some((base, n)) if !n.is_empty() && n.chars().all(|c| c.is_ascii_digit()) => {
                base.to_string()
            }
            _ => m.name.clone(),
        };
        if !families.contains_key(&key) {
            order.push(key.clone());
        }
        families.entry(key).or_default().push(m);
    }
    for key in order {
        let members = families.remove(&key).unwrap_or_default();
        let is_family = members.len() > 1
            && members.iter().enumerate().all(|(i, m)| {
                m.name == format!("{key}_{i}")
                    && m.dlc == members[0].dlc
                    && m.cycle_ms == members[0].cycle_ms
                    && m.e2e.map(|e| e.1) == members[0].e2e.map(|e| e.1)
                    && m.sigs.len() == members[0].sigs.len()
                    && m.sigs
                        .iter()
                        .zip(&members[0].sigs)
                        .all(|(a, b)| a.same_layout(b))
            });
        if is_family {
            groups.push(Group {
                ty: camel(&key),
                name: key,
                msgs: members,
            });
        } else {
            for m in members {
                groups.push(Group {
                    ty: camel(&m.name),
                    name: m.name.clone(),
                    msgs: vec![m],
                });
            }
        }
    }
    Ok((groups, enums))
}

/// The Rust source for a DBC text, or why the DBC is refused.
pub(crate) fn generate(text: &str) -> Res<String> {
    let (groups, enums) = parse(text)?;
    let mut o = String::new();
    o.push_str("// @generated by can-dbc/build.rs from hand.dbc. Do not edit: edit hand.dbc.\n\n");
    for (name, values) in &enums {
        gen_enum(&mut o, name, values);
    }
    for g in &groups {
        gen_group(&mut o, g)?;
    }
    gen_dispatch(&mut o, &groups);
    gen_info(&mut o, &groups);
    Ok(o)
}

fn gen_enum(o: &mut String, name: &str, values: &[(i64, String)]) {
    let max = values.iter().map(|v| v.0).max().unwrap_or(0);
    let repr = if max <= i64::from(u8::MAX) {
        "u8"
    } else {
        "u32"
    };
    let _ = writeln!(
        o,
        "{}",
        doc(&format!("Value table `{name}` of hand.dbc.")).trim_end()
    );
    let _ = writeln!(o, "#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]");
    let _ = writeln!(o, "pub enum {name} {{");
    for (v, d) in values {
        let _ = write!(o, "    {}", doc(&format!("`{d}` (raw {v})")));
        let _ = writeln!(o, "    {},", camel(d));
    }
    let _ = writeln!(o, "}}\n");
    let _ = writeln!(o, "impl {name} {{");
    let _ = writeln!(o, "    /// Every value, in raw order.");
    let _ = write!(o, "    pub const ALL: [{name}; {}] = [", values.len());
    for (_, d) in values {
        let _ = write!(o, "{name}::{}, ", camel(d));
    }
    let _ = writeln!(o, "];\n");
    let _ = writeln!(o, "    /// The raw value on the bus.");
    let _ = writeln!(
        o,
        "    pub const fn raw(self) -> {repr} {{\n        match self {{"
    );
    for (v, d) in values {
        let _ = writeln!(o, "            {name}::{} => {v},", camel(d));
    }
    let _ = writeln!(o, "        }}\n    }}\n");
    let _ = writeln!(
        o,
        "    /// The value for a raw value, `None` if the table does not name it."
    );
    let _ = writeln!(
        o,
        "    pub const fn from_raw(raw: i64) -> Option<Self> {{\n        match raw {{"
    );
    for (v, d) in values {
        let _ = writeln!(o, "            {v} => Some({name}::{}),", camel(d));
    }
    let _ = writeln!(o, "            _ => None,\n        }}\n    }}\n");
    let _ = writeln!(o, "    /// The name hand.dbc gives this value.");
    let _ = writeln!(
        o,
        "    pub const fn dbc_name(self) -> &'static str {{\n        match self {{"
    );
    for (_, d) in values {
        let _ = writeln!(o, "            {name}::{} => {d:?},", camel(d));
    }
    let _ = writeln!(o, "        }}\n    }}\n}}\n");
}

/// Expression extracting signal `s` (as its raw type) from the `u64` named `bits`.
fn extract(s: &Sig) -> String {
    if s.signed {
        let up = 64 - s.start - s.size;
        let down = 64 - s.size;
        if up == 0 {
            format!("((bits as i64) >> {down}) as {}", s.raw_ty)
        } else {
            format!("(((bits << {up}) as i64) >> {down}) as {}", s.raw_ty)
        }
    } else {
        let mask = (1u64 << s.size) - 1;
        if s.start == 0 {
            format!("(bits & {mask:#x}) as {}", s.raw_ty)
        } else {
            format!("((bits >> {}) & {mask:#x}) as {}", s.start, s.raw_ty)
        }
    }
}

/// Statement OR-ing the raw value expression `raw` (of the signal's raw type) into `bits`.
fn insert(s: &Sig, raw: &str) -> String {
    let mask = (1u64 << s.size) - 1;
    let widened = if s.signed {
        if s.raw_ty == "i64" {
            format!("({raw} as u64)")
        } else {
            format!("(i64::from({raw}) as u64)")
        }
    } else if s.raw_ty == "u64" {
        raw.to_string()
    } else {
        format!("u64::from({raw})")
    };
    if s.start == 0 {
        format!("bits |= {widened} & {mask:#x};")
    } else {
        format!("bits |= ({widened} & {mask:#x}) << {};", s.start)
    }
}

/// Code checking the raw value `v` (signal raw type) against the DBC raw range; emits only the
/// comparisons the type does not already guarantee.
fn raw_check(s: &Sig, v: &str, name_expr: &str) -> String {
    let mut conds = Vec::new();
    if s.raw_min > s.type_min() {
        conds.push(format!("{v} < {}", s.raw_min));
    }
    if s.raw_max < s.type_max() {
        conds.push(format!("{v} > {}", s.raw_max));
    }
    if conds.is_empty() {
        return String::new();
    }
    let cond = if conds.len() == 2 {
        format!("!({}..={}).contains(&{v})", s.raw_min, s.raw_max)
    } else {
        conds.join(" || ")
    };
    let raw_i64 = if s.raw_ty == "u64" {
        format!("{v} as i64")
    } else {
        format!("i64::from({v})")
    };
    let message = if name_expr == "message" {
        "message".to_string()
    } else {
        format!("message: {name_expr}")
    };
    format!(
        "if {} {{ return Err(CodecError::RawOutOfRange {{ {message}, signal: {:?}, \
         raw: {raw_i64}, min: {}, max: {} }}); }}\n",
        cond, s.name, s.raw_min, s.raw_max
    )
}

fn raw_to_f64(s: &Sig, v: &str) -> String {
    match s.raw_ty {
        "u64" | "i64" => format!("({v} as f64)"),
        _ => format!("f64::from({v})"),
    }
}

fn gen_group(o: &mut String, g: &Group) -> Res<()> {
    let m = g.first();
    let ty = &g.ty;
    let n = g.msgs.len();
    let fam = g.family();
    let name_expr = if fam {
        "Self::NAMES[usize::from(self.instance)]".to_string()
    } else {
        "Self::NAME".to_string()
    };

    // Struct.
    let mut d = String::new();
    if fam {
        let _ = writeln!(
            d,
            "Messages {} (one per instance, ids {}), as one type with an instance index.\n",
            g.msgs
                .iter()
                .map(|m| m.name.as_str())
                .collect::<Vec<_>>()
                .join(", "),
            g.msgs
                .iter()
                .map(|m| format!("{:#05x}", m.id))
                .collect::<Vec<_>>()
                .join(", ")
        );
    } else {
        let _ = writeln!(d, "Message {} (id {:#05x}).\n", m.name, m.id);
    }
    if let Some(c) = &m.comment {
        let _ = writeln!(d, "{c}\n");
    }
    let _ = write!(
        d,
        "DLC {}, every {} ms, sent by {}, received by {}.",
        m.dlc,
        m.cycle_ms,
        m.senders.join(", "),
        m.receivers.join(", ")
    );
    if let Some((id, bits)) = m.e2e {
        let _ = write!(
            d,
            " E2E protected: CRC-8 in byte 0, {bits}-bit alive counter (data id {id:#06x}{})",
            if fam { " for instance 0" } else { "" }
        );
    }
    o.push_str(&doc(&d));
    let _ = writeln!(o, "#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]");
    let _ = writeln!(o, "pub struct {ty} {{");
    if fam {
        let _ = writeln!(o, "    instance: u8,");
    }
    for s in &m.sigs {
        let fty = match &s.kind {
            Kind::Enum(e) => e.as_str(),
            _ => s.raw_ty,
        };
        let _ = writeln!(o, "    {}: {fty},", s.field);
    }
    let _ = writeln!(o, "}}\n");

    let _ = writeln!(o, "impl {ty} {{");
    // Consts.
    if fam {
        let _ = writeln!(o, "    /// Number of instances (e.g. one per finger).");
        let _ = writeln!(o, "    pub const INSTANCES: usize = {n};");
        let _ = writeln!(
            o,
            "    /// Family name in hand.dbc (member names add `_<instance>`)."
        );
        let _ = writeln!(o, "    pub const NAME: &'static str = {:?};", g.name);
        let _ = writeln!(o, "    /// DBC name of each instance.");
        let _ = writeln!(
            o,
            "    pub const NAMES: [&'static str; {n}] = [{}];",
            g.msgs
                .iter()
                .map(|m| format!("{:?}", m.name))
                .collect::<Vec<_>>()
                .join(", ")
        );
        let _ = writeln!(o, "    /// CAN id of each instance.");
        let _ = writeln!(
            o,
            "    pub const IDS: [u32; {n}] = [{}];",
            g.msgs
                .iter()
                .map(|m| format!("{:#05x}", m.id))
                .collect::<Vec<_>>()
                .join(", ")
        );
    } else {
        let _ = writeln!(o, "    /// Name in hand.dbc.");
        let _ = writeln!(o, "    pub const NAME: &'static str = {:?};", m.name);
        let _ = writeln!(o, "    /// CAN id (11-bit).");
        let _ = writeln!(o, "    pub const ID: u32 = {:#05x};", m.id);
    }
    let _ = writeln!(o, "    /// Payload length in bytes.");
    let _ = writeln!(o, "    pub const DLC: usize = {};", m.dlc);
    let _ = writeln!(o, "    /// Send period from `GenMsgCycleTime` (ms).");
    let _ = writeln!(o, "    pub const CYCLE_TIME_MS: u32 = {};", m.cycle_ms);
    if m.e2e.is_some() {
        let profiles: Vec<String> = g
            .msgs
            .iter()
            .map(|mm| {
                let (id, bits) = mm.e2e.expect("family members share E2E");
                format!("E2eProfile::from_dbc({id:#06x}, {bits}, {})", mm.dlc)
            })
            .collect();
        if fam {
            let _ = writeln!(o, "    /// E2E profile of each instance.");
            let _ = writeln!(
                o,
                "    pub const E2E: [E2eProfile; {n}] = [{}];",
                profiles.join(", ")
            );
        } else {
            let _ = writeln!(o, "    /// E2E profile.");
            let _ = writeln!(o, "    pub const E2E: E2eProfile = {};", profiles[0]);
        }
    }
    for s in &m.sigs {
        let up = s.upper();
        let ty_c = match s.kind {
            Kind::Scaled => "f64",
            _ => s.raw_ty,
        };
        let (lo, hi) = match s.kind {
            Kind::Scaled => (flit(s.min), flit(s.max)),
            _ => (s.raw_min.to_string(), s.raw_max.to_string()),
        };
        if !matches!(s.kind, Kind::Enum(_)) {
            let _ = writeln!(o, "    /// Smallest allowed `{}` ({}).", s.name, s.unit);
            let _ = writeln!(o, "    pub const {up}_MIN: {ty_c} = {lo};");
            let _ = writeln!(o, "    /// Largest allowed `{}` ({}).", s.name, s.unit);
            let _ = writeln!(o, "    pub const {up}_MAX: {ty_c} = {hi};");
        }
        if s.kind == Kind::Scaled {
            let _ = writeln!(o, "    /// `{}`: {} per raw step.", s.name, s.unit);
            let _ = writeln!(o, "    pub const {up}_FACTOR: f64 = {};", flit(s.factor));
            let _ = writeln!(
                o,
                "    /// `{}`: physical value of raw 0 ({}).",
                s.name, s.unit
            );
            let _ = writeln!(o, "    pub const {up}_OFFSET: f64 = {};", flit(s.offset));
        }
    }
    o.push('\n');

    // Constructor.
    let e2e_sig = |s: &Sig| m.e2e.is_some() && (s.name == "Crc" || s.name == "Counter");
    let args: Vec<&Sig> = m.sigs.iter().filter(|s| !e2e_sig(s)).collect();
    let mut cd =
        String::from("Builds the message from physical values, each checked against hand.dbc.");
    if m.e2e.is_some() {
        cd.push_str(
            " Crc and Counter start at 0: an [`crate::e2e::E2eProtector`] fills them when sending.",
        );
    }
    o.push_str(&indent(&doc(&cd), 1));
    let n_args = args.len() + usize::from(fam);
    if n_args > 7 {
        let _ = writeln!(
            o,
            "    #[allow(clippy::too_many_arguments, reason = \"one argument per DBC signal\")]"
        );
    }
    let _ = write!(o, "    pub fn new(");
    let mut params = Vec::new();
    if fam {
        params.push("instance: usize".to_string());
    }
    for s in &args {
        params.push(format!("{}: {}", s.field, s.api_ty()));
    }
    let _ = writeln!(o, "{}) -> Result<Self, CodecError> {{", params.join(", "));
    if fam {
        let _ = writeln!(
            o,
            "        if instance >= {n} {{ return Err(CodecError::InstanceOutOfRange {{ message: \
             Self::NAME, instance, count: {n} }}); }}"
        );
    }
    let _ = writeln!(o, "        let mut msg = Self {{");
    if fam {
        let _ = writeln!(o, "            instance: instance as u8,");
    }
    for s in &m.sigs {
        let init = match &s.kind {
            Kind::Enum(e) => format!("{e}::ALL[0]"),
            _ => {
                // Zero may lie outside the range; start from the raw minimum when it does.
                let z = if s.raw_min <= 0 && 0 <= s.raw_max {
                    0
                } else {
                    s.raw_min
                };
                z.to_string()
            }
        };
        let _ = writeln!(o, "            {}: {init},", s.field);
    }
    let _ = writeln!(o, "        }};");
    for s in &args {
        match s.kind {
            Kind::Enum(_) => {
                let _ = writeln!(o, "        msg.set_{}({});", s.field, s.field);
            }
            _ => {
                let _ = writeln!(o, "        msg.set_{}({})?;", s.field, s.field);
            }
        }
    }
    let _ = writeln!(o, "        Ok(msg)\n    }}\n");

    if fam {
        let _ = writeln!(o, "    /// Instance index (e.g. the finger).");
        let _ = writeln!(
            o,
            "    pub fn instance(&self) -> usize {{ usize::from(self.instance) }}\n"
        );
        let _ = writeln!(o, "    /// CAN id of this instance.");
        let _ = writeln!(
            o,
            "    pub fn id(&self) -> u32 {{ Self::IDS[usize::from(self.instance)] }}\n"
        );
        let _ = writeln!(o, "    /// DBC name of this instance.");
        let _ = writeln!(o, "    pub fn name(&self) -> &'static str {{ Self::NAMES[usize::from(self.instance)] }}\n");
        let _ = writeln!(o, "    /// The instance a CAN id belongs to, if any.");
        let _ = writeln!(o, "    pub fn instance_of(id: u32) -> Option<usize> {{ Self::IDS.iter().position(|&i| i == id) }}\n");
        if m.e2e.is_some() {
            let _ = writeln!(o, "    /// E2E profile of this instance.");
            let _ = writeln!(
                o,
                "    pub fn e2e(&self) -> E2eProfile {{ Self::E2E[usize::from(self.instance)] }}\n"
            );
        }
    } else {
        let _ = writeln!(o, "    /// CAN id.");
        let _ = writeln!(o, "    pub fn id(&self) -> u32 {{ Self::ID }}\n");
        let _ = writeln!(o, "    /// DBC name.");
        let _ = writeln!(
            o,
            "    pub fn name(&self) -> &'static str {{ Self::NAME }}\n"
        );
        if m.e2e.is_some() {
            let _ = writeln!(o, "    /// E2E profile.");
            let _ = writeln!(o, "    pub fn e2e(&self) -> E2eProfile {{ Self::E2E }}\n");
        }
    }

    // Accessors.
    for s in &m.sigs {
        let f = &s.field;
        let mut sd = format!("`{}`", s.name);
        if !s.unit.is_empty() {
            let _ = write!(sd, " ({})", s.unit);
        }
        if let Some(c) = &s.comment {
            let _ = write!(sd, ": {c}");
        }
        let range = match s.kind {
            Kind::Scaled => format!("[{}, {}] {}", s.min, s.max, s.unit),
            _ => format!("[{}, {}]", s.raw_min, s.raw_max),
        };
        match &s.kind {
            Kind::Enum(e) => {
                o.push_str(&indent(&doc(&sd), 1));
                let _ = writeln!(o, "    pub fn {f}(&self) -> {e} {{ self.{f} }}\n");
                let _ = writeln!(
                    o,
                    "    /// Sets `{}` (every enum value is in range).",
                    s.name
                );
                let _ = writeln!(
                    o,
                    "    pub fn set_{f}(&mut self, value: {e}) {{ self.{f} = value; }}\n"
                );
            }
            Kind::Int => {
                o.push_str(&indent(&doc(&sd), 1));
                let _ = writeln!(o, "    pub fn {f}(&self) -> {} {{ self.{f} }}\n", s.raw_ty);
                let _ = writeln!(
                    o,
                    "    /// Sets `{}`; refuses values outside {range}.",
                    s.name
                );
                let _ = writeln!(
                    o,
                    "    pub fn set_{f}(&mut self, value: {}) -> Result<(), CodecError> {{",
                    s.raw_ty
                );
                o.push_str(&indent(&raw_check(s, "value", &name_expr), 2));
                let _ = writeln!(o, "        self.{f} = value;\n        Ok(())\n    }}\n");
            }
            Kind::Scaled => {
                o.push_str(&indent(&doc(&sd), 1));
                let phys = format!(
                    "{} * {}{}",
                    raw_to_f64(s, &format!("self.{f}")),
                    flit(s.factor),
                    if s.offset != 0.0 {
                        format!(" + {}", flit(s.offset))
                    } else {
                        String::new()
                    }
                );
                let _ = writeln!(o, "    pub fn {f}(&self) -> f64 {{ {phys} }}\n");
                let _ = writeln!(o, "    /// `{}` as the raw integer on the bus.", s.name);
                let _ = writeln!(
                    o,
                    "    pub fn {f}_raw(&self) -> {} {{ self.{f} }}\n",
                    s.raw_ty
                );
                let _ = writeln!(
                    o,
                    "    /// Sets `{}` from a physical value, rounded to the nearest raw step; \
                     refuses non-finite values and values outside {range} (never wraps or \
                     saturates).",
                    s.name
                );
                let _ = writeln!(
                    o,
                    "    pub fn set_{f}(&mut self, value: f64) -> Result<(), CodecError> {{"
                );
                let _ = writeln!(
                    o,
                    "        let tol = {};\n        if !value.is_finite() || value < Self::{up}_MIN - tol || value > Self::{up}_MAX + tol {{",
                    flit(s.factor * 1e-6),
                    up = s.upper()
                );
                let _ = writeln!(
                    o,
                    "            return Err(CodecError::OutOfRange {{ message: {name_expr}, signal: {:?}, value, min: Self::{up}_MIN, max: Self::{up}_MAX, unit: {:?} }});\n        }}",
                    s.name,
                    s.unit,
                    up = s.upper()
                );
                let _ = writeln!(
                    o,
                    "        let raw = ((value - {}) / {}).round() as i64;",
                    flit(s.offset),
                    flit(s.factor)
                );
                let _ = writeln!(
                    o,
                    "        if !({}..={}).contains(&raw) {{ return Err(CodecError::OutOfRange {{ message: {name_expr}, signal: {:?}, value, min: Self::{up}_MIN, max: Self::{up}_MAX, unit: {:?} }}); }}",
                    s.raw_min,
                    s.raw_max,
                    s.name,
                    s.unit,
                    up = s.upper()
                );
                let _ = writeln!(
                    o,
                    "        self.{f} = raw as {};\n        Ok(())\n    }}\n",
                    s.raw_ty
                );
                let _ = writeln!(
                    o,
                    "    /// Sets `{}` from a raw value; refuses raw values outside [{}, {}].",
                    s.name, s.raw_min, s.raw_max
                );
                let _ = writeln!(
                    o,
                    "    pub fn set_{f}_raw(&mut self, raw: {}) -> Result<(), CodecError> {{",
                    s.raw_ty
                );
                o.push_str(&indent(&raw_check(s, "raw", &name_expr), 2));
                let _ = writeln!(o, "        self.{f} = raw;\n        Ok(())\n    }}\n");
            }
        }
    }

    // Decode.
    let _ = writeln!(o, "    /// Decodes a payload; refuses a wrong length, raw values outside the DBC range and values the value tables do not name. The CRC is not checked here: that is [`crate::e2e::E2eChecker`]'s job.");
    if fam {
        let _ = writeln!(
            o,
            "    pub fn decode(id: u32, data: &[u8]) -> Result<Self, CodecError> {{"
        );
        let _ = writeln!(o, "        let Some(instance) = Self::instance_of(id) else {{ return Err(CodecError::WrongId {{ message: Self::NAME, id }}); }};");
        let _ = writeln!(o, "        let message = Self::NAMES[instance];");
    } else {
        let _ = writeln!(
            o,
            "    pub fn decode(data: &[u8]) -> Result<Self, CodecError> {{"
        );
        let _ = writeln!(o, "        let message = Self::NAME;");
    }
    let _ = writeln!(o, "        if data.len() != Self::DLC {{ return Err(CodecError::WrongLength {{ message, expected: Self::DLC, got: data.len() }}); }}");
    let _ = writeln!(o, "        let mut bytes = [0u8; 8];\n        bytes[..Self::DLC].copy_from_slice(data);\n        let bits = u64::from_le_bytes(bytes);");
    for s in &m.sigs {
        let f = &s.field;
        let _ = writeln!(o, "        let {f} = {};", extract(s));
        match &s.kind {
            Kind::Enum(e) => {
                let _ = writeln!(o, "        let Some({f}) = {e}::from_raw(i64::from({f})) else {{ return Err(CodecError::UnknownValue {{ message, signal: {:?}, raw: i64::from({f}) }}); }};", s.name);
            }
            // Bits that cover exactly the allowed range need no check after extraction.
            _ if s.raw_min == s.bit_min() && s.raw_max == s.bit_max() => {}
            _ => o.push_str(&indent(&raw_check(s, f, "message"), 2)),
        }
    }
    let _ = write!(o, "        Ok(Self {{ ");
    if fam {
        let _ = write!(o, "instance: instance as u8, ");
    }
    for s in &m.sigs {
        let _ = write!(o, "{}, ", s.field);
    }
    let _ = writeln!(o, "}})\n    }}\n");

    // Encode.
    let _ = writeln!(
        o,
        "    /// The payload bytes (values were range-checked when set, so this cannot fail)."
    );
    let _ = writeln!(o, "    pub fn encode(&self) -> [u8; {}] {{", m.dlc);
    let _ = writeln!(o, "        let mut bits = 0u64;");
    for s in &m.sigs {
        let raw = match &s.kind {
            Kind::Enum(_) => format!("self.{}.raw()", s.field),
            _ => format!("self.{}", s.field),
        };
        let _ = writeln!(o, "        {}", insert(s, &raw));
    }
    if m.dlc == 8 {
        let _ = writeln!(o, "        bits.to_le_bytes()\n    }}\n");
    } else {
        let _ = writeln!(o, "        let mut out = [0u8; {}];\n        out.copy_from_slice(&bits.to_le_bytes()[..{}]);\n        out\n    }}\n", m.dlc, m.dlc);
    }

    // Frames.
    let _ = writeln!(o, "    /// The message as a [`CanFrame`].");
    let _ = writeln!(o, "    pub fn to_frame(&self) -> CanFrame {{ CanFrame::from_dbc(self.id(), &self.encode()) }}\n");
    let _ = writeln!(
        o,
        "    /// The message as any [`embedded_can::Frame`] (e.g. a SocketCAN frame)."
    );
    let _ = writeln!(o, "    pub fn to_can_frame<F: embedded_can::Frame>(&self) -> Result<F, CodecError> {{ to_can_frame(self.id(), &self.encode()) }}\n");
    let _ = writeln!(o, "    /// Decodes any [`embedded_can::Frame`]; refuses remote frames, extended ids and other messages' ids.");
    let _ = writeln!(o, "    pub fn try_from_frame<F: embedded_can::Frame>(frame: &F) -> Result<Self, CodecError> {{");
    let _ = writeln!(o, "        let id = standard_data_frame(frame)?;");
    if fam {
        let _ = writeln!(o, "        Self::decode(id, frame.data())");
    } else {
        let _ = writeln!(o, "        if id != Self::ID {{ return Err(CodecError::WrongId {{ message: Self::NAME, id }}); }}");
        let _ = writeln!(o, "        Self::decode(frame.data())");
    }
    let _ = writeln!(o, "    }}\n");

    // Name-based access (tools, cross-checks).
    let _ = writeln!(o, "    /// Calls `f` with each signal's DBC name and physical value (enums as their raw value).");
    let _ = writeln!(
        o,
        "    pub fn for_each_signal(&self, f: &mut dyn FnMut(&'static str, f64)) {{"
    );
    for s in &m.sigs {
        let v = match &s.kind {
            Kind::Enum(_) => format!("f64::from(self.{}.raw())", s.field),
            Kind::Int => raw_to_f64(s, &format!("self.{}", s.field)),
            Kind::Scaled => format!("self.{}()", s.field),
        };
        let _ = writeln!(o, "        f({:?}, {v});", s.name);
    }
    let _ = writeln!(o, "    }}\n");
    let _ = writeln!(o, "    /// Builds the message from physical values looked up by DBC signal name (enums by raw value), each checked; E2E signals included.");
    if fam {
        let _ = writeln!(o, "    pub fn from_signals(instance: usize, get: &mut dyn FnMut(&str) -> Option<f64>) -> Result<Self, CodecError> {{");
        let _ = writeln!(o, "        if instance >= {n} {{ return Err(CodecError::InstanceOutOfRange {{ message: Self::NAME, instance, count: {n} }}); }}");
        let _ = writeln!(o, "        let message = Self::NAMES[instance];");
    } else {
        let _ = writeln!(o, "    pub fn from_signals(get: &mut dyn FnMut(&str) -> Option<f64>) -> Result<Self, CodecError> {{");
        let _ = writeln!(o, "        let message = Self::NAME;");
    }
    let _ = writeln!(o, "        let mut msg = Self {{");
    if fam {
        let _ = writeln!(o, "            instance: instance as u8,");
    }
    for s in &m.sigs {
        let init = match &s.kind {
            Kind::Enum(e) => format!("{e}::ALL[0]"),
            _ => {
                let z = if s.raw_min <= 0 && 0 <= s.raw_max {
                    0
                } else {
                    s.raw_min
                };
                z.to_string()
            }
        };
        let _ = writeln!(o, "            {}: {init},", s.field);
    }
    let _ = writeln!(o, "        }};");
    for s in &m.sigs {
        let f = &s.field;
        let _ = writeln!(o, "        let v = get({:?}).ok_or(CodecError::MissingSignal {{ message, signal: {:?} }})?;", s.name, s.name);
        match &s.kind {
            Kind::Enum(e) => {
                let _ = writeln!(o, "        let raw = whole(message, {:?}, v)?;", s.name);
                let _ = writeln!(o, "        msg.{f} = {e}::from_raw(raw).ok_or(CodecError::UnknownValue {{ message, signal: {:?}, raw }})?;", s.name);
            }
            Kind::Int => {
                let _ = writeln!(o, "        let raw = whole(message, {:?}, v)?;", s.name);
                let _ = writeln!(o, "        let raw = {}::try_from(raw).map_err(|_| CodecError::RawOutOfRange {{ message, signal: {:?}, raw, min: {}, max: {} }})?;", s.raw_ty, s.name, s.raw_min, s.raw_max);
                let _ = writeln!(o, "        msg.set_{f}(raw)?;");
            }
            Kind::Scaled => {
                let _ = writeln!(o, "        msg.set_{f}(v)?;");
            }
        }
    }
    let _ = writeln!(o, "        Ok(msg)\n    }}");
    let _ = writeln!(o, "}}\n");

    if m.e2e.is_some() {
        let _ = writeln!(o, "impl crate::e2e::Protected for {ty} {{");
        let _ = writeln!(
            o,
            "    fn e2e_profile(&self) -> E2eProfile {{ self.e2e() }}"
        );
        let _ = writeln!(
            o,
            "    fn to_frame(&self) -> CanFrame {{ {ty}::to_frame(self) }}"
        );
        let _ = writeln!(o, "}}\n");
    }
    Ok(())
}

fn indent(text: &str, levels: usize) -> String {
    let pad = "    ".repeat(levels);
    text.lines()
        .map(|l| {
            if l.is_empty() {
                "\n".to_string()
            } else {
                format!("{pad}{l}\n")
            }
        })
        .collect()
}

/// Match pattern for a group's ids: a range when they are consecutive.
fn id_pattern(g: &Group) -> String {
    let ids: Vec<u32> = g.msgs.iter().map(|m| m.id).collect();
    let consecutive = ids.windows(2).all(|w| w[1] == w[0] + 1);
    if ids.len() > 2 && consecutive {
        format!("{:#05x}..={:#05x}", ids[0], ids[ids.len() - 1])
    } else {
        ids.iter()
            .map(|i| format!("{i:#05x}"))
            .collect::<Vec<_>>()
            .join(" | ")
    }
}

fn gen_dispatch(o: &mut String, groups: &[Group]) {
    let _ = writeln!(o, "/// Any message of hand.dbc, as decoded by [`decode`].");
    let _ = writeln!(o, "#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]");
    let _ = writeln!(o, "pub enum Message {{");
    for g in groups {
        let _ = writeln!(o, "    /// {}", g.name);
        let _ = writeln!(o, "    {}({}),", g.ty, g.ty);
    }
    let _ = writeln!(o, "}}\n");

    let _ = writeln!(o, "/// Decodes a payload by CAN id into the matching message; refuses unknown ids, wrong lengths, out-of-range raw values and unnamed enum values. Never panics.");
    let _ = writeln!(
        o,
        "pub fn decode(id: u32, data: &[u8]) -> Result<Message, CodecError> {{"
    );
    let _ = writeln!(o, "    match id {{");
    for g in groups {
        let ids = id_pattern(g);
        if g.family() {
            let _ = writeln!(
                o,
                "        {ids} => {}::decode(id, data).map(Message::{}),",
                g.ty, g.ty
            );
        } else {
            let _ = writeln!(
                o,
                "        {ids} => {}::decode(data).map(Message::{}),",
                g.ty, g.ty
            );
        }
    }
    let _ = writeln!(
        o,
        "        _ => Err(CodecError::UnknownId {{ id }}),\n    }}\n}}\n"
    );

    let _ = writeln!(
        o,
        "/// Decodes any [`embedded_can::Frame`]; refuses remote frames and extended ids."
    );
    let _ = writeln!(
        o,
        "pub fn decode_frame<F: embedded_can::Frame>(frame: &F) -> Result<Message, CodecError> {{"
    );
    let _ = writeln!(
        o,
        "    let id = standard_data_frame(frame)?;\n    decode(id, frame.data())\n}}\n"
    );

    let _ = writeln!(o, "/// Builds a message from physical values looked up by DBC signal name (see each type's `from_signals`).");
    let _ = writeln!(o, "pub fn from_signals(id: u32, get: &mut dyn FnMut(&str) -> Option<f64>) -> Result<Message, CodecError> {{");
    let _ = writeln!(o, "    match id {{");
    for g in groups {
        let ids = id_pattern(g);
        if g.family() {
            let _ = writeln!(o, "        {ids} => {}::from_signals({}::instance_of(id).unwrap_or(usize::MAX), get).map(Message::{}),", g.ty, g.ty, g.ty);
        } else {
            let _ = writeln!(
                o,
                "        {ids} => {}::from_signals(get).map(Message::{}),",
                g.ty, g.ty
            );
        }
    }
    let _ = writeln!(
        o,
        "        _ => Err(CodecError::UnknownId {{ id }}),\n    }}\n}}\n"
    );

    let _ = writeln!(o, "impl Message {{");
    for (fname, ret, doc_s, body) in [
        ("id", "u32", "CAN id.", "m.id()"),
        ("name", "&'static str", "DBC message name.", "m.name()"),
        (
            "to_frame",
            "CanFrame",
            "The message as a [`CanFrame`].",
            "m.to_frame()",
        ),
    ] {
        let _ = writeln!(o, "    /// {doc_s}");
        let _ = writeln!(
            o,
            "    pub fn {fname}(&self) -> {ret} {{\n        match self {{"
        );
        for g in groups {
            let _ = writeln!(o, "            Message::{}(m) => {body},", g.ty);
        }
        let _ = writeln!(o, "        }}\n    }}\n");
    }
    let _ = writeln!(
        o,
        "    /// Calls `f` with each signal's DBC name and physical value."
    );
    let _ = writeln!(o, "    pub fn for_each_signal(&self, f: &mut dyn FnMut(&'static str, f64)) {{\n        match self {{");
    for g in groups {
        let _ = writeln!(
            o,
            "            Message::{}(m) => m.for_each_signal(f),",
            g.ty
        );
    }
    let _ = writeln!(o, "        }}\n    }}\n");
    let _ = writeln!(o, "    /// E2E profile, `None` for unprotected messages.");
    let _ = writeln!(
        o,
        "    pub fn e2e(&self) -> Option<E2eProfile> {{\n        match self {{"
    );
    for g in groups {
        if g.first().e2e.is_some() {
            let _ = writeln!(o, "            Message::{}(m) => Some(m.e2e()),", g.ty);
        } else {
            let _ = writeln!(o, "            Message::{}(_) => None,", g.ty);
        }
    }
    let _ = writeln!(o, "        }}\n    }}\n}}\n");
}

fn gen_info(o: &mut String, groups: &[Group]) {
    let _ = writeln!(o, "/// Every message of hand.dbc in file order, with its signals: the DBC as data (bus load, tools, cross-checks).");
    let _ = writeln!(o, "pub const MESSAGES: &[MessageInfo] = &[");
    for g in groups {
        for m in &g.msgs {
            let _ = writeln!(o, "    MessageInfo {{");
            let _ = writeln!(o, "        name: {:?},\n        id: {:#05x},\n        dlc: {},\n        cycle_time_ms: {},", m.name, m.id, m.dlc, m.cycle_ms);
            let _ = writeln!(
                o,
                "        senders: &[{}],",
                m.senders
                    .iter()
                    .map(|s| format!("{s:?}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            );
            let _ = writeln!(
                o,
                "        receivers: &[{}],",
                m.receivers
                    .iter()
                    .map(|s| format!("{s:?}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            );
            match m.e2e {
                Some((id, bits)) => {
                    let _ = writeln!(
                        o,
                        "        e2e: Some(E2eProfile::from_dbc({id:#06x}, {bits}, {})),",
                        m.dlc
                    );
                }
                None => {
                    let _ = writeln!(o, "        e2e: None,");
                }
            }
            let _ = writeln!(
                o,
                "        comment: {:?},",
                m.comment.clone().unwrap_or_default()
            );
            let _ = writeln!(o, "        signals: &[");
            for s in &m.sigs {
                let _ = writeln!(
                    o,
                    "            SignalInfo {{ name: {:?}, start_bit: {}, size: {}, signed: {}, factor: {}, offset: {}, min: {}, max: {}, raw_min: {}, raw_max: {}, unit: {:?}, values: &[{}], comment: {:?} }},",
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
                    s.values.iter().map(|(v, d)| format!("({v}, {d:?})")).collect::<Vec<_>>().join(", "),
                    s.comment.clone().unwrap_or_default()
                );
            }
            let _ = writeln!(o, "        ],\n    }},");
        }
    }
    let _ = writeln!(o, "];");
}
