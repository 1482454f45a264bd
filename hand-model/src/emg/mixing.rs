//! The cross-talk matrix: how much of each muscle every electrode picks up.
//!
//! Geometry (a deliberately simple forearm model, documented so tests and readers can reason
//! about it): the 12 electrodes sit equally spaced around the forearm, channel `c` at angular
//! position `c` (in electrode spacings, circular, 12 = 0). Channels 0..5 lie over the volar
//! (flexor) side, 6..11 over the dorsal (extensor) side. The flexor of finger `f` (0 thumb ..
//! 4 pinky) is centred at `f + 0.5`, its extensor at `6 + f + 0.5`, so each muscle sits between
//! two electrodes. The gain from muscle at `p` to channel `c` is `exp(-d² / (2 w²))`, `d` the
//! circular distance and `w` the configured cross-talk width: `w = 1` gives 0.88 on the two
//! nearest channels, 0.32 on the next two and 0.04 on the two after that, so neighbouring
//! fingers overlap (finger coupling) and channels 5 and 11, between the groups, see both a
//! flexor and an extensor.

use crate::finger::N_FINGERS;

/// Number of EMG channels (hand.dbc: EMG_SAMPLES_G0..G2, 4 channels each).
pub use hand_dbc::emg::EMG_CHANNELS as N_CHANNELS;
/// Number of muscle sources: a flexor and an extensor per finger.
pub const N_SOURCES: usize = 2 * N_FINGERS;

/// Index of finger `f`'s flexor among the sources.
pub const fn flexor(f: usize) -> usize {
    f
}

/// Index of finger `f`'s extensor among the sources.
pub const fn extensor(f: usize) -> usize {
    N_FINGERS + f
}

/// Electrode position of source `s`, in electrode spacings around the forearm.
pub fn source_position(s: usize) -> f64 {
    if s < N_FINGERS {
        s as f64 + 0.5
    } else {
        6.0 + (s - N_FINGERS) as f64 + 0.5
    }
}

/// The 12 × 10 gain matrix (row = channel, column = source) for cross-talk width `width`
/// (in electrode spacings, > 0), with the electrode band turned by `shift` spacings around
/// the forearm (0: where it was calibrated; channel `c` then sits at `c + shift`).
pub fn crosstalk_matrix(width: f64, shift: f64) -> [[f64; N_SOURCES]; N_CHANNELS] {
    let mut m = [[0.0; N_SOURCES]; N_CHANNELS];
    for (c, row) in m.iter_mut().enumerate() {
        for (s, g) in row.iter_mut().enumerate() {
            let raw = (c as f64 + shift - source_position(s)).rem_euclid(N_CHANNELS as f64);
            let d = raw.min(N_CHANNELS as f64 - raw);
            *g = (-d * d / (2.0 * width * width)).exp();
        }
    }
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nearest_channels_dominate_and_wrap_around() {
        let m = crosstalk_matrix(1.0, 0.0);
        // Thumb flexor at 0.5: channels 0 and 1 nearest, channel 11 is 1.5 away across the wrap.
        assert!((m[0][flexor(0)] - (-0.125f64).exp()).abs() < 1e-12);
        assert!((m[1][flexor(0)] - m[0][flexor(0)]).abs() < 1e-12);
        assert!((m[11][flexor(0)] - m[2][flexor(0)]).abs() < 1e-12);
        // Pinky extensor at 10.5: the far side of the arm sees almost nothing of it.
        assert!(m[4][extensor(4)] < 1e-6);
        for row in &m {
            assert!(row.iter().all(|g| (0.0..=1.0).contains(g)));
        }
    }

    #[test]
    fn a_shifted_band_sees_each_muscle_from_the_shifted_place() {
        let m = crosstalk_matrix(1.0, 0.0);
        let half = crosstalk_matrix(1.0, 0.5);
        // Shifted by half a spacing, channel 0 sits over the thumb flexor (at 0.5): gain 1.
        assert!((half[0][flexor(0)] - 1.0).abs() < 1e-12);
        assert!(half[0][flexor(0)] > m[0][flexor(0)]);
        // A whole spacing is the next channel's place.
        let one = crosstalk_matrix(1.0, 1.0);
        for s in 0..N_SOURCES {
            assert!((one[0][s] - m[1][s]).abs() < 1e-12);
        }
    }
}
