//! hand.dbc as data: one [`MessageInfo`] per message with its [`SignalInfo`]s, generated into
//! [`crate::messages::MESSAGES`]. Used for bus load, tools and the cantools cross-check.

use crate::e2e::E2eProfile;

/// One message of hand.dbc.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MessageInfo {
    /// DBC name, e.g. `FINGER_SETPOINT_2`.
    pub name: &'static str,
    /// 11-bit CAN id.
    pub id: u32,
    /// Payload length in bytes.
    pub dlc: usize,
    /// `GenMsgCycleTime` in ms (0 would mean event-only; every message here has a period).
    pub cycle_time_ms: u32,
    /// Nodes that may send it (`BO_` sender plus `BO_TX_BU_`).
    pub senders: &'static [&'static str],
    /// Nodes that receive at least one of its signals.
    pub receivers: &'static [&'static str],
    /// E2E protection, if any.
    pub e2e: Option<E2eProfile>,
    /// The DBC's comment on the message.
    pub comment: &'static str,
    /// Its signals in DBC order.
    pub signals: &'static [SignalInfo],
}

/// One signal of a message (little-endian bit field).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SignalInfo {
    /// DBC name.
    pub name: &'static str,
    /// First bit (Intel numbering).
    pub start_bit: u32,
    /// Width in bits.
    pub size: u32,
    /// Two's complement raw value.
    pub signed: bool,
    /// Physical units per raw step.
    pub factor: f64,
    /// Physical value of raw 0.
    pub offset: f64,
    /// Smallest allowed physical value.
    pub min: f64,
    /// Largest allowed physical value.
    pub max: f64,
    /// Smallest allowed raw value.
    pub raw_min: i64,
    /// Largest allowed raw value.
    pub raw_max: i64,
    /// Unit text.
    pub unit: &'static str,
    /// Value table (raw value, name), empty for plain numbers.
    pub values: &'static [(i64, &'static str)],
    /// The DBC's comment on the signal.
    pub comment: &'static str,
}

impl MessageInfo {
    /// The message with this id, if hand.dbc defines one.
    pub fn by_id(id: u32) -> Option<&'static MessageInfo> {
        crate::messages::MESSAGES.iter().find(|m| m.id == id)
    }

    /// The message with this DBC name.
    pub fn by_name(name: &str) -> Option<&'static MessageInfo> {
        crate::messages::MESSAGES.iter().find(|m| m.name == name)
    }

    /// Frames per second from the cycle time.
    pub fn rate_hz(&self) -> f64 {
        if self.cycle_time_ms == 0 {
            0.0
        } else {
            1000.0 / f64::from(self.cycle_time_ms)
        }
    }
}

impl SignalInfo {
    /// Physical value of a raw value.
    pub fn physical(&self, raw: i64) -> f64 {
        raw as f64 * self.factor + self.offset
    }
}
