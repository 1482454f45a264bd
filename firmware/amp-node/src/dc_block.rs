//! DC removal on the node, before the bus's 12-bit quantisation.
//!
//! The bus carries +-5.12 mV (2.5 µV per LSB) for the AC sEMG, while the ADS1299 is DC-coupled
//! and sees each electrode pair's differential half-cell offset: tens of mV are common with
//! gel electrodes, far more than the bus's range, so a DC-coupled channel rails. The node
//! therefore takes the DC out of each channel's codes first, with the classic first-order DC
//! blocker
//!
//! `y[n] = x[n] - d[n-1]`, `d[n] = d[n-1] + (x[n] - d[n-1]) / 2^k`
//!
//! (`H(z) = (1 - z^-1) / (1 - (1 - 2^-k) z^-1)`: a zero at DC, a pole at `1 - 2^-k`, the corner
//! near `fs / (2π 2^k)`), in integer arithmetic: the estimate `d` has 16 fractional bits,
//! `y` goes to the bus through [`BusScale::fraction_to_bus`] with them, so nothing is lost to
//! an intermediate rounding. The estimate starts at the first conversion, so a node that
//! starts on an offset does not rail while it settles; a later step of the offset (an
//! electrode pressed or reseated) decays with `2^k` samples.

use ads1299::Code;

use crate::units::{BusSample, BusScale};

/// Fractional bits of the DC estimate.
const FRAC: u32 = 16;

/// The per-channel DC estimates of a node whose bus sample rate is `fs`.
#[derive(Debug, Clone)]
pub struct DcBlock<const C: usize> {
    shift: u32,
    /// `d` per channel, codes with [`FRAC`] fractional bits; `None` before the first sample.
    estimate: Option<[i64; C]>,
}

impl<const C: usize> DcBlock<C> {
    /// A blocker with its pole at `1 - 2^-shift` (`shift` is validated by the node's settings:
    /// [`crate::DcRemoval`]).
    pub const fn new(shift: u8) -> Self {
        Self {
            shift: shift as u32,
            estimate: None,
        }
    }

    /// One bus sample: each channel's code less its DC on the bus (a saturation code goes to
    /// the rail of its sign, flagged, as [`BusScale::to_bus`]); the estimates then take the
    /// sample in.
    #[inline]
    pub fn to_bus(&mut self, codes: &[Code; C], scale: BusScale) -> [BusSample; C] {
        let estimate = self
            .estimate
            .get_or_insert_with(|| core::array::from_fn(|c| i64::from(codes[c].get()) << FRAC));
        core::array::from_fn(|c| {
            let x = i64::from(codes[c].get()) << FRAC;
            let d = &mut estimate[c];
            let out = if codes[c].is_saturated() {
                scale.to_bus(codes[c])
            } else {
                scale.fraction_to_bus(x - *d, FRAC)
            };
            *d += (x - *d) >> self.shift;
            out
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ads1299::Gain;

    fn code(v: f64) -> Code {
        Code::new(v.round() as i32).expect("24 bit")
    }

    /// Against the same filter in f64: within one LSB at every sample, for an offset of
    /// 50 mV with a 100 Hz, 1 mV sine on it and a 30 mV step of the offset at 1 s.
    #[test]
    fn matches_the_float_filter_and_removes_an_offset() {
        let scale = BusScale::new(Gain::X8);
        let per_code = scale.uv_per_code();
        let shift = 6;
        let mut block = DcBlock::<1>::new(shift);
        let a = 1.0 / f64::from(1u32 << shift);
        let mut d: Option<f64> = None;
        let mut worst = 0i32;
        let mut settled_max = 0i16;
        for n in 0..3000 {
            let t = f64::from(n) / 1000.0;
            let offset = if n < 1000 { 50_000.0 } else { 80_000.0 };
            let uv = offset + 1000.0 * (core::f64::consts::TAU * 100.0 * t).sin();
            let c = code(uv / per_code);
            let got = block.to_bus(&[c], scale)[0];
            let x = f64::from(c.get());
            let dd = d.get_or_insert(x);
            let want = ((x - *dd) * per_code / 2.5).round().clamp(-2048.0, 2047.0) as i32;
            *dd += (x - *dd) * a;
            worst = worst.max((i32::from(got.raw) - want).abs());
            if n >= 2500 {
                settled_max = settled_max.max(got.raw.abs());
            }
        }
        assert!(worst <= 1, "{worst} LSB off the float filter");
        // Settled: the sine alone, no offset (the 50 mV would be 20,000 LSB): 400 LSB times
        // the blocker's 1.0074 at 100 Hz, sampled at most at 72° (sin 0.951): 383.
        assert!((380..=390).contains(&settled_max), "{settled_max}");
    }

    #[test]
    fn starts_on_its_first_sample_and_keeps_saturation() {
        let scale = BusScale::new(Gain::X8);
        let mut block = DcBlock::<2>::new(8);
        let offset = code(100_000.0 / scale.uv_per_code());
        let first = block.to_bus(&[offset, Code::POSITIVE_FULL_SCALE], scale);
        assert!(first[0].raw == 0 && !first[0].clipped, "{first:?}");
        assert!(first[1].raw == 2047 && first[1].clipped);
        let next = block.to_bus(&[offset, Code::NEGATIVE_FULL_SCALE], scale);
        assert!(next[0].raw == 0 && next[1].raw == -2048 && next[1].clipped);
    }
}
