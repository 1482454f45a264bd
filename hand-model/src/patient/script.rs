//! Scripted intents: a timeline of rests, holds and ramps.

use super::intent::Intent;
use crate::error::SimError;
use crate::finger::N_FINGERS;

/// What the patient does during one segment.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Motion {
    /// Keep `Intent` constant.
    Hold(Intent),
    /// Move linearly from the first intent to the second over the segment.
    Ramp(Intent, Intent),
}

/// One segment of a script, `[start_us, end_us)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Segment {
    /// Start time in µs from the script's start.
    pub start_us: u64,
    /// End time (exclusive) in µs.
    pub end_us: u64,
    /// What happens.
    pub motion: Motion,
}

/// A timeline of contiguous segments. After the last segment the patient rests.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Script {
    segments: Vec<Segment>,
    /// Index of the segment last looked up: scenarios query times in increasing order, so the
    /// lookup is O(1) amortised without allocation.
    cursor: usize,
}

/// Named whole-hand postures for gesture sequences.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Gesture {
    /// All fingers flexed.
    Fist,
    /// All fingers extended.
    Open,
    /// Thumb and index flexed, others relaxed.
    Pinch,
    /// Index extended, the others flexed.
    Point,
    /// Thumb extended, the others flexed.
    ThumbsUp,
}

impl Gesture {
    /// Every gesture, in a fixed order.
    pub const ALL: [Gesture; 5] = [
        Gesture::Fist,
        Gesture::Open,
        Gesture::Pinch,
        Gesture::Point,
        Gesture::ThumbsUp,
    ];

    /// The intent of this gesture at full effort.
    pub fn intent(self) -> Intent {
        match self {
            Gesture::Fist => Intent::all(1.0),
            Gesture::Open => Intent::all(-1.0),
            Gesture::Pinch => Intent([0.8, 0.8, 0.0, 0.0, 0.0]),
            Gesture::Point => Intent([0.7, -0.8, 0.9, 0.9, 0.9]),
            Gesture::ThumbsUp => Intent([-0.9, 0.9, 0.9, 0.9, 0.9]),
        }
    }
}

impl Script {
    /// An empty script (rest forever).
    pub fn new() -> Self {
        Self::default()
    }

    /// Appends a segment of `duration_us` doing `motion`.
    pub fn push(&mut self, duration_us: u64, motion: Motion) -> &mut Self {
        let start = self.duration_us();
        self.segments.push(Segment {
            start_us: start,
            end_us: start + duration_us,
            motion,
        });
        self
    }

    /// Appends a rest of `duration_us`.
    pub fn rest(&mut self, duration_us: u64) -> &mut Self {
        self.push(duration_us, Motion::Hold(Intent::REST))
    }

    /// Appends a hold of `intent` for `duration_us`.
    pub fn hold(&mut self, intent: Intent, duration_us: u64) -> &mut Self {
        self.push(duration_us, Motion::Hold(intent.clamped()))
    }

    /// Appends a ramp from the current end intent to `to` over `duration_us`.
    pub fn ramp_to(&mut self, to: Intent, duration_us: u64) -> &mut Self {
        let from = self.end_intent();
        self.push(duration_us, Motion::Ramp(from, to.clamped()))
    }

    /// The intent at the end of the script.
    pub fn end_intent(&self) -> Intent {
        match self.segments.last().map(|s| s.motion) {
            Some(Motion::Hold(i)) | Some(Motion::Ramp(_, i)) => i,
            None => Intent::REST,
        }
    }

    /// Length of the script in µs.
    pub fn duration_us(&self) -> u64 {
        self.segments.last().map_or(0, |s| s.end_us)
    }

    /// The segments.
    pub fn segments(&self) -> &[Segment] {
        &self.segments
    }

    /// The intent at `t_us` (rest after the end).
    pub fn intent_at(&mut self, t_us: u64) -> Intent {
        if self.segments.is_empty() || t_us >= self.duration_us() {
            return Intent::REST;
        }
        if self.segments[self.cursor.min(self.segments.len() - 1)].start_us > t_us {
            self.cursor = 0;
        }
        while self.segments[self.cursor].end_us <= t_us {
            self.cursor += 1;
        }
        let seg = self.segments[self.cursor];
        match seg.motion {
            Motion::Hold(i) => i,
            Motion::Ramp(a, b) => {
                let len = (seg.end_us - seg.start_us).max(1) as f64;
                a.lerp(&b, (t_us - seg.start_us) as f64 / len)
            }
        }
    }

    /// Rest only, for `duration_us`.
    pub fn resting(duration_us: u64) -> Script {
        let mut s = Script::new();
        s.rest(duration_us);
        s
    }

    /// Rest, then a ramp to `level` on finger `finger` (or all fingers when `None`), a hold,
    /// a ramp back and rest: one contraction. Errors on a bad finger index.
    pub fn contraction(
        finger: Option<usize>,
        level: f64,
        ramp_us: u64,
        hold_us: u64,
        rest_us: u64,
    ) -> Result<Script, SimError> {
        let target = target_intent(finger, level)?;
        let mut s = Script::new();
        s.rest(rest_us)
            .ramp_to(target, ramp_us)
            .hold(target, hold_us)
            .ramp_to(Intent::REST, ramp_us)
            .rest(rest_us);
        Ok(s)
    }

    /// A sequence of gestures, each reached by a ramp, held and released.
    pub fn gestures(gestures: &[Gesture], ramp_us: u64, hold_us: u64, rest_us: u64) -> Script {
        let mut s = Script::new();
        s.rest(rest_us);
        for g in gestures {
            s.ramp_to(g.intent(), ramp_us)
                .hold(g.intent(), hold_us)
                .ramp_to(Intent::REST, ramp_us)
                .rest(rest_us);
        }
        s
    }
}

/// The intent of `level` on `finger` (`None` = all fingers).
pub fn target_intent(finger: Option<usize>, level: f64) -> Result<Intent, SimError> {
    match finger {
        Some(f) if f >= N_FINGERS => Err(SimError::BadFinger(f)),
        Some(f) => Ok(Intent::finger(f, level)),
        None => Ok(Intent::all(level)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ramps_interpolate_and_the_end_is_rest() {
        let mut s = Script::contraction(Some(1), 1.0, 100_000, 200_000, 50_000).expect("valid");
        assert_eq!(s.duration_us(), 500_000);
        assert_eq!(s.intent_at(0), Intent::REST);
        assert!((s.intent_at(100_000).0[1] - 0.5).abs() < 1e-12);
        assert_eq!(s.intent_at(200_000).0[1], 1.0);
        // Looking back in time works too (the cursor rewinds).
        assert!((s.intent_at(100_000).0[1] - 0.5).abs() < 1e-12);
        assert_eq!(s.intent_at(10_000_000), Intent::REST);
        assert!(Script::contraction(Some(5), 1.0, 1, 1, 1).is_err());
    }
}
