//! ADS1299 codes in the bus's units.
//!
//! An ADS1299 code is `V_in * gain * 2^23 / VREF` (two's complement, 24 bits; full scale
//! +-VREF / gain), VREF = 4.5 V from the internal reference. hand.dbc's EMG signals are µV at
//! 2.5 µV per LSB, signed 12 bit (EMG_SAMPLES_G0..G2 `Emg0..11`, factor 2.5, -2048..2047),
//! referred to the input whatever the gain. So
//!
//! `bus = round(code * VREF_uV / (gain * 2^23 * 2.5)) = round(code * 1_800_000 / (gain * 2^23))`
//!
//! rounded half away from zero, in i64 (|code * 1_800_000| < 2^44): exact, no float. A
//! result outside the 12-bit range is clamped to the rail, and a code at either saturation
//! code (0x7FFFFF, 0x800000) goes to the rail of its sign; both are flagged, and a value at a
//! rail is what the daemon's front end counts as clipped (`hand::at_rail`).

use ads1299::{Code, Gain};
use hand_dbc_core::emg::EMG_LSB_UV;
use hand_dbc_core::hand::{at_rail, ADC_MAX, ADC_MIN};

/// The ADS1299's internal reference, µV.
pub const VREF_UV: i64 = 4_500_000;

/// The bus LSB in tenths of a µV (2.5 µV).
const LSB_TENTH_UV: i64 = 25;
const _: () = assert!(
    EMG_LSB_UV == 2.5,
    "the node's integer scale assumes 2.5 uV per LSB"
);

/// `VREF_uV / LSB_uV` = 1_800_000: the numerator's factor.
const NUMERATOR: i64 = VREF_UV * 10 / LSB_TENTH_UV;

/// One channel value for the bus.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BusSample {
    /// Raw bus value, LSB 2.5 µV, within `ADC_MIN..=ADC_MAX`.
    pub raw: i16,
    /// At a rail: the ADC saturated, or the input exceeded the bus's +-5.12 mV.
    pub clipped: bool,
}

/// The conversion for one gain.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BusScale {
    denominator: i64,
}

impl BusScale {
    /// The scale at `gain`.
    pub const fn new(gain: Gain) -> Self {
        Self {
            denominator: (gain.factor() as i64) << 23,
        }
    }

    /// A code on the bus (see the module docs).
    #[inline]
    pub fn to_bus(self, code: Code) -> BusSample {
        if code == Code::POSITIVE_FULL_SCALE {
            return BusSample {
                raw: ADC_MAX,
                clipped: true,
            };
        }
        if code == Code::NEGATIVE_FULL_SCALE {
            return BusSample {
                raw: ADC_MIN,
                clipped: true,
            };
        }
        self.fraction_to_bus(i64::from(code.get()), 0)
    }

    /// A value in codes with `frac` fractional bits (`value / 2^frac` codes; |value| below
    /// 2^41, `frac` at most 16: the product stays below 2^63) on the bus, rounded half away
    /// from zero and clamped to the rails (flagged there), as [`BusScale::to_bus`].
    #[inline]
    pub fn fraction_to_bus(self, value: i64, frac: u32) -> BusSample {
        let num = value * NUMERATOR;
        let den = self.denominator << frac;
        let half = den / 2;
        let q = if num >= 0 {
            (num + half) / den
        } else {
            (num - half) / den
        };
        let raw = q.clamp(i64::from(ADC_MIN), i64::from(ADC_MAX)) as i16;
        BusSample {
            raw,
            clipped: at_rail(raw),
        }
    }

    /// µV per code (for documentation and tests): `VREF / (gain * 2^23)`.
    pub fn uv_per_code(self) -> f64 {
        VREF_UV as f64 / self.denominator as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exact_against_float_reference() {
        for gain in [Gain::X1, Gain::X2, Gain::X4, Gain::X8, Gain::X24] {
            let s = BusScale::new(gain);
            for v in (-0x7F_FFFE..0x7F_FFFE).step_by(997) {
                let code = Code::new(v).expect("24 bit");
                let uv = f64::from(v) * 4.5e6 / (f64::from(gain.factor()) * 8_388_608.0);
                let want = (uv / 2.5).round().clamp(-2048.0, 2047.0) as i16;
                let got = s.to_bus(code);
                assert!(
                    got.raw == want,
                    "gain {gain:?} code {v}: {} vs {want}",
                    got.raw
                );
                assert!(got.clipped == (want == -2048 || want == 2047));
            }
        }
    }

    #[test]
    fn rails_and_saturation() {
        let s = BusScale::new(Gain::X8);
        let pos = s.to_bus(Code::POSITIVE_FULL_SCALE);
        let neg = s.to_bus(Code::NEGATIVE_FULL_SCALE);
        assert!(
            pos == BusSample {
                raw: 2047,
                clipped: true
            }
        );
        assert!(
            neg == BusSample {
                raw: -2048,
                clipped: true
            }
        );
        // Half an LSB (1.25 µV) rounds away from zero: at gain 8, 1.25 µV is 18.64 codes.
        assert!(s.to_bus(Code::new(19).expect("24 bit")).raw == 1);
        assert!(s.to_bus(Code::new(-19).expect("24 bit")).raw == -1);
        assert!(s.to_bus(Code::new(18).expect("24 bit")).raw == 0);
        assert!((s.uv_per_code() - 0.067_055_225_372_314_45).abs() < 1e-15);
    }
}
