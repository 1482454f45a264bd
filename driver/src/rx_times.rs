//! Receive times that do not follow the wall clock.
//!
//! SocketCAN stamps every frame with the kernel's receive time on CLOCK_REALTIME (there is no
//! socket option for a monotonic stamp). The daemon runs on a monotonic clock, so each stamp is
//! mapped by the offset between the two clocks. That offset is not constant: NTP's first sync on
//! a board without a real-time clock steps the wall clock by minutes or years, and so does
//! `date -s`. With an offset measured once, a backward step after start made every window stale
//! (SAFE until a reopen) and a forward step put every frame past the tick's deadline, so the
//! loop read nothing more, E-stop frames included, for as long as the step.
//!
//! [`RxTimes`] re-measures the offset at every read (two clock reads, no system call on vDSO
//! platforms). When it moved by more than [`STEP_US`] the wall clock was stepped: the new offset
//! applies from then on and the step is counted. A frame stamped before the step but read after
//! it would map an hour early or late on the new offset; it was stamped on the old one, which is
//! kept, so it maps exactly on that. Which offset a frame was stamped on is told by where it
//! lands: receive times never go back and no frame is received after it is read, so a time
//! before the last one handed out or after now (beyond [`STEP_US`] of jitter either way) is the
//! wrong offset. Exact times matter: a backlog placed at the last time handed out looked like
//! 50 ms without EMG to the tick that read it (an EMG-silence fault and half a second of safe
//! stops after a -1 h step, the VM drill found), and one placed at the read time, past that
//! tick's deadline, was held back one frame per tick (SAFE for seconds). A frame that fits
//! neither offset (two steps within one backlog) takes the last time handed out. A time within [`STEP_US`] of the range is only the jitter of the two clock reads and
//! is clamped into it. Slow NTP slewing moves the offset by microseconds per second and is
//! followed without a step being counted.

/// An offset change larger than this is a step of the wall clock, µs.
pub const STEP_US: i128 = 5_000;

/// Maps kernel receive stamps (wall clock) onto the daemon's monotonic clock.
#[derive(Debug, Clone, Copy, Default)]
pub struct RxTimes {
    /// Wall clock minus monotonic clock, µs, as last measured.
    offset_us: Option<i128>,
    /// The offset before the last step: frames stamped before it, read after it, map on it.
    before_step_us: Option<i128>,
    /// The last time handed out, µs on the monotonic clock.
    last_us: u64,
    /// Wall-clock steps seen.
    steps: u64,
    /// The largest step seen, µs (signed: negative is backward).
    largest_step_us: i128,
}

impl RxTimes {
    /// The receive time, µs on the monotonic clock, of a frame stamped `stamp_wall_us` (µs on
    /// the wall clock) and read when the clocks read `wall_now_us` and `mono_now_us`.
    pub fn map(&mut self, stamp_wall_us: i128, wall_now_us: i128, mono_now_us: u64) -> u64 {
        let offset_now = wall_now_us - i128::from(mono_now_us);
        if let Some(o) = self.offset_us {
            let step = offset_now - o;
            if step.abs() > STEP_US {
                self.steps += 1;
                if step.abs() > self.largest_step_us.abs() {
                    self.largest_step_us = step;
                }
                self.before_step_us = Some(o);
            }
            // Otherwise slewing (or nothing): followed without counting.
        }
        self.offset_us = Some(offset_now);
        let earliest = self.last_us.min(mono_now_us);
        let fits = |offset: i128| {
            let t = stamp_wall_us - offset;
            let ok = t >= i128::from(earliest) - STEP_US && t <= i128::from(mono_now_us) + STEP_US;
            ok.then_some(t)
        };
        let t = match fits(offset_now).or_else(|| self.before_step_us.and_then(fits)) {
            Some(t) => t.clamp(i128::from(earliest), i128::from(mono_now_us)) as u64,
            // Stamped on neither offset: at the last frame's time, inside the tick that reads
            // it (at now, past that tick's deadline, each such frame would hold the next back).
            None => earliest,
        };
        self.last_us = t;
        t
    }

    /// Forget the last time handed out (a reopened socket starts afresh; the step count stays).
    pub fn reset(&mut self) {
        self.last_us = 0;
    }

    /// Wall-clock steps seen since start.
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// The largest step seen, µs (negative: backward).
    pub fn largest_step_us(&self) -> i128 {
        self.largest_step_us
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const HOUR: i128 = 3_600_000_000;
    const WALL0: i128 = 1_800_000_000_000_000;

    #[test]
    fn without_a_step_a_stamp_maps_exactly() {
        let mut r = RxTimes::default();
        // Read 300 µs after the frame arrived, at monotonic 1 s.
        assert_eq!(
            r.map(WALL0 + 1_000_000 - 300, WALL0 + 1_000_000, 1_000_000),
            999_700
        );
        assert_eq!(
            r.map(WALL0 + 1_050_000, WALL0 + 1_050_100, 1_050_100),
            1_050_000
        );
        assert_eq!(r.steps(), 0);
    }

    #[test]
    fn a_backward_step_neither_stales_nor_reorders_the_frames() {
        let mut r = RxTimes::default();
        assert_eq!(
            r.map(WALL0 + 999_000, WALL0 + 1_000_000, 1_000_000),
            999_000
        );
        // The wall clock goes back an hour at monotonic 1.02 s. Frames stamped before the
        // step, read after it (a tick with deadline 1.025 s reading its backlog at 1.03 s):
        // at their own times, on the offset they were stamped on; not an hour in the future,
        // not at the read time (past the tick's deadline: each would hold the next back) and
        // not at the last frame's time (50 ms without EMG to that tick).
        let wall = |mono: i128| WALL0 + mono - HOUR;
        for stamped in [1_010_000, 1_015_000, 1_019_000] {
            assert_eq!(
                r.map(WALL0 + stamped, wall(1_030_000), 1_030_000),
                stamped as u64
            );
        }
        // Frames stamped after the step map exactly.
        assert_eq!(
            r.map(wall(1_040_000), wall(1_040_500), 1_040_500),
            1_040_000
        );
        assert_eq!(r.steps(), 1);
        assert_eq!(r.largest_step_us(), -HOUR);
    }

    #[test]
    fn a_forward_step_does_not_put_the_frames_past_the_deadline() {
        let mut r = RxTimes::default();
        assert_eq!(
            r.map(WALL0 + 999_000, WALL0 + 1_000_000, 1_000_000),
            999_000
        );
        let wall = |mono: i128| WALL0 + mono + HOUR;
        // Stamped before the step: an hour in the past on the new offset, exact on the old.
        assert_eq!(
            r.map(WALL0 + 1_010_000, wall(1_030_000), 1_030_000),
            1_010_000
        );
        assert_eq!(
            r.map(wall(1_040_000), wall(1_040_500), 1_040_500),
            1_040_000
        );
        assert_eq!(r.steps(), 1);
    }

    #[test]
    fn a_frame_that_fits_neither_offset_takes_the_last_time_handed_out() {
        let mut r = RxTimes::default();
        assert_eq!(
            r.map(WALL0 + 999_000, WALL0 + 1_000_000, 1_000_000),
            999_000
        );
        // Two steps (-1 h, then +3 h) before the backlog is read: the first frame was stamped
        // on the offset before both, which neither kept offset gives.
        let _ = r.map(
            WALL0 - HOUR + 1_005_000,
            WALL0 - HOUR + 1_005_100,
            1_005_100,
        );
        let wall = |mono: i128| WALL0 + mono + 2 * HOUR;
        assert_eq!(
            r.map(WALL0 + 1_001_000, wall(1_030_000), 1_030_000),
            1_005_000
        );
        // In the future on every offset: the same, never the read time.
        assert_eq!(
            r.map(wall(1_030_000) + HOUR, wall(1_031_000), 1_031_000),
            1_005_000
        );
        assert_eq!(r.steps(), 2);
    }

    #[test]
    fn a_stamp_just_past_now_is_jitter_and_clamped_to_now() {
        let mut r = RxTimes::default();
        assert_eq!(
            r.map(WALL0 + 999_000, WALL0 + 1_000_000, 1_000_000),
            999_000
        );
        // The wall clock read a few µs before the monotonic one: a frame stamped just then
        // maps a little past now.
        assert_eq!(
            r.map(WALL0 + 1_010_003, WALL0 + 1_010_000, 1_009_990),
            1_009_990
        );
        assert_eq!(r.steps(), 0);
    }

    #[test]
    fn slewing_is_followed_without_a_step() {
        let mut r = RxTimes::default();
        for k in 0..1_000i128 {
            // 500 ppm of slew, the most adjtime allows: 0.5 µs per ms.
            let mono = 1_000_000 + k * 1_000;
            let wall = WALL0 + mono + k / 2;
            assert_eq!(r.map(wall - 100, wall, mono as u64), (mono - 100) as u64);
        }
        assert_eq!(r.steps(), 0);
    }
}
