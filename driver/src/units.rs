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

/// The hand's single-source constants (from hand.dbc's generated code): the number of fingers
/// and their names (0 thumb .. 4 pinky), and the EMG ADC's upper rail, in bus LSB, where a
/// recorded session's `full_scale` lies.
pub use hand_dbc::hand::{finger_index, ADC_MAX, FINGER_NAMES, N_FINGERS};

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
