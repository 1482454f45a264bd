//! The bus load over the last second, from the frames the daemon reads and sends, in fixed
//! memory (updated in the tick: no allocation).
//!
//! Each frame counts its worst-case length in bits (hand.dbc's formula, bit stuffing included:
//! [`hand_dbc::busload::frame_bits_worst_case`]), so the figure is an upper bound of the true
//! load, comparable with the design's 50 % limit.

use hand_dbc::busload::{frame_bits_worst_case, BITRATE_BPS};
use hand_dbc::CanFrame;

/// Most ticks in one second (the shortest tick the config allows is 10 ms).
const MAX_TICKS_PER_S: usize = 100;

/// Bits per tick over the last second.
#[derive(Debug, Clone)]
pub struct BusLoad {
    bits: [u64; MAX_TICKS_PER_S],
    /// Ticks in one second (at most [`MAX_TICKS_PER_S`]).
    n: usize,
    /// Next slot to write.
    next: usize,
    /// Ticks closed so far, up to `n`.
    filled: usize,
    /// Bits of the tick in progress.
    current: u64,
    tick_us: u64,
}

impl BusLoad {
    /// For ticks of `tick_us` (at least 10 ms, as the config checks; shorter is clamped).
    pub fn new(tick_us: u64) -> Self {
        let tick_us = tick_us.max(1_000_000 / MAX_TICKS_PER_S as u64);
        Self {
            bits: [0; MAX_TICKS_PER_S],
            n: (1_000_000 / tick_us).clamp(1, MAX_TICKS_PER_S as u64) as usize,
            next: 0,
            filled: 0,
            current: 0,
            tick_us,
        }
    }

    /// One frame read or sent.
    pub fn frame(&mut self, frame: &CanFrame) {
        self.current += frame_bits_worst_case(frame.data().len());
    }

    /// Closes the tick: its bits join the last second's.
    pub fn close_tick(&mut self) {
        self.bits[self.next] = self.current;
        self.current = 0;
        self.next = (self.next + 1) % self.n;
        self.filled = (self.filled + 1).min(self.n);
    }

    /// Fraction of the bit rate used over the closed ticks of the last second (fewer at the
    /// start); 0 before the first tick closes.
    pub fn load(&self) -> f64 {
        if self.filled == 0 {
            return 0.0;
        }
        let bits: u64 = self.bits[..self.n].iter().sum();
        let seconds = (self.filled as u64 * self.tick_us) as f64 * 1e-6;
        bits as f64 / (seconds * BITRATE_BPS)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn load_of_a_steady_stream_is_bits_over_the_bit_rate() {
        let mut b = BusLoad::new(50_000);
        assert_eq!(b.load(), 0.0);
        let f8 = CanFrame::new_standard(0x100, &[0; 8]).expect("frame");
        let f2 = CanFrame::new_standard(0x101, &[0; 2]).expect("frame");
        // 100 eight-byte frames per tick: 135 bits each (hand.dbc), 20 ticks per second.
        for _ in 0..20 {
            for _ in 0..100 {
                b.frame(&f8);
            }
            b.close_tick();
        }
        assert!(
            (b.load() - 100.0 * 135.0 * 20.0 / 1e6).abs() < 1e-12,
            "{}",
            b.load()
        );
        // A second of two-byte frames replaces it (47 + 16 + 49/4 = 75 bits each).
        for _ in 0..20 {
            for _ in 0..10 {
                b.frame(&f2);
            }
            b.close_tick();
        }
        assert!(
            (b.load() - 10.0 * 75.0 * 20.0 / 1e6).abs() < 1e-12,
            "{}",
            b.load()
        );
        // Half a second counts over half a second.
        let mut h = BusLoad::new(50_000);
        for _ in 0..10 {
            h.frame(&f8);
            h.close_tick();
        }
        assert!(
            (h.load() - 135.0 * 20.0 / 1e6).abs() < 1e-12,
            "{}",
            h.load()
        );
    }
}
