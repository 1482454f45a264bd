//! What the monitor measures itself from frames: the bus load over the last second and the
//! tick latency's percentiles over the last HAND_DIAG frames.

use std::collections::VecDeque;

use hand_dbc::busload::{frame_bits_worst_case, BITRATE_BPS};

/// Bits on the bus over a sliding second, hand.dbc's worst-case frame length (stuffing
/// included), as handd's own bus load figure.
#[derive(Debug, Clone, Default)]
pub struct BusLoadMeter {
    /// (receive time µs, bits), oldest first.
    frames: VecDeque<(u64, u64)>,
    bits: u64,
    first_us: Option<u64>,
}

/// The window of the bus load, µs.
const LOAD_WINDOW_US: u64 = 1_000_000;

impl BusLoadMeter {
    /// Counts one frame of `dlc` bytes received at `t_us`.
    pub fn add(&mut self, t_us: u64, dlc: usize) {
        let bits = frame_bits_worst_case(dlc);
        self.first_us.get_or_insert(t_us);
        self.frames.push_back((t_us, bits));
        self.bits += bits;
        self.expire(t_us);
    }

    fn expire(&mut self, now_us: u64) {
        while let Some(&(t, b)) = self.frames.front() {
            if now_us.saturating_sub(t) < LOAD_WINDOW_US {
                break;
            }
            self.frames.pop_front();
            self.bits -= b;
        }
    }

    /// Fraction of the bit rate used over the last second before `now_us`; `None` until a
    /// whole second has been seen.
    pub fn load(&mut self, now_us: u64) -> Option<f64> {
        self.expire(now_us);
        let first = self.first_us?;
        (now_us.saturating_sub(first) >= LOAD_WINDOW_US)
            .then(|| self.bits as f64 / (BITRATE_BPS * LOAD_WINDOW_US as f64 * 1e-6))
    }
}

/// The last ticks' latencies (HAND_DIAG's TickLatency), for p50 and p99.
#[derive(Debug, Clone, Default)]
pub struct LatencyWindow {
    values: VecDeque<u64>,
    scratch: Vec<u64>,
}

/// Ticks the percentiles cover: 10 s at handd's 20 Hz.
const LATENCY_TICKS: usize = 200;

impl LatencyWindow {
    /// Adds one tick's latency, µs.
    pub fn add(&mut self, us: u64) {
        if self.values.len() == LATENCY_TICKS {
            self.values.pop_front();
        }
        self.values.push_back(us);
    }

    /// (p50, p99) by the nearest-rank rule; `None` before the first value.
    pub fn percentiles(&mut self) -> Option<(u64, u64)> {
        if self.values.is_empty() {
            return None;
        }
        self.scratch.clear();
        self.scratch.extend(self.values.iter().copied());
        self.scratch.sort_unstable();
        let rank = |p: f64| {
            let n = self.scratch.len();
            let k = ((p * n as f64).ceil() as usize).clamp(1, n);
            self.scratch[k - 1]
        };
        Some((rank(0.50), rank(0.99)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bus_load_counts_the_last_second_of_worst_case_bits() {
        let mut m = BusLoadMeter::default();
        // 3000 EMG frames a second (135 bits each) for 2 s.
        for k in 0..6000u64 {
            m.add(k * 1_000_000 / 3000, 8);
        }
        let load = m.load(2_000_000).expect("two seconds seen");
        assert!((load - 0.405).abs() < 0.001, "{load}");
        assert_eq!(BusLoadMeter::default().load(5), None);
        assert_eq!(
            m.load(10_000_000),
            Some(0.0),
            "a silent second is an idle bus"
        );
    }

    #[test]
    fn latency_percentiles_by_nearest_rank() {
        let mut w = LatencyWindow::default();
        assert_eq!(w.percentiles(), None);
        for v in 1..=100 {
            w.add(v);
        }
        assert_eq!(w.percentiles(), Some((50, 99)));
        for _ in 0..LATENCY_TICKS {
            w.add(7);
        }
        assert_eq!(w.percentiles(), Some((7, 7)), "only the last ticks count");
    }
}
