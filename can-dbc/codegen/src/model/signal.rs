//! Signals: bit layout, scaling, range, and value tables (which become enums).

use std::collections::BTreeMap;

use can_dbc::{ByteOrder, Dbc, MultiplexIndicator, NumericValue, ValueType};

use super::{bit_range, Kind, RawType, Signal};
use crate::error::DbcError;
use crate::names::{camel, snake};

/// Value table entries (raw value, name) by enum type name.
pub(super) type Enums = BTreeMap<String, Vec<(i64, String)>>;

/// Reads the signals of each message, collecting the enums their value tables define.
pub(super) struct SignalReader<'a> {
    dbc: &'a Dbc,
    /// `VAL_TABLE_`s by Rust name: a signal whose values equal one is that enum.
    tables: Enums,
    enums: Enums,
}

/// The message and signal names every signal refusal carries.
struct At {
    message: String,
    signal: String,
}

impl<'a> SignalReader<'a> {
    pub(super) fn new(dbc: &'a Dbc) -> Self {
        let mut tables = Enums::new();
        for t in &dbc.value_tables {
            let values = t.descriptions.iter().map(|d| (d.id, d.description.clone()));
            let mut values: Vec<(i64, String)> = values.collect();
            values.sort();
            tables.insert(camel(&t.name), values);
        }
        Self {
            dbc,
            tables,
            enums: Enums::new(),
        }
    }

    pub(super) fn into_enums(self) -> Enums {
        self.enums
    }

    /// A message's signals, checked one by one and against each other (no shared bits).
    pub(super) fn signals(
        &mut self,
        m: &can_dbc::Message,
        dlc: u32,
    ) -> Result<Vec<Signal>, DbcError> {
        let mut occupied = 0u64;
        let mut signals = Vec::new();
        for s in &m.signals {
            let at = At {
                message: m.name.clone(),
                signal: s.name.clone(),
            };
            let (start, size) = layout(&at, s, dlc)?;
            let mask = ((1u64 << size) - 1) << start;
            if occupied & mask != 0 {
                return Err(DbcError::Overlap {
                    message: at.message,
                    signal: at.signal,
                });
            }
            occupied |= mask;
            signals.push(self.signal(at, m, s, start, size)?);
        }
        Ok(signals)
    }

    fn signal(
        &mut self,
        at: At,
        m: &can_dbc::Message,
        s: &can_dbc::Signal,
        start: u32,
        size: u32,
    ) -> Result<Signal, DbcError> {
        let signed = s.value_type == ValueType::Signed;
        let (min, max) = scaling(&at, s)?;
        let (raw_min, raw_max) = raw_range(&at, s, signed, size)?;
        let mut values: Vec<(i64, String)> = self
            .dbc
            .value_descriptions_for_signal(m.id, &s.name)
            .unwrap_or(&[])
            .iter()
            .map(|d| (d.id, d.description.clone()))
            .collect();
        values.sort();
        let kind = self.kind(&at, &camel(&m.name), s, &values, (raw_min, raw_max))?;
        Ok(Signal {
            field: snake(&s.name),
            name: at.signal,
            start,
            size,
            signed,
            factor: s.factor,
            offset: s.offset,
            min,
            max,
            raw_min,
            raw_max,
            raw_ty: RawType::for_bits(signed, size),
            unit: s.unit.clone(),
            comment: self.dbc.signal_comment(m.id, &s.name).map(str::to_string),
            kind,
            values,
        })
    }

    /// Enum (value table: factor 1, offset 0, every value in range), integer or scaled.
    fn kind(
        &mut self,
        at: &At,
        msg_ty: &str,
        s: &can_dbc::Signal,
        values: &[(i64, String)],
        (raw_min, raw_max): (i64, i64),
    ) -> Result<Kind, DbcError> {
        let is_int = s.factor == 1.0 && s.offset == 0.0;
        if values.is_empty() {
            return Ok(if is_int { Kind::Int } else { Kind::Scaled });
        }
        let (message, signal) = (at.message.clone(), at.signal.clone());
        if !is_int {
            return Err(DbcError::ScaledEnum { message, signal });
        }
        if let Some((value, name)) = values.iter().find(|(v, _)| *v < raw_min || *v > raw_max) {
            let (value, name) = (*value, name.clone());
            return Err(DbcError::ValueOutOfRange {
                message,
                signal,
                value,
                name,
            });
        }
        let name = self
            .tables
            .iter()
            .find(|(_, t)| t.as_slice() == values)
            .map(|(n, _)| n.clone())
            .unwrap_or_else(|| format!("{msg_ty}{}", camel(&s.name)));
        if self
            .enums
            .get(&name)
            .is_some_and(|prev| prev.as_slice() != values)
        {
            return Err(DbcError::EnumConflict {
                message,
                signal,
                name,
            });
        }
        self.enums.insert(name.clone(), values.to_vec());
        Ok(Kind::Enum(name))
    }
}

/// Plain (not multiplexed), little-endian, inside the payload: (start, size).
fn layout(at: &At, s: &can_dbc::Signal, dlc: u32) -> Result<(u32, u32), DbcError> {
    let (message, signal) = (at.message.clone(), at.signal.clone());
    if s.multiplexer_indicator != MultiplexIndicator::Plain {
        return Err(DbcError::Multiplexed { message, signal });
    }
    if s.byte_order != ByteOrder::LittleEndian {
        return Err(DbcError::ByteOrder { message, signal });
    }
    let fits = s.size >= 1 && s.size <= 63 && s.start_bit + s.size <= u64::from(dlc) * 8;
    match (u32::try_from(s.start_bit), u32::try_from(s.size)) {
        (Ok(start), Ok(size)) if fits => Ok((start, size)),
        _ => Err(DbcError::Bits {
            message,
            signal,
            start: s.start_bit,
            size: s.size,
            dlc: u64::from(dlc),
        }),
    }
}

/// A positive finite factor, a finite offset and a range with min < max: (min, max).
fn scaling(at: &At, s: &can_dbc::Signal) -> Result<(f64, f64), DbcError> {
    let (message, signal) = (at.message.clone(), at.signal.clone());
    if s.factor <= 0.0 || !s.factor.is_finite() || !s.offset.is_finite() {
        return Err(DbcError::Factor { message, signal });
    }
    let (min, max) = (num(&s.min), num(&s.max));
    if min >= max || min.is_nan() || max.is_nan() {
        return Err(DbcError::NoRange {
            message,
            signal,
            min,
            max,
        });
    }
    Ok((min, max))
}

/// The raw range of `[min|max]`, which the bits must hold.
fn raw_range(
    at: &At,
    s: &can_dbc::Signal,
    signed: bool,
    size: u32,
) -> Result<(i64, i64), DbcError> {
    let (min, max) = (num(&s.min), num(&s.max));
    let (bit_min, bit_max) = bit_range(signed, size);
    let raw_min = ((min - s.offset) / s.factor - 1e-9).ceil();
    let raw_max = ((max - s.offset) / s.factor + 1e-9).floor();
    if raw_min < bit_min as f64 || raw_max > bit_max as f64 {
        return Err(DbcError::RangeTooWide {
            message: at.message.clone(),
            signal: at.signal.clone(),
            min,
            max,
            raw_min,
            raw_max,
            size,
            bit_min,
            bit_max,
        });
    }
    Ok((raw_min as i64, raw_max as i64))
}

fn num(v: &NumericValue) -> f64 {
    match v {
        NumericValue::Uint(u) => *u as f64,
        NumericValue::Int(i) => *i as f64,
        NumericValue::Double(d) => *d,
    }
}
