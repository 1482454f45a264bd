//! `decode` and `encode`: the bit layout of each signal in a little-endian `u64`.

use super::join;
use super::range::raw_check;
use crate::model::{Group, Kind, Signal};

/// `decode` then `encode`.
pub(super) fn render(g: &Group) -> String {
    decode(g) + &encode(g)
}

/// Checks length, extracts each signal, checks each range and enum value.
fn decode(g: &Group) -> String {
    let head = if g.is_family() {
        "#[inline]
pub fn decode(id: u32, data: &[u8]) -> Result<Self, CodecError> {
let Some(instance) = Self::instance_of(id) else { return Err(CodecError::WrongId { message: Self::NAME, id }); };
let message = Self::NAMES[instance];
"
    } else {
        "#[inline]\npub fn decode(data: &[u8]) -> Result<Self, CodecError> {\nlet message = Self::NAME;\n"
    };
    let signals = &g.first().signals;
    let fields = join(signals, "", |s| format!("{}, ", s.field));
    let instance = if g.is_family() {
        "instance: instance as u8, "
    } else {
        ""
    };
    format!(
        "/// Decodes a payload; refuses a wrong length, raw values outside the DBC range and \
         values the value tables do not name. The CRC is not checked here: that is \
         [`crate::e2e::E2eChecker`]'s job.
{head}if data.len() != Self::DLC {{ return Err(CodecError::WrongLength {{ message, expected: \
         Self::DLC, got: data.len() }}); }}
let mut bytes = [0u8; 8];
bytes[..Self::DLC].copy_from_slice(data);
let bits = u64::from_le_bytes(bytes);
{}Ok(Self {{ {instance}{fields}}})
}}

",
        join(signals, "", decode_signal)
    )
}

/// `let field = ..;` and its check: enum lookup, or the raw range unless the bits cover
/// exactly the allowed range.
fn decode_signal(s: &Signal) -> String {
    let f = &s.field;
    let check = match &s.kind {
        Kind::Enum(e) => format!(
            "let Some({f}) = {e}::from_raw(i64::from({f})) else {{ return \
             Err(CodecError::UnknownValue {{ message, signal: {:?}, raw: i64::from({f}) }}); }};\n",
            s.name
        ),
        _ if s.raw_min == s.bit_min() && s.raw_max == s.bit_max() => String::new(),
        _ => raw_check(s, f, "message"),
    };
    format!("let {f} = {};\n{check}", extract(s))
}

/// Values were range-checked when set, so encoding cannot fail.
fn encode(g: &Group) -> String {
    let m = g.first();
    let dlc = m.dlc;
    let inserts = join(&m.signals, "", |s| match &s.kind {
        Kind::Enum(_) => insert(s, &format!("self.{}.raw()", s.field)),
        _ => insert(s, &format!("self.{}", s.field)),
    });
    let bytes = if dlc == 8 {
        "bits.to_le_bytes()".to_string()
    } else {
        format!(
            "let mut out = [0u8; {dlc}];\nout.copy_from_slice(&bits.to_le_bytes()[..{dlc}]);\nout"
        )
    };
    format!(
        "/// The payload bytes (values were range-checked when set, so this cannot fail).
#[inline]
pub fn encode(&self) -> [u8; {dlc}] {{
let mut bits = 0u64;
{inserts}{bytes}
}}

"
    )
}

/// Expression extracting signal `s` (as its raw type) from the `u64` named `bits`; signed
/// signals are sign-extended by shifting up to bit 63 and arithmetically back down.
fn extract(s: &Signal) -> String {
    let ty = s.raw_ty.name();
    if s.signed {
        let up = 64 - s.start - s.size;
        let down = 64 - s.size;
        if up == 0 {
            format!("((bits as i64) >> {down}) as {ty}")
        } else {
            format!("(((bits << {up}) as i64) >> {down}) as {ty}")
        }
    } else {
        let mask = (1u64 << s.size) - 1;
        if s.start == 0 {
            format!("(bits & {mask:#x}) as {ty}")
        } else {
            format!("((bits >> {}) & {mask:#x}) as {ty}", s.start)
        }
    }
}

/// Statement OR-ing the raw value expression `raw` (of the signal's raw type) into `bits`.
fn insert(s: &Signal, raw: &str) -> String {
    let mask = (1u64 << s.size) - 1;
    let widened = match (s.signed, s.raw_ty.is_64()) {
        (true, true) => format!("({raw} as u64)"),
        (true, false) => format!("(i64::from({raw}) as u64)"),
        (false, true) => raw.to_string(),
        (false, false) => format!("u64::from({raw})"),
    };
    if s.start == 0 {
        format!("bits |= {widened} & {mask:#x};\n")
    } else {
        format!("bits |= ({widened} & {mask:#x}) << {};\n", s.start)
    }
}
