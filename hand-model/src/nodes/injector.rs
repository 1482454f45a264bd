//! The node that puts foreign traffic on the bus: E-stops, bursts of unknown ids, a flood.

use hand_dbc::messages::{EstopReason, EstopRequest, EstopSource, HandEstop};

use super::{Bus, NodeStats};
use crate::dbc::{seal, CanFrame};
use crate::faults::{Fault, FaultPlan};

/// Id of the flood: above every hand.dbc id in priority, so it wins arbitration.
pub const FLOOD_ID: u16 = 0x001;
/// Worst-case bits of an 8-byte classic frame with 11-bit id (hand.dbc's bus-load formula:
/// 47 + 8·DLC + ⌊(34 + 8·DLC − 1)/4⌋ = 135).
pub const FLOOD_FRAME_BITS: u64 = hand_dbc::busload::frame_bits_worst_case(8);
/// Bit rate of the bus.
pub const BUS_BIT_RATE: u64 = hand_dbc::busload::BITRATE_BPS as u64;
/// HAND_ESTOP repetition while asserted, µs (hand.dbc GenMsgCycleTime).
pub const ESTOP_PERIOD_US: u64 = 10_000;

/// Sends the E-stop, unknown-id and flood faults of its plan.
#[derive(Debug, Clone)]
pub struct FaultInjector {
    faults: FaultPlan,
    one_shots: u64,
    estop_counter: u8,
    next_estop_us: u64,
    /// Flood frames owed: bit time accumulated since the flood started, in frames.
    flood_sent: u64,
    flood_start_us: Option<u64>,
    stats: NodeStats,
}

impl FaultInjector {
    /// An injector running `faults` (only E-stop, unknown-id bursts and floods concern it).
    pub fn new(faults: FaultPlan) -> Self {
        Self {
            faults,
            one_shots: 0,
            estop_counter: 0,
            next_estop_us: 0,
            flood_sent: 0,
            flood_start_us: None,
            stats: NodeStats::default(),
        }
    }

    /// Transmit counts.
    pub fn stats(&self) -> NodeStats {
        self.stats
    }

    /// Sends whatever its faults require by `now_us`.
    pub fn poll<B: Bus>(&mut self, now_us: u64, bus: &mut B) {
        while self.stats.receive(bus).is_some() {}
        let mut estop = false;
        let mut flood = false;
        for (i, f) in self.faults.active(now_us) {
            match f {
                Fault::EStop => estop = true,
                Fault::BusFlood => flood = true,
                Fault::UnknownIdBurst { id, count } if self.one_shots & (1 << i) == 0 => {
                    self.one_shots |= 1 << i;
                    for k in 0..count {
                        if let Some(frame) = CanFrame::new_standard(id, &k.to_le_bytes()) {
                            self.stats.transmit(bus, &frame);
                        }
                    }
                }
                _ => {}
            }
        }
        if estop {
            if now_us >= self.next_estop_us {
                self.send_estop(bus);
                self.next_estop_us = now_us + ESTOP_PERIOD_US;
            }
        } else {
            self.next_estop_us = 0;
        }
        if flood {
            let start = *self.flood_start_us.get_or_insert(now_us);
            let due = (now_us - start + 1) * BUS_BIT_RATE / 1_000_000 / FLOOD_FRAME_BITS + 1;
            while self.flood_sent < due {
                let payload = self.flood_sent.to_le_bytes();
                if let Some(frame) = CanFrame::new_standard(FLOOD_ID, &payload) {
                    self.stats.transmit(bus, &frame);
                }
                self.flood_sent += 1;
            }
        } else {
            self.flood_start_us = None;
            self.flood_sent = 0;
        }
    }

    fn send_estop<B: Bus>(&mut self, bus: &mut B) {
        let Ok(msg) = HandEstop::new(
            EstopRequest::Stop,
            EstopSource::Tool,
            EstopReason::Technician,
        ) else {
            self.stats.tx_errors += 1;
            return;
        };
        let mut frame = msg.to_frame();
        seal(&mut frame, HandEstop::E2E, self.estop_counter, false);
        self.estop_counter = (self.estop_counter + 1) & 0x0F;
        self.stats.transmit(bus, &frame);
    }
}
