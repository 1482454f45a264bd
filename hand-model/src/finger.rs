//! Finger indices.

/// Number of fingers: 0 thumb, 1 index, 2 middle, 3 ring, 4 pinky.
pub const N_FINGERS: usize = 5;
