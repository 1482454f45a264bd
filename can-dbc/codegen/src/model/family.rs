//! Families: messages `NAME_0..NAME_n` with identical layouts become one type with an
//! instance index.

use std::collections::BTreeMap;

use super::{Group, Message};
use crate::names::camel;

/// Groups messages into generated types, in file order of each group's first message.
pub(super) fn group(messages: Vec<Message>) -> Vec<Group> {
    let mut candidates: BTreeMap<String, Vec<Message>> = BTreeMap::new();
    let mut order: Vec<String> = Vec::new();
    for m in messages {
        let key = family_key(&m.name);
        if !candidates.contains_key(&key) {
            order.push(key.clone());
        }
        candidates.entry(key).or_default().push(m);
    }
    let mut groups = Vec::new();
    for key in order {
        let members = candidates.remove(&key).unwrap_or_default();
        if is_family(&key, &members) {
            groups.push(Group {
                ty: camel(&key),
                name: key,
                messages: members,
            });
        } else {
            groups.extend(members.into_iter().map(single));
        }
    }
    groups
}

/// `NAME` for `NAME_<digits>`, else the whole name.
fn family_key(name: &str) -> String {
    match name.rsplit_once('_') {
        Some((base, n)) if !n.is_empty() && n.chars().all(|c| c.is_ascii_digit()) => {
            base.to_string()
        }
        _ => name.to_string(),
    }
}

/// Two or more members named `KEY_0, KEY_1, ..` in order, all laid out like the first.
fn is_family(key: &str, members: &[Message]) -> bool {
    let first = &members[0];
    let like_first = |m: &Message| {
        m.dlc == first.dlc
            && m.cycle_ms == first.cycle_ms
            && m.e2e.map(|e| e.counter_bits) == first.e2e.map(|e| e.counter_bits)
            && m.signals.len() == first.signals.len()
            && m.signals
                .iter()
                .zip(&first.signals)
                .all(|(a, b)| a.same_layout(b))
    };
    members.len() > 1
        && members
            .iter()
            .enumerate()
            .all(|(i, m)| m.name == format!("{key}_{i}") && like_first(m))
}

fn single(m: Message) -> Group {
    Group {
        ty: camel(&m.name),
        name: m.name.clone(),
        messages: vec![m],
    }
}
