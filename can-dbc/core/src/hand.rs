//! Single-source constants of the hand, taken from the generated codec so they cannot drift
//! from hand.dbc: the number of fingers, their names and index order, and the EMG ADC rails.
//!
//! Finger index `f` runs 0 thumb, 1 index, 2 middle, 3 ring, 4 pinky: the instance of the
//! `FINGER_SETPOINT_f`/`FINGER_STATUS_f` messages. The paper numbers the fingers the other way,
//! L1..L5 from pinky to thumb, so the paper's L(5-f) is finger `f` (L5 = thumb = 0).

use crate::messages::{EmgSamplesG0, FingerSetpoint};

/// Number of fingers: the instances of the `FINGER_SETPOINT` family in hand.dbc.
pub const N_FINGERS: usize = FingerSetpoint::INSTANCES;

/// Finger names in index order (0 thumb .. 4 pinky), as the CLI and the config file spell them.
pub const FINGER_NAMES: [&str; N_FINGERS] = ["thumb", "index", "middle", "ring", "pinky"];

/// Smallest EMG ADC count (signed 12 bit): the raw minimum of `Emg0` in hand.dbc, -2048
/// (-5120 uV at 2.5 uV/LSB). It is the lower rail: a sample equal to it is clipped.
pub const ADC_MIN: i16 = EmgSamplesG0::EMG0_RAW_MIN;

/// Largest EMG ADC count (signed 12 bit): the raw maximum of `Emg0` in hand.dbc, 2047
/// (5117.5 uV). It is the upper rail: a sample equal to it is clipped.
///
/// So the unclipped samples are `ADC_MIN + 1..ADC_MAX` (`[-2047, 2047)`), and [`at_rail`] is
/// true exactly for `ADC_MIN` and `ADC_MAX`: the EMG front end counts railed samples with it.
pub const ADC_MAX: i16 = EmgSamplesG0::EMG0_RAW_MAX;

/// The index of a finger from its name (`"index"`, any case, surrounding blanks ignored) or its
/// number (`"1"`).
pub fn finger_index(name: &str) -> Option<usize> {
    let name = name.trim();
    FINGER_NAMES
        .iter()
        .position(|n| n.eq_ignore_ascii_case(name))
        .or_else(|| name.parse::<usize>().ok().filter(|&i| i < N_FINGERS))
}

/// Whether a raw EMG sample sits on an ADC rail (equal to [`ADC_MIN`] or [`ADC_MAX`]).
#[inline]
pub fn at_rail(raw: i16) -> bool {
    raw <= ADC_MIN || raw >= ADC_MAX
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::messages::{EmgSamplesG2, FingerStatus};

    #[test]
    fn fingers_match_the_dbc_families() {
        assert_eq!(N_FINGERS, 5);
        assert_eq!(FingerStatus::INSTANCES, N_FINGERS);
        assert_eq!(FingerSetpoint::NAMES[0], "FINGER_SETPOINT_0");
        for (f, name) in FINGER_NAMES.iter().enumerate() {
            assert_eq!(finger_index(name), Some(f));
            assert_eq!(finger_index(&f.to_string()), Some(f));
        }
        assert_eq!(finger_index(" Pinky "), Some(4));
        assert_eq!(finger_index("5"), None);
        assert_eq!(finger_index("palm"), None);
    }

    #[test]
    fn adc_rails_are_the_emg_signals_raw_range() {
        assert_eq!((ADC_MIN, ADC_MAX), (-2048, 2047));
        assert_eq!(
            f64::from(ADC_MIN) * EmgSamplesG0::EMG0_FACTOR,
            EmgSamplesG0::EMG0_MIN
        );
        assert_eq!(
            f64::from(ADC_MAX) * EmgSamplesG0::EMG0_FACTOR,
            EmgSamplesG0::EMG0_MAX
        );
        assert_eq!(EmgSamplesG2::EMG11_RAW_MIN, ADC_MIN);
        assert_eq!(EmgSamplesG2::EMG11_RAW_MAX, ADC_MAX);
        // At a rail exactly when outside the unclipped [-2047, 2047).
        let unclipped = -2047..2047;
        assert!((i16::MIN..=i16::MAX).all(|r| at_rail(r) != unclipped.contains(&r)));
    }
}
