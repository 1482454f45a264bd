//! Reassembly of 12-channel sEMG samples from the three EMG_SAMPLES_G0..G2 frames.
//!
//! Each 1 kHz sample travels as three frames (channels 0-3, 4-7, 8-11) that share one 8-bit
//! sample counter. [`EmgAssembler`] puts them back together in counter order, tolerating the
//! small reordering that CAN arbitration can cause (the next sample's G0 has a lower id than
//! this sample's G2 and can overtake it), bridges lost frames and samples by holding each
//! channel's previous value (so the filter bank downstream keeps a steady 1 kHz stream and
//! sees no step to zero), counts what it bridged, and reports a gap longer than the configured
//! limit (20 ms by default) instead of bridging it: the daemon must treat a window with such a
//! gap as invalid. Nothing is allocated per frame.
//!
//! A gap is a break in the *samples*, told by the counter. A silence on the bus whose frames
//! then resume with the counter in sequence is a late stream, not a gap: every sample is
//! there, only delivered late (a sender or a receiver that stalled, a USB adapter delivering
//! in batches). Within [`COUNTER_TRUST_SAMPLES`] periods the 8-bit counter tells the two apart
//! unambiguously (a sender that loses samples in real time cannot lose more than it had time
//! to sample), so such a silence is counted ([`EmgStats::late_resumes`]) and the stream goes
//! on; a longer silence could hide a whole counter wrap and is a gap whatever the counter
//! says. Whether late samples are fresh enough to act on is the consumer's call (the daemon
//! checks the newest sample's age and the silence in progress on its own).

use thiserror::Error;

use crate::messages::{CodecError, EmgSamplesG0, EmgSamplesG1, EmgSamplesG2, Message};

/// Microvolts per raw LSB of every EMG channel (the DBC factor of `Emg0`..`Emg11`).
pub const EMG_LSB_UV: f64 = EmgSamplesG0::EMG0_FACTOR;
/// Channels per sample.
pub const EMG_CHANNELS: usize = 12;
/// Frames (groups) per sample.
pub const EMG_GROUPS: usize = 3;
/// Channels per frame.
pub const CHANNELS_PER_GROUP: usize = 4;

/// How many samples may be in flight (incomplete) at once: reordering by arbitration never
/// spans more than a sample or two, and a deeper window would only delay the stream.
const REORDER_WINDOW: u8 = 4;
/// Frames whose counter lies up to this far behind the next expected sample are late
/// arrivals of samples already emitted (dropped and counted), not a jump forward.
const LATE_WINDOW: u8 = 64;
/// A silence shorter than this many sample periods whose frames resume in counter sequence is
/// a late stream, not a gap: a real-time sender loses at most one sample per period, so a
/// loss in that time moves the counter by less than half its range, far from the
/// [`LATE_WINDOW`] that a wrap would alias into. Longer silences break the stream.
pub const COUNTER_TRUST_SAMPLES: u64 = 128;

/// One decoded EMG frame: the group (0..3), the sample counter and its 4 raw channels.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct EmgFrame {
    group: u8,
    counter: u8,
    raw: [i16; CHANNELS_PER_GROUP],
}

impl EmgFrame {
    /// A frame of group `group` (0, 1 or 2); `None` for another group.
    pub fn new(group: u8, counter: u8, raw: [i16; CHANNELS_PER_GROUP]) -> Option<Self> {
        (usize::from(group) < EMG_GROUPS).then_some(Self {
            group,
            counter,
            raw,
        })
    }

    /// The group: frame `g` carries channels `4g..4g+4`.
    pub fn group(&self) -> u8 {
        self.group
    }

    /// The sample counter.
    pub fn counter(&self) -> u8 {
        self.counter
    }

    /// The four raw channel values (LSB = [`EMG_LSB_UV`]).
    pub fn raw(&self) -> [i16; CHANNELS_PER_GROUP] {
        self.raw
    }

    /// The EMG frame inside a decoded message, `None` for other messages.
    pub fn from_message(message: &Message) -> Option<Self> {
        match message {
            Message::EmgSamplesG0(m) => Some(Self::from(m)),
            Message::EmgSamplesG1(m) => Some(Self::from(m)),
            Message::EmgSamplesG2(m) => Some(Self::from(m)),
            _ => None,
        }
    }

    /// Decodes a payload if `id` is one of the EMG ids: `Ok(None)` for any other id.
    #[inline]
    pub fn decode(id: u32, data: &[u8]) -> Result<Option<Self>, CodecError> {
        Ok(match id {
            EmgSamplesG0::ID => Some(Self::from(&EmgSamplesG0::decode(data)?)),
            EmgSamplesG1::ID => Some(Self::from(&EmgSamplesG1::decode(data)?)),
            EmgSamplesG2::ID => Some(Self::from(&EmgSamplesG2::decode(data)?)),
            _ => None,
        })
    }
}

impl From<&EmgSamplesG0> for EmgFrame {
    #[inline]
    fn from(m: &EmgSamplesG0) -> Self {
        Self {
            group: 0,
            counter: m.counter(),
            raw: [m.emg0_raw(), m.emg1_raw(), m.emg2_raw(), m.emg3_raw()],
        }
    }
}

impl From<&EmgSamplesG1> for EmgFrame {
    #[inline]
    fn from(m: &EmgSamplesG1) -> Self {
        Self {
            group: 1,
            counter: m.counter(),
            raw: [m.emg4_raw(), m.emg5_raw(), m.emg6_raw(), m.emg7_raw()],
        }
    }
}

impl From<&EmgSamplesG2> for EmgFrame {
    #[inline]
    fn from(m: &EmgSamplesG2) -> Self {
        Self {
            group: 2,
            counter: m.counter(),
            raw: [m.emg8_raw(), m.emg9_raw(), m.emg10_raw(), m.emg11_raw()],
        }
    }
}

/// One reassembled 12-channel sample.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct EmgSample {
    /// Position in the emitted stream (0, 1, 2, ...; bridged samples count).
    pub seq: u64,
    /// The sample counter from the bus.
    pub counter: u8,
    /// Raw channel values (LSB = [`EMG_LSB_UV`]).
    pub raw: [i16; EMG_CHANNELS],
    /// Bit `g` set: group `g`'s frame was lost and its channels hold the previous values.
    pub bridged_groups: u8,
    /// The first sample after a gap longer than the limit: windows spanning it are invalid.
    pub after_gap: bool,
    /// Receive time (µs) of the newest frame that contributed to or released this sample.
    pub received_us: u64,
}

impl EmgSample {
    /// Channel `ch` in µV.
    pub fn uv(&self, ch: usize) -> f64 {
        f64::from(self.raw[ch]) * EMG_LSB_UV
    }

    /// All channels in µV.
    pub fn to_uv(&self) -> [f64; EMG_CHANNELS] {
        self.raw.map(|r| f64::from(r) * EMG_LSB_UV)
    }

    /// True if any channel of this sample is a held value rather than a measurement.
    pub fn is_bridged(&self) -> bool {
        self.bridged_groups != 0
    }
}

/// A refused [`EmgConfig`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Error)]
pub enum EmgConfigError {
    /// The sample period must be positive.
    #[error("sample period must be > 0 us")]
    SamplePeriod,
    /// The gap limit must be at least one sample period and below 64 periods (the 8-bit
    /// counter cannot measure longer gaps unambiguously).
    #[error("max gap {max_gap_us} us must be between {min} and {max} us for a {period_us} us sample period")]
    MaxGap {
        /// The refused gap.
        max_gap_us: u64,
        /// The sample period.
        period_us: u64,
        /// Smallest allowed gap.
        min: u64,
        /// Largest allowed gap.
        max: u64,
    },
}

/// Settings of the assembler.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct EmgConfig {
    /// Nominal sample period (1000 µs at 1 kHz).
    pub sample_period_us: u64,
    /// Counter jump (as time: samples lost) beyond which the stream is reported as broken
    /// rather than bridged (20 ms by default); a silence over it breaks the stream too unless
    /// the frames resume in counter sequence within [`COUNTER_TRUST_SAMPLES`] periods.
    pub max_gap_us: u64,
}

/// Default longest silence or counter jump that is bridged, µs: the daemon, sessions read from
/// candump logs and replay all use it.
pub const DEFAULT_MAX_GAP_US: u64 = 20_000;

impl Default for EmgConfig {
    fn default() -> Self {
        Self {
            sample_period_us: 1000,
            max_gap_us: DEFAULT_MAX_GAP_US,
        }
    }
}

/// What the assembler has counted since it was created.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct EmgStats {
    /// Complete samples emitted without bridging.
    pub complete_samples: u64,
    /// Samples emitted with at least one group bridged (held values).
    pub lost_samples: u64,
    /// Group frames that never arrived in time (bridged).
    pub lost_frames: u64,
    /// Frames for a sample already emitted (arrived too late), dropped.
    pub late_frames: u64,
    /// Frames for a group already received for that sample, dropped.
    pub duplicate_frames: u64,
    /// Gaps longer than the limit.
    pub gaps: u64,
    /// Silences longer than the limit after which the counter went on in sequence (a late
    /// stream, every sample there), not counted as gaps.
    pub late_resumes: u64,
}

#[derive(Debug, Clone, Copy, Default)]
struct Slot {
    active: bool,
    counter: u8,
    present: u8,
    raw: [i16; EMG_CHANNELS],
    received_us: u64,
}

/// Reassembles EMG frames into 12-channel samples in counter order (see the module docs).
#[derive(Debug, Clone)]
pub struct EmgAssembler {
    max_gap_us: u64,
    trust_us: u64,
    max_gap_samples: u8,
    slots: [Slot; REORDER_WINDOW as usize],
    next: Option<u8>,
    held: [i16; EMG_CHANNELS],
    last_rx_us: Option<u64>,
    pending_gap: bool,
    seq: u64,
    stats: EmgStats,
}

const ALL_GROUPS: u8 = (1 << EMG_GROUPS) - 1;

impl EmgAssembler {
    /// An assembler; the config is validated here once.
    pub fn try_new(config: EmgConfig) -> Result<Self, EmgConfigError> {
        let period = config.sample_period_us;
        if period == 0 {
            return Err(EmgConfigError::SamplePeriod);
        }
        let max = period * u64::from(LATE_WINDOW - 1);
        if config.max_gap_us < period || config.max_gap_us > max {
            return Err(EmgConfigError::MaxGap {
                max_gap_us: config.max_gap_us,
                period_us: period,
                min: period,
                max,
            });
        }
        Ok(Self {
            max_gap_us: config.max_gap_us,
            trust_us: period.saturating_mul(COUNTER_TRUST_SAMPLES),
            // Bounded by LATE_WINDOW - 1 above, so it fits.
            max_gap_samples: (config.max_gap_us / period) as u8,
            slots: [Slot::default(); REORDER_WINDOW as usize],
            next: None,
            held: [0; EMG_CHANNELS],
            last_rx_us: None,
            pending_gap: false,
            seq: 0,
            stats: EmgStats::default(),
        })
    }

    /// Counters since creation.
    pub fn stats(&self) -> EmgStats {
        self.stats
    }

    /// Receive time of the newest frame accepted, if any.
    pub fn last_received_us(&self) -> Option<u64> {
        self.last_rx_us
    }

    /// Feeds one frame received at `received_us`; every sample it completes or forces out
    /// (bridged) is handed to `sink`, in counter order.
    ///
    /// `received_us` must be the frame's own receive time (e.g. the SocketCAN timestamp or the
    /// candump log time), not the time a batch of frames was read: frames read once per 50 ms
    /// tick and stamped with the read time would look like 50 ms gaps.
    pub fn push(&mut self, frame: &EmgFrame, received_us: u64, sink: &mut impl FnMut(&EmgSample)) {
        if self.silence_breaks(frame.counter, received_us) {
            self.break_stream(sink);
        }
        self.last_rx_us = Some(received_us.max(self.last_rx_us.unwrap_or(0)));
        let next = *self.next.get_or_insert(frame.counter);
        let ahead = frame.counter.wrapping_sub(next);
        if ahead > u8::MAX - LATE_WINDOW {
            self.stats.late_frames += 1;
            return;
        }
        if ahead >= REORDER_WINDOW {
            // Samples between `next` and this frame's sample must go out now.
            let missing_after_window = ahead - (REORDER_WINDOW - 1);
            if ahead > self.max_gap_samples {
                self.break_stream(sink);
                self.next = Some(frame.counter);
            } else {
                for _ in 0..missing_after_window {
                    self.emit_next(received_us, sink);
                }
            }
        }
        let slot = &mut self.slots[usize::from(frame.counter % REORDER_WINDOW)];
        if !slot.active || slot.counter != frame.counter {
            *slot = Slot {
                active: true,
                counter: frame.counter,
                present: 0,
                raw: [0; EMG_CHANNELS],
                received_us,
            };
        }
        let bit = 1u8 << frame.group;
        if slot.present & bit != 0 {
            self.stats.duplicate_frames += 1;
            return;
        }
        slot.present |= bit;
        slot.received_us = slot.received_us.max(received_us);
        let base = usize::from(frame.group) * CHANNELS_PER_GROUP;
        slot.raw[base..base + CHANNELS_PER_GROUP].copy_from_slice(&frame.raw);
        // Release every complete sample at the head, in order.
        while let Some(next) = self.next {
            let head = &self.slots[usize::from(next % REORDER_WINDOW)];
            if head.active && head.counter == next && head.present == ALL_GROUPS {
                self.emit_next(received_us, sink);
            } else {
                break;
            }
        }
    }

    /// Whether the silence before a frame with `counter` received at `received_us` breaks the
    /// stream: over the limit and either too long for the counter to vouch for, or not resumed
    /// in counter sequence. A silence the counter vouches for is counted as a late resume.
    #[inline]
    fn silence_breaks(&mut self, counter: u8, received_us: u64) -> bool {
        let Some(last) = self.last_rx_us else {
            return false;
        };
        let silence = received_us.saturating_sub(last);
        if silence <= self.max_gap_us {
            return false;
        }
        let in_sequence = self
            .next
            .is_some_and(|next| counter.wrapping_sub(next) <= self.max_gap_samples);
        if silence >= self.trust_us || !in_sequence {
            return true;
        }
        self.stats.late_resumes += 1;
        false
    }

    /// Emits every pending sample (bridging what is missing), e.g. at the end of a replay.
    pub fn flush(&mut self, sink: &mut impl FnMut(&EmgSample)) {
        let Some(next) = self.next else { return };
        // Only as far as the newest pending sample: never invent samples past it.
        let mut last_pending = None;
        for k in 0..REORDER_WINDOW {
            let c = next.wrapping_add(k);
            let s = &self.slots[usize::from(c % REORDER_WINDOW)];
            if s.active && s.counter == c {
                last_pending = Some(k);
            }
        }
        if let Some(k) = last_pending {
            let now = self.last_rx_us.unwrap_or(0);
            for _ in 0..=k {
                self.emit_next(now, sink);
            }
        }
    }

    /// A gap too long to bridge: flush what is pending, forget the counter, and mark the next
    /// sample as following a gap.
    fn break_stream(&mut self, sink: &mut impl FnMut(&EmgSample)) {
        self.flush(sink);
        self.next = None;
        for s in &mut self.slots {
            s.active = false;
        }
        self.pending_gap = true;
        self.stats.gaps += 1;
    }

    /// Emits the sample at `next` (bridging missing groups) and advances.
    fn emit_next(&mut self, now_us: u64, sink: &mut impl FnMut(&EmgSample)) {
        let Some(next) = self.next else { return };
        let slot = &mut self.slots[usize::from(next % REORDER_WINDOW)];
        let (present, received_us) = if slot.active && slot.counter == next {
            slot.active = false;
            (slot.present, slot.received_us)
        } else {
            (0, now_us)
        };
        let mut raw = self.held;
        for g in 0..EMG_GROUPS {
            if present & (1 << g) != 0 {
                let range = g * CHANNELS_PER_GROUP..(g + 1) * CHANNELS_PER_GROUP;
                raw[range.clone()].copy_from_slice(&slot.raw[range]);
            }
        }
        let bridged_groups = !present & ALL_GROUPS;
        if bridged_groups == 0 {
            self.stats.complete_samples += 1;
        } else {
            self.stats.lost_samples += 1;
            self.stats.lost_frames += u64::from(bridged_groups.count_ones());
        }
        self.held = raw;
        let sample = EmgSample {
            seq: self.seq,
            counter: next,
            raw,
            bridged_groups,
            after_gap: core::mem::take(&mut self.pending_gap),
            received_us,
        };
        self.seq += 1;
        self.next = Some(next.wrapping_add(1));
        sink(&sample);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frames(counter: u8, base: i16) -> [EmgFrame; 3] {
        [0u8, 1, 2].map(|g| {
            let v = base + i16::from(g) * 4;
            EmgFrame::new(g, counter, [v, v + 1, v + 2, v + 3]).expect("valid group")
        })
    }

    fn run(asm: &mut EmgAssembler, input: &[(EmgFrame, u64)]) -> Vec<EmgSample> {
        let mut out = Vec::new();
        for (f, t) in input {
            asm.push(f, *t, &mut |s| out.push(*s));
        }
        out
    }

    fn assembler() -> EmgAssembler {
        EmgAssembler::try_new(EmgConfig::default()).expect("default config is valid")
    }

    #[test]
    fn lsb_matches_every_channel_of_the_dbc() {
        assert_eq!(EMG_LSB_UV, 2.5);
        for info in crate::messages::MESSAGES
            .iter()
            .filter(|m| m.name.starts_with("EMG_SAMPLES"))
        {
            for s in info.signals.iter().filter(|s| s.name.starts_with("Emg")) {
                assert_eq!(s.factor, EMG_LSB_UV, "{}.{}", info.name, s.name);
            }
        }
    }

    #[test]
    fn in_order_frames_yield_complete_samples_across_the_counter_wrap() {
        let mut asm = assembler();
        let mut input = Vec::new();
        for k in 0..300u16 {
            let c = (k % 256) as u8;
            for f in frames(c, k as i16) {
                input.push((f, u64::from(k) * 1000));
            }
        }
        let out = run(&mut asm, &input);
        assert_eq!(out.len(), 300);
        for (k, s) in out.iter().enumerate() {
            assert_eq!(s.seq, k as u64);
            assert_eq!(s.counter, (k % 256) as u8);
            assert_eq!(s.raw[0], k as i16);
            assert_eq!(s.raw[11], k as i16 + 11);
            assert!(!s.is_bridged() && !s.after_gap);
        }
        assert_eq!(asm.stats().complete_samples, 300);
        assert_eq!(asm.stats().lost_samples, 0);
    }

    #[test]
    fn reordered_groups_are_put_back_in_order() {
        let mut asm = assembler();
        let a = frames(10, 100);
        let b = frames(11, 200);
        // b's G0 overtakes a's G2.
        let out = run(
            &mut asm,
            &[
                (a[0], 0),
                (a[1], 1),
                (b[0], 2),
                (a[2], 3),
                (b[1], 4),
                (b[2], 5),
            ],
        );
        assert_eq!(out.len(), 2);
        assert_eq!((out[0].counter, out[0].raw[8]), (10, 108));
        assert_eq!((out[1].counter, out[1].raw[0]), (11, 200));
        assert_eq!(asm.stats().lost_frames, 0);
    }

    #[test]
    fn lost_frames_and_samples_are_bridged_with_held_values() {
        let mut asm = assembler();
        let mut input = Vec::new();
        for f in frames(0, 100) {
            input.push((f, 0));
        }
        // Sample 1 loses group 1; samples 2 and 3 are lost entirely.
        let s1 = frames(1, 200);
        input.push((s1[0], 1000));
        input.push((s1[2], 1000));
        for c in 4..10u8 {
            for f in frames(c, 100 * i16::from(c)) {
                input.push((f, u64::from(c) * 1000));
            }
        }
        let out = run(&mut asm, &input);
        let counters: Vec<u8> = out.iter().map(|s| s.counter).collect();
        assert_eq!(counters, (0..10).collect::<Vec<u8>>());
        assert_eq!(out[1].bridged_groups, 0b010);
        assert_eq!(out[1].raw[0], 200);
        assert_eq!(out[1].raw[4], 104, "group 1 holds sample 0's value");
        assert_eq!(out[2].bridged_groups, 0b111);
        assert_eq!(out[2].raw, out[1].raw);
        assert_eq!(out[3].raw, out[1].raw);
        let st = asm.stats();
        assert_eq!(st.lost_samples, 3);
        assert_eq!(st.lost_frames, 1 + 3 + 3);
        assert_eq!(st.complete_samples, 7);
        assert_eq!(st.gaps, 0);
    }

    #[test]
    fn silence_with_samples_lost_beyond_the_limit_is_a_gap_not_bridged() {
        let mut asm = assembler();
        let mut input = Vec::new();
        for f in frames(0, 1) {
            input.push((f, 0));
        }
        // 25 ms of silence, the counter continues from 25.
        for f in frames(25, 2) {
            input.push((f, 25_000));
        }
        let out = run(&mut asm, &input);
        assert_eq!(out.len(), 2);
        assert!(out[1].after_gap);
        assert!(!out[1].is_bridged());
        assert_eq!(asm.stats().gaps, 1);
        assert_eq!(asm.stats().lost_samples, 0);
    }

    /// Samples `from..to` (counter mod 256), all three frames of sample `c` received at
    /// `t0 + (c - from) ms`.
    fn stream(from: u32, to: u32, t0: u64) -> Vec<(EmgFrame, u64)> {
        (from..to)
            .flat_map(|c| {
                let t = t0 + u64::from(c - from) * 1000;
                frames(c as u8, c as i16).map(|f| (f, t))
            })
            .collect()
    }

    #[test]
    fn a_silence_then_the_counter_in_sequence_is_a_late_stream_not_a_gap() {
        // A stalled sender: samples 0..10 on time, then 60 ms of nothing, then 10..300 in a
        // burst and on time again (across a counter wrap).
        for silence_ms in [21, 60, COUNTER_TRUST_SAMPLES - 1] {
            let mut asm = assembler();
            let mut input = stream(0, 10, 0);
            input.extend(stream(10, 300, 9_000 + silence_ms * 1000));
            let out = run(&mut asm, &input);
            let counters: Vec<u8> = out.iter().map(|s| s.counter).collect();
            assert_eq!(counters, (0..300u32).map(|c| c as u8).collect::<Vec<_>>());
            assert!(
                out.iter().all(|s| !s.after_gap && !s.is_bridged()),
                "{silence_ms} ms"
            );
            let st = asm.stats();
            assert_eq!((st.gaps, st.late_resumes, st.lost_samples), (0, 1, 0));
        }
    }

    #[test]
    fn a_silence_the_counter_cannot_vouch_for_is_a_gap() {
        // Long enough to hide a counter wrap: a gap whatever the counter says.
        let mut asm = assembler();
        let mut input = stream(0, 10, 0);
        input.extend(stream(10, 20, 9_000 + COUNTER_TRUST_SAMPLES * 1000));
        let out = run(&mut asm, &input);
        let gap: Vec<usize> = (0..out.len()).filter(|&i| out[i].after_gap).collect();
        assert_eq!(gap, [10]);
        assert_eq!((asm.stats().gaps, asm.stats().late_resumes), (1, 0));
        // A silence within trust whose counter jumps past the limit (samples lost): a gap.
        let mut asm = assembler();
        let mut input = stream(0, 10, 0);
        input.extend(stream(40, 50, 39_000));
        let out = run(&mut asm, &input);
        assert!(out[10].after_gap && out[10].counter == 40);
        assert_eq!((asm.stats().gaps, asm.stats().late_resumes), (1, 0));
        // Within trust, a few samples lost in the silence: bridged, as without the silence.
        let mut asm = assembler();
        let mut input = stream(0, 10, 0);
        input.extend(stream(15, 25, 40_000));
        let out = run(&mut asm, &input);
        assert!(out.iter().all(|s| !s.after_gap));
        assert_eq!(out.iter().filter(|s| s.is_bridged()).count(), 5);
        assert_eq!((asm.stats().gaps, asm.stats().late_resumes), (0, 1));
    }

    #[test]
    fn counter_jump_beyond_the_limit_is_a_gap_even_without_silence() {
        let mut asm = assembler();
        let mut input = Vec::new();
        for f in frames(0, 1) {
            input.push((f, 0));
        }
        for f in frames(30, 2) {
            input.push((f, 1000));
        }
        let out = run(&mut asm, &input);
        assert_eq!(out.len(), 2);
        assert!(out[1].after_gap);
        assert_eq!(out[1].counter, 30);
        assert_eq!(asm.stats().gaps, 1);
    }

    #[test]
    fn late_and_duplicate_frames_are_dropped_and_counted() {
        let mut asm = assembler();
        let a = frames(5, 1);
        let out = run(
            &mut asm,
            &[(a[0], 0), (a[0], 0), (a[1], 0), (a[2], 0), (a[1], 10)],
        );
        assert_eq!(out.len(), 1);
        assert_eq!(asm.stats().duplicate_frames, 1);
        assert_eq!(asm.stats().late_frames, 1);
    }

    #[test]
    fn flush_emits_pending_samples_bridged() {
        let mut asm = assembler();
        let a = frames(7, 1);
        let mut out = run(&mut asm, &[(a[0], 0)]);
        assert!(out.is_empty());
        asm.flush(&mut |s| out.push(*s));
        assert_eq!(out.len(), 1);
        assert_eq!(out[0].bridged_groups, 0b110);
    }

    #[test]
    fn decode_path_and_config_validation() {
        let m = EmgSamplesG1::decode(&[0, 9, 0xFF, 0x0F, 0, 0, 0, 0]).expect("valid payload");
        let f = EmgFrame::decode(EmgSamplesG1::ID, &m.encode())
            .expect("valid")
            .expect("an EMG id");
        assert_eq!((f.group(), f.counter()), (1, 9));
        assert_eq!(f.raw()[0], -1);
        assert_eq!(EmgFrame::decode(0x300, &[0; 8]).expect("not EMG"), None);
        assert!(EmgFrame::new(3, 0, [0; 4]).is_none());
        assert!(EmgAssembler::try_new(EmgConfig {
            sample_period_us: 0,
            max_gap_us: 20_000
        })
        .is_err());
        assert!(EmgAssembler::try_new(EmgConfig {
            sample_period_us: 1000,
            max_gap_us: 100_000
        })
        .is_err());
    }
}
