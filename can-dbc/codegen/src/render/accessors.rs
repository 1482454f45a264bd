//! Getters and checked setters, one set per signal kind: enums (always in range), integers
//! (raw range checked) and scaled signals (physical and raw, both checked).

use super::range::{raw_check, raw_to_f64};
use super::{doc, flit, self_name};
use crate::model::{Group, Kind, Signal};

/// The accessors of every signal of a message type.
pub(super) fn render(g: &Group) -> String {
    let message = self_name(g);
    let mut out = String::new();
    for s in &g.first().signals {
        out += &doc(&description(s));
        out += &match &s.kind {
            Kind::Enum(e) => enumerated(s, e),
            Kind::Int => integer(s, message),
            Kind::Scaled => scaled_get(s) + &scaled_set(s, message) + &scaled_set_raw(s, message),
        };
    }
    out
}

/// "`Name` (unit): comment".
fn description(s: &Signal) -> String {
    let mut text = format!("`{}`", s.name);
    if !s.unit.is_empty() {
        text += &format!(" ({})", s.unit);
    }
    if let Some(c) = &s.comment {
        text += &format!(": {c}");
    }
    text
}

fn enumerated(s: &Signal, e: &str) -> String {
    let (f, name) = (&s.field, &s.name);
    format!(
        "pub fn {f}(&self) -> {e} {{ self.{f} }}

/// Sets `{name}` (every enum value is in range).
pub fn set_{f}(&mut self, value: {e}) {{ self.{f} = value; }}

"
    )
}

fn integer(s: &Signal, message: &str) -> String {
    let (f, name, ty) = (&s.field, &s.name, s.raw_ty.name());
    format!(
        "pub fn {f}(&self) -> {ty} {{ self.{f} }}

/// Sets `{name}`; refuses values outside [{}, {}].
pub fn set_{f}(&mut self, value: {ty}) -> Result<(), CodecError> {{
{}self.{f} = value;
Ok(())
}}

",
        s.raw_min,
        s.raw_max,
        raw_check(s, "value", message)
    )
}

/// The physical getter and the raw getter.
fn scaled_get(s: &Signal) -> String {
    let (f, name, ty) = (&s.field, &s.name, s.raw_ty.name());
    let offset = if s.offset != 0.0 {
        format!(" + {}", flit(s.offset))
    } else {
        String::new()
    };
    let phys = format!(
        "{} * {}{offset}",
        raw_to_f64(s, &format!("self.{f}")),
        flit(s.factor)
    );
    format!(
        "pub fn {f}(&self) -> f64 {{ {phys} }}

/// `{name}` as the raw integer on the bus.
pub fn {f}_raw(&self) -> {ty} {{ self.{f} }}

"
    )
}

/// The physical setter: rounds to the nearest raw step, refuses non-finite and out-of-range
/// values (with a tolerance of a millionth of a step at the range ends).
fn scaled_set(s: &Signal, message: &str) -> String {
    let (f, name, unit, up) = (&s.field, &s.name, &s.unit, s.upper());
    let refuse = format!(
        "return Err(CodecError::OutOfRange {{ message: {message}, signal: {name:?}, value, \
         min: Self::{up}_MIN, max: Self::{up}_MAX, unit: {unit:?} }});"
    );
    format!(
        "/// Sets `{name}` from a physical value, rounded to the nearest raw step; refuses \
         non-finite values and values outside [{}, {}] {unit} (never wraps or saturates).
pub fn set_{f}(&mut self, value: f64) -> Result<(), CodecError> {{
let tol = {};
if !value.is_finite() || value < Self::{up}_MIN - tol || value > Self::{up}_MAX + tol {{
{refuse}
}}
let raw = round((value - {}) / {}) as i64;
if !({}..={}).contains(&raw) {{ {refuse} }}
self.{f} = raw as {};
Ok(())
}}

",
        s.min,
        s.max,
        flit(s.factor * 1e-6),
        flit(s.offset),
        flit(s.factor),
        s.raw_min,
        s.raw_max,
        s.raw_ty.name()
    )
}

fn scaled_set_raw(s: &Signal, message: &str) -> String {
    let (f, name, ty) = (&s.field, &s.name, s.raw_ty.name());
    format!(
        "/// Sets `{name}` from a raw value; refuses raw values outside [{}, {}].
pub fn set_{f}_raw(&mut self, raw: {ty}) -> Result<(), CodecError> {{
{}self.{f} = raw;
Ok(())
}}

",
        s.raw_min,
        s.raw_max,
        raw_check(s, "raw", message)
    )
}
