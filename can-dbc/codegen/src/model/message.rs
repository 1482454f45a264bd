//! Messages: ids, DLC, cycle time, senders and receivers, and the E2E layout.

use std::collections::BTreeMap;

use can_dbc::{AttributeValue, Dbc, MessageId};

use super::signal::{Enums, SignalReader};
use super::{family, Bus, E2e, EnumDef, Kind, Message, Signal};
use crate::error::DbcError;

impl Bus {
    /// Parses and validates a DBC text: the only place a DBC is refused.
    pub fn from_dbc(text: &str) -> Result<Bus, DbcError> {
        let dbc = Dbc::try_from(text).map_err(|e| DbcError::Parse(format!("{e:?}")))?;
        let mut reader = SignalReader::new(&dbc);
        let mut seen_ids = BTreeMap::new();
        let mut messages = Vec::new();
        for m in &dbc.messages {
            messages.push(message(&dbc, m, &mut reader, &mut seen_ids)?);
        }
        e2e_registers_differ(&messages)?;
        let enums = reader.into_enums();
        Ok(Bus {
            enums: enums_of(enums),
            groups: family::group(messages),
        })
    }
}

fn enums_of(enums: Enums) -> Vec<EnumDef> {
    enums
        .into_iter()
        .map(|(name, values)| EnumDef { name, values })
        .collect()
}

/// One message, checked.
fn message(
    dbc: &Dbc,
    m: &can_dbc::Message,
    reader: &mut SignalReader<'_>,
    seen_ids: &mut BTreeMap<u32, String>,
) -> Result<Message, DbcError> {
    let message = m.name.clone();
    let id = standard_id(m)?;
    if let Some(other) = seen_ids.insert(id, m.name.clone()) {
        return Err(DbcError::SharedId { message, other, id });
    }
    let dlc = u32::try_from(m.size)
        .ok()
        .filter(|&d| d <= 8)
        .ok_or(DbcError::Dlc {
            message: message.clone(),
            dlc: m.size,
        })?;
    let cycle_ms = cycle_time(dbc, m)?;
    let data_id = attr_int(dbc.resolved_message_attribute(m.id, "HandE2EDataId")).unwrap_or(0);
    let signals = reader.signals(m, dlc)?;
    let e2e = e2e(m, data_id, &signals)?;
    Ok(Message {
        receivers: receivers(m),
        senders: senders(dbc, m),
        comment: dbc.message_comment(m.id).map(str::to_string),
        name: message,
        id,
        dlc,
        cycle_ms,
        signals,
        e2e,
    })
}

fn standard_id(m: &can_dbc::Message) -> Result<u32, DbcError> {
    let message = m.name.clone();
    let id = match m.id {
        MessageId::Standard(id) => u32::from(id),
        MessageId::Extended(_) => return Err(DbcError::ExtendedId { message }),
    };
    if id > 0x7FF {
        return Err(DbcError::IdTooWide { message, id });
    }
    Ok(id)
}

fn cycle_time(dbc: &Dbc, m: &can_dbc::Message) -> Result<u32, DbcError> {
    let message = m.name.clone();
    let value = attr_int(dbc.resolved_message_attribute(m.id, "GenMsgCycleTime")).ok_or(
        DbcError::NoCycleTime {
            message: message.clone(),
        },
    )?;
    u32::try_from(value).map_err(|_| DbcError::CycleTime { message, value })
}

fn attr_int(v: Option<&AttributeValue>) -> Option<i64> {
    match v? {
        AttributeValue::Uint(u) => i64::try_from(*u).ok(),
        AttributeValue::Int(i) => Some(*i),
        AttributeValue::Double(d) => Some(*d as i64),
        AttributeValue::String(_) => None,
    }
}

/// The `BO_` transmitter, then any `BO_TX_BU_` transmitters.
fn senders(dbc: &Dbc, m: &can_dbc::Message) -> Vec<String> {
    let mut senders: Vec<String> = m.transmitter.iter().cloned().collect();
    let extra = dbc
        .message_transmitters
        .iter()
        .filter(|t| t.message_id == m.id);
    for s in extra.flat_map(|t| &t.transmitter) {
        if !senders.contains(s) {
            senders.push(s.clone());
        }
    }
    senders
}

/// Every signal's receivers, first-seen order, without `Vector__XXX`.
fn receivers(m: &can_dbc::Message) -> Vec<String> {
    let mut receivers: Vec<String> = Vec::new();
    for r in m.signals.iter().flat_map(|s| &s.receivers) {
        if r != "Vector__XXX" && !receivers.contains(r) {
            receivers.push(r.clone());
        }
    }
    receivers
}

/// E2E protection from `HandE2EDataId`: CRC at bits 0..8, a full-range unsigned counter of 4
/// or 8 bits at bit 8.
fn e2e(m: &can_dbc::Message, data_id: i64, signals: &[Signal]) -> Result<Option<E2e>, DbcError> {
    if data_id <= 0 {
        return Ok(None);
    }
    let message = m.name.clone();
    let data_id = u16::try_from(data_id).map_err(|_| DbcError::DataId {
        message: message.clone(),
        value: data_id,
    })?;
    let find = |name: &str| signals.iter().find(|s| s.name == name);
    match (find("Crc"), find("Counter")) {
        (Some(c), Some(k)) if is_crc(c) && is_counter(k) => Ok(Some(E2e {
            data_id,
            counter_bits: k.size,
        })),
        _ => Err(DbcError::E2eLayout { message }),
    }
}

fn is_crc(c: &Signal) -> bool {
    c.start == 0 && c.size == 8 && c.kind == Kind::Int && c.raw_min == 0 && c.raw_max == 255
}

fn is_counter(k: &Signal) -> bool {
    k.start == 8
        && (k.size == 4 || k.size == 8)
        && !k.signed
        && k.kind == Kind::Int
        && k.raw_min == 0
        && k.raw_max == (1 << k.size) - 1
}

/// No two protected messages of one length share the CRC register after the data id.
///
/// The CRC covers the data id and then payload bytes 1..DLC, so the data id matters only
/// through that register: equal registers and equal lengths mean one CRC for every payload,
/// and a frame of one message is E2E-valid under the other's id. The counter width is left
/// out of the rule on purpose: it only says which bits of byte 1 the receiver reads as the
/// counter, the CRC still matches, and any byte-1 value is some counter value, so a 4-bit and
/// an 8-bit message collide just the same. Different lengths never collide (the receiver
/// checks the length before the CRC). Different registers never do either: the register
/// difference passes through the CRC table, a bijection, for every payload byte, so the two
/// CRCs differ for every payload.
fn e2e_registers_differ(messages: &[Message]) -> Result<(), DbcError> {
    let mut seen: BTreeMap<(u32, u8), &Message> = BTreeMap::new();
    for m in messages {
        let Some(e2e) = m.e2e else { continue };
        let register = e2e.register();
        if let Some(first) = seen.insert((m.dlc, register), m) {
            return Err(DbcError::E2eCollision {
                message: first.name.clone(),
                data_id: first.e2e.map_or(0, |e| e.data_id),
                other: m.name.clone(),
                other_data_id: e2e.data_id,
                dlc: m.dlc,
                register,
            });
        }
    }
    Ok(())
}
