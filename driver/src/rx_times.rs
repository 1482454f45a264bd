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
//! it would map to a time far from the truth, an hour early or late. Receive times never go
//! back, so one mapped before the last time handed out takes that time. One mapped into the
//! future (a backward step) also takes the last time handed out, not now: it was received
//! before now and after that frame, and now is past the deadline of the tick that reads its
//! backlog, so a frame placed at now is held back for the next tick, which holds back the
//! next one again: one frame per tick while the backlog lasts, SAFE for seconds (the VM drill
//! found this). A time within [`STEP_US`] of now is only the jitter of the two clock reads and
//! is clamped to now. Such a frame's time is off by at most the time it waited in the socket, a
//! tick at most; every frame after it is exact again. Slow NTP slewing moves the offset by microseconds per second
//! and is followed without a step being counted.

/// An offset change larger than this is a step of the wall clock, µs.
pub const STEP_US: i128 = 5_000;

/// Maps kernel receive stamps (wall clock) onto the daemon's monotonic clock.
#[derive(Debug, Clone, Copy, Default)]
pub struct RxTimes {
    /// Wall clock minus monotonic clock, µs, as last measured.
    offset_us: Option<i128>,
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
        let offset = match self.offset_us {
            Some(o) if (offset_now - o).abs() > STEP_US => {
                self.steps += 1;
                if (offset_now - o).abs() > self.largest_step_us.abs() {
                    self.largest_step_us = offset_now - o;
                }
                offset_now
            }
            // Slewing (or nothing): follow it without counting.
            Some(_) | None => offset_now,
        };
        self.offset_us = Some(offset);
        let mapped = (stamp_wall_us - offset).clamp(0, i128::from(u64::MAX)) as u64;
        let earliest = self.last_us.min(mono_now_us);
        let t = if u128::from(mapped) > u128::from(mono_now_us) + STEP_US as u128 {
            // Stamped before a backward step: at the last frame's time, inside this tick.
            earliest
        } else {
            mapped.clamp(earliest, mono_now_us)
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
        // at the last frame's time, not an hour in the future, and not at the read time either,
        // which is past the tick's deadline and would hold each back to the next tick.
        let wall = |mono: i128| WALL0 + mono - HOUR;
        for stamped in [1_010_000, 1_015_000, 1_019_000] {
            assert_eq!(r.map(WALL0 + stamped, wall(1_030_000), 1_030_000), 999_000);
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
        // Stamped before the step: an hour in the past on the new offset; clamped to the last
        // time handed out, never before it.
        assert_eq!(
            r.map(WALL0 + 1_010_000, wall(1_030_000), 1_030_000),
            999_000
        );
        assert_eq!(
            r.map(wall(1_040_000), wall(1_040_500), 1_040_500),
            1_040_000
        );
        assert_eq!(r.steps(), 1);
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
