//! 2 kSPS to the bus's 1 kHz: the decimating FIR that lets the ADS1299 run at 2 kSPS, where
//! its sinc3 filter is -3 dB at 524 Hz instead of 262 Hz (README, "Data rate").
//!
//! A 63-tap linear-phase low-pass ([`TAPS_Q15`]: scipy's `firwin(63, 475, fs=2000,
//! window=("kaiser", 6.0))` rounded to Q15, the centre tap adjusted so the taps sum to exactly
//! 2^15: unity gain at DC), computed once per output on every second conversion. Integer
//! arithmetic throughout: a 24-bit code times a Q15 tap summed 63 times stays below 2^45 in
//! an `i64`; the sum is rounded half up to a code and clamped to the 24-bit range. Delay: 31
//! conversions, 15.5 ms.

use ads1299::Code;

/// Code zero.
pub(crate) const ZERO: Code = Code::from_be_bytes([0, 0, 0]);

/// Taps of the decimating FIR.
pub const TAPS: usize = 63;

/// The FIR's taps in Q15 (scipy.signal.firwin(63, 475.0, fs=2000.0, window=("kaiser", 6.0)),
/// rounded; the centre tap 15563 -> 15566 so they sum to 32768). Symmetric.
pub const TAPS_Q15: [i32; TAPS] = {
    const HALF: [i32; 32] = [
        4, 6, -9, -16, 14, 32, -18, -58, 18, 96, -9, -146, -14, 209, 59, -284, -135, 369, 254,
        -460, -432, 551, 696, -637, -1103, 712, 1794, -770, -3295, 806, 10367, 15566,
    ];
    let mut t = [0; TAPS];
    let mut i = 0;
    while i < 32 {
        t[i] = HALF[i];
        t[TAPS - 1 - i] = HALF[i];
        i += 1;
    }
    t
};

const _: () = {
    let mut sum = 0;
    let mut i = 0;
    while i < TAPS {
        sum += TAPS_Q15[i];
        i += 1;
    }
    assert!(sum == 1 << 15, "the taps must sum to 2^15 (unity DC gain)");
};

/// Per channel, the last [`TAPS`] conversions; every second conversion gives one output.
#[derive(Debug, Clone)]
pub struct Decimator<const C: usize> {
    /// Ring of conversions per channel; `head` is where the next one goes.
    history: [[i32; TAPS]; C],
    head: usize,
    /// Conversions taken so far modulo 2: an output follows every odd one.
    odd: bool,
}

impl<const C: usize> Default for Decimator<C> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const C: usize> Decimator<C> {
    /// Empty history (zeros), the next conversion the first of a pair.
    pub const fn new() -> Self {
        Self {
            history: [[0; TAPS]; C],
            head: 0,
            odd: false,
        }
    }

    /// Whether the next conversion completes a pair (an output follows it).
    pub fn completes_pair(&self) -> bool {
        self.odd
    }

    /// Takes one conversion per channel; on every second call, the filtered codes at 1 kHz.
    pub fn push(&mut self, codes: &[Code; C]) -> Option<[Code; C]> {
        for (h, c) in self.history.iter_mut().zip(codes) {
            h[self.head] = c.get();
        }
        self.head = (self.head + 1) % TAPS;
        self.odd = !self.odd;
        if self.odd {
            return None;
        }
        let mut out = [ZERO; C];
        for (o, h) in out.iter_mut().zip(&self.history) {
            *o = Self::filter(h, self.head);
        }
        Some(out)
    }

    /// One channel's output: the oldest conversion sits at `head`.
    fn filter(h: &[i32; TAPS], head: usize) -> Code {
        let mut acc: i64 = 0;
        let (newer, older) = h.split_at(head);
        for (x, t) in older.iter().chain(newer).zip(&TAPS_Q15) {
            acc += i64::from(*x) * i64::from(*t);
        }
        let v = (acc + (1 << 14)) >> 15;
        Code::new(v.clamp(
            i64::from(Code::NEGATIVE_FULL_SCALE.get()),
            i64::from(Code::POSITIVE_FULL_SCALE.get()),
        ) as i32)
        .unwrap_or(ZERO)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn code(v: i32) -> Code {
        Code::new(v).expect("a 24-bit code")
    }

    /// Gain of the decimator for a sine at `f` Hz (2 kHz input), from the settled output's
    /// RMS over one second (a whole number of periods of `f` and of its alias).
    fn gain(f: f64) -> f64 {
        let mut d = Decimator::<1>::new();
        let a = 1_000_000.0;
        let mut out = Vec::new();
        for n in 0..4_000 {
            let x = (a * (2.0 * core::f64::consts::PI * f * n as f64 / 2_000.0).sin()).round();
            if let Some([y]) = d.push(&[code(x as i32)]) {
                out.push(f64::from(y.get()));
            }
        }
        let settled = &out[100..1_100];
        let rms = (settled.iter().map(|y| y * y).sum::<f64>() / settled.len() as f64).sqrt();
        rms * core::f64::consts::SQRT_2 / a
    }

    #[test]
    fn a_constant_comes_through_exactly_after_the_filter_fills() {
        let mut d = Decimator::<2>::new();
        let mut outs = Vec::new();
        for _ in 0..200 {
            if let Some(o) = d.push(&[code(1_234_567), code(-8_000_000)]) {
                outs.push(o);
            }
        }
        assert_eq!(outs.len(), 100, "one output per two conversions");
        for o in &outs[32..] {
            assert_eq!(*o, [code(1_234_567), code(-8_000_000)]);
        }
        // Full scale stays in the 24-bit range (clamped, not wrapped).
        let mut d = Decimator::<1>::new();
        let mut last = None;
        for n in 0..200 {
            let c = if n % 2 == 0 {
                Code::POSITIVE_FULL_SCALE
            } else {
                Code::NEGATIVE_FULL_SCALE
            };
            last = d.push(&[c]).or(last);
        }
        assert!(last.is_some());
    }

    #[test]
    fn passes_the_band_and_stops_what_would_alias() {
        // The chain's band is 10-450 Hz; what lies above 550 Hz folds into 450..500 Hz or
        // below at 1 kHz. Figures from scipy.signal.freqz on TAPS_Q15 / 2^15: 0.00 dB at 100
        // and 262 Hz, -1.52 dB at 450 Hz, -66.5 dB at 550 Hz, -74.4 dB at 800 Hz.
        for (f, lo, hi) in [
            (100.0, 0.998, 1.002),
            (262.0, 0.998, 1.002),
            (450.0, 0.835, 0.845),
        ] {
            let g = gain(f);
            assert!(g > lo && g < hi, "gain {g} at {f} Hz");
        }
        for f in [550.0, 600.0, 800.0, 950.0] {
            let g = gain(f);
            assert!(g < 10f64.powf(-60.0 / 20.0), "gain {g} at {f} Hz");
        }
    }
}
