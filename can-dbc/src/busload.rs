//! Worst-case bus load of hand.dbc, computed from the generated [`crate::messages::MESSAGES`]
//! (cycle times and DLCs straight from the DBC).
//!
//! Bits per classic CAN frame with an 11-bit id, worst-case bit stuffing included:
//! `47 + 8*DLC + floor((34 + 8*DLC - 1) / 4)` (47 bits of frame overhead: SOF, id, control,
//! CRC, delimiters, ACK, EOF and interframe space; of these, the 34 + 8*DLC bits from SOF to
//! the CRC are subject to stuffing, at worst one stuff bit per 4 bits after the first).

use crate::messages::MESSAGES;
use crate::MessageInfo;

/// Nominal bit rate of the hand bus.
pub const BITRATE_BPS: f64 = 1_000_000.0;
/// The design limit: at most half the bus, so retransmissions and a tool's traffic fit.
pub const MAX_LOAD: f64 = 0.5;

/// Worst-case length in bits of a classic CAN data frame with an 11-bit id.
pub const fn frame_bits_worst_case(dlc: usize) -> u64 {
    let data_bits = 8 * dlc as u64;
    47 + data_bits + (34 + data_bits - 1) / 4
}

/// One message's share of the bus.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BusLoadRow {
    /// DBC name.
    pub name: &'static str,
    /// CAN id.
    pub id: u32,
    /// Payload bytes.
    pub dlc: usize,
    /// Period from `GenMsgCycleTime` (ms).
    pub cycle_time_ms: u32,
    /// Frames per second.
    pub frames_per_s: f64,
    /// Worst-case bits per frame.
    pub bits_per_frame: u64,
    /// Worst-case bits per second.
    pub bits_per_s: f64,
    /// Fraction of [`BITRATE_BPS`].
    pub load: f64,
}

impl BusLoadRow {
    fn of(info: &MessageInfo) -> Self {
        let frames_per_s = info.rate_hz();
        let bits_per_frame = frame_bits_worst_case(info.dlc);
        let bits_per_s = frames_per_s * bits_per_frame as f64;
        Self {
            name: info.name,
            id: info.id,
            dlc: info.dlc,
            cycle_time_ms: info.cycle_time_ms,
            frames_per_s,
            bits_per_frame,
            bits_per_s,
            load: bits_per_s / BITRATE_BPS,
        }
    }
}

/// Per-message rows of hand.dbc in DBC order, and the total load as a fraction of 1 Mbit/s.
pub fn bus_load() -> (Vec<BusLoadRow>, f64) {
    let rows: Vec<BusLoadRow> = MESSAGES.iter().map(BusLoadRow::of).collect();
    let total = rows.iter().map(|r| r.load).sum();
    (rows, total)
}

/// The table printed by `cargo run -p hand-dbc --bin busload`.
pub fn format_table() -> String {
    use std::fmt::Write as _;
    let (rows, total) = bus_load();
    let mut out = String::new();
    let _ = writeln!(
        out,
        "{:<20} {:>5} {:>3} {:>8} {:>8} {:>9} {:>10} {:>7}",
        "message", "id", "dlc", "cycle ms", "frames/s", "bits/frm", "bit/s", "load %"
    );
    for r in &rows {
        let _ = writeln!(
            out,
            "{:<20} {:>5} {:>3} {:>8} {:>8.0} {:>9} {:>10.0} {:>7.2}",
            r.name,
            format!("{:#05x}", r.id),
            r.dlc,
            r.cycle_time_ms,
            r.frames_per_s,
            r.bits_per_frame,
            r.bits_per_s,
            r.load * 100.0
        );
    }
    let bits: f64 = rows.iter().map(|r| r.bits_per_s).sum();
    let _ = writeln!(
        out,
        "{:<20} {:>5} {:>3} {:>8} {:>8.0} {:>9} {:>10.0} {:>7.2}",
        "total",
        "",
        "",
        "",
        rows.iter().map(|r| r.frames_per_s).sum::<f64>(),
        "",
        bits,
        total * 100.0
    );
    let _ = writeln!(
        out,
        "worst-case stuffing, 11-bit ids: bits/frame = 47 + 8*DLC + floor((34 + 8*DLC - 1)/4); \
         limit {:.0}% of {:.0} Mbit/s",
        MAX_LOAD * 100.0,
        BITRATE_BPS / 1e6
    );
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_bits_match_the_textbook_values() {
        // 8 bytes: 47 + 64 + floor(97/4) = 135; 0 bytes: 47 + 0 + floor(33/4) = 55.
        assert_eq!(frame_bits_worst_case(8), 135);
        assert_eq!(frame_bits_worst_case(0), 55);
        assert_eq!(frame_bits_worst_case(3), 85);
    }

    #[test]
    fn hand_bus_stays_at_or_under_half_of_1_mbit() {
        let (rows, total) = bus_load();
        assert_eq!(rows.len(), MESSAGES.len());
        assert!(
            rows.iter().all(|r| r.cycle_time_ms > 0),
            "every message needs a cycle time"
        );
        assert!(
            total <= MAX_LOAD,
            "bus load {:.2}% exceeds 50%",
            total * 100.0
        );
    }

    #[test]
    fn dbc_comment_states_the_computed_sum() {
        let (rows, total) = bus_load();
        let bits: f64 = rows.iter().map(|r| r.bits_per_s).sum();
        let dbc = include_str!("../hand.dbc");
        let sum = format!("total {bits:.0} bit/s = {:.1}%", total * 100.0);
        assert!(
            dbc.contains(&sum),
            "hand.dbc's bus-load comment must say \"{sum}\""
        );
    }

    #[test]
    fn table_lists_every_message() {
        let table = format_table();
        for m in MESSAGES {
            assert!(table.contains(m.name), "{} missing", m.name);
        }
        assert!(table.contains("total"));
    }
}
