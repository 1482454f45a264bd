//! Units at the edges of the control law: labels are dimensionless in [-1, 1]; what leaves the
//! daemon is a force in newtons and a joint velocity in radians per second.

/// A finger force, in newtons (positive = flexion).
#[derive(Debug, Clone, Copy, PartialEq, PartialOrd, Default)]
pub struct Newton(pub f64);

/// A joint velocity, in radians per second (positive = flexion).
#[derive(Debug, Clone, Copy, PartialEq, PartialOrd, Default)]
pub struct RadPerSec(pub f64);

/// A joint acceleration, in radians per second squared (positive = flexion).
#[derive(Debug, Clone, Copy, PartialEq, PartialOrd, Default)]
pub struct RadPerSec2(pub f64);

// single source: hand_dbc::hand (N_FINGERS, FINGER_NAMES, finger_index, ADC_MIN, ADC_MAX are
// being added to the codec crate; switch these to re-exports of it at the merge).

/// Largest raw EMG value of the amplifier's signed 12-bit ADC, in bus LSB: where the bus's EMG
/// signals saturate (a recorded session's `full_scale`).
pub const ADC_MAX: i16 = 2047;

/// Number of fingers of the hand: 0 thumb, 1 index, 2 middle, 3 ring, 4 pinky.
pub const N_FINGERS: usize = 5;

/// Finger names in index order, as the CLI and the config file spell them.
pub const FINGER_NAMES: [&str; N_FINGERS] = ["thumb", "index", "middle", "ring", "pinky"];

/// The index of a finger from its name (`"index"`) or its number (`"1"`).
pub fn finger_index(name: &str) -> Option<usize> {
    let lower = name.trim().to_ascii_lowercase();
    FINGER_NAMES
        .iter()
        .position(|n| *n == lower)
        .or_else(|| lower.parse::<usize>().ok().filter(|&i| i < N_FINGERS))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finger_names_and_numbers_resolve() {
        assert_eq!(finger_index("thumb"), Some(0));
        assert_eq!(finger_index(" Index "), Some(1));
        assert_eq!(finger_index("4"), Some(4));
        assert_eq!(finger_index("5"), None);
        assert_eq!(finger_index("toe"), None);
    }
}
