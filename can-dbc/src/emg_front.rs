//! The one EMG front end: raw CAN frames with their receive time in, samples in µV out.
//!
//! Every consumer of EMG_SAMPLES frames goes through [`EmgFront`]: the daemon's engine on the
//! live bus, session loading from a candump log, and so replay and the recorder's logs. Per
//! frame, in this order:
//!
//! 1. E2E check (CRC, then the counter step against [`EmgFrontConfig::counter_delta`]) *before*
//!    the payload is decoded: a frame with a wrong CRC or length is counted and dropped, a
//!    repeated one (same counter as the last of its group) is dropped;
//! 2. decode into an [`EmgFrame`];
//! 3. reassembly by counter ([`EmgAssembler`]): reordering tolerated, short losses bridged, a
//!    gap over [`EmgFrontConfig::max_gap_us`] (samples lost, or a silence the counter
//!    cannot vouch for) reported on the next sample;
//! 4. rail detection (a raw value equal to [`crate::hand::ADC_MIN`] or [`crate::hand::ADC_MAX`]
//!    is at a rail of the 12-bit ADC, [`crate::hand::at_rail`]) and
//!    conversion to µV ([`EMG_LSB_UV`]).
//!
//! Settings are validated once ([`EmgFrontSettings::try_new`]); after that nothing returns a
//! `Result`, allocates or panics per frame. Knows no sockets or clocks: the caller gives each
//! frame's own receive time.

use thiserror::Error;

use crate::e2e::{E2eChecker, E2eError, E2eStatus};
use crate::emg::{
    EmgAssembler, EmgConfig, EmgConfigError, EmgFrame, EmgSample, EMG_CHANNELS, EMG_GROUPS,
    EMG_LSB_UV,
};
use crate::hand::at_rail;
use crate::messages::{EmgSamplesG0, EmgSamplesG1, EmgSamplesG2};
use crate::CanFrame;

/// Default counter step the E2E check accepts as a loss rather than a broken sequence: the
/// counter is 8 bits at 1 kHz, and up to 20 lost samples are bridged.
pub const DEFAULT_COUNTER_DELTA: u16 = 20;
pub use crate::emg::DEFAULT_MAX_GAP_US;

/// The ids of EMG_SAMPLES_G0..G2, by group.
const GROUP_IDS: [u32; EMG_GROUPS] = [EmgSamplesG0::ID, EmgSamplesG1::ID, EmgSamplesG2::ID];

/// The parameters of the front end, before validation.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct EmgFrontConfig {
    /// Nominal sample period, µs.
    pub sample_period_us: u64,
    /// Counter jump (samples lost, as time) beyond which the stream is reported broken, µs;
    /// a silence over it too, unless the counter resumes in sequence soon enough to be
    /// trusted ([`crate::emg::COUNTER_TRUST_SAMPLES`]).
    pub max_gap_us: u64,
    /// Largest counter step (per group) the E2E check accepts as in sequence.
    pub counter_delta: u16,
    /// Channels handed on per sample (the first `channels` of the bus's 12).
    pub channels: usize,
}

impl Default for EmgFrontConfig {
    fn default() -> Self {
        Self {
            sample_period_us: 1000,
            max_gap_us: DEFAULT_MAX_GAP_US,
            counter_delta: DEFAULT_COUNTER_DELTA,
            channels: EMG_CHANNELS,
        }
    }
}

impl EmgFrontConfig {
    /// The defaults at a sample rate (period rounded to whole µs).
    pub fn at_rate(sample_rate_hz: f64) -> Self {
        Self {
            sample_period_us: (1e6 / sample_rate_hz).round() as u64,
            ..Self::default()
        }
    }
}

/// A refused [`EmgFrontConfig`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Error)]
pub enum EmgFrontError {
    /// Sample period or gap limit refused by the assembler.
    #[error("EMG reassembly: {0}")]
    Assembler(#[from] EmgConfigError),
    /// Counter delta refused by the E2E checker.
    #[error("EMG E2E check: {0}")]
    E2e(#[from] E2eError),
    /// More channels than the bus carries, or none.
    #[error("{channels} EMG channels asked for, the bus carries 1..={EMG_CHANNELS}")]
    Channels {
        /// The refused count.
        channels: usize,
    },
}

/// Validated settings: building an [`EmgFront`] from them cannot fail.
#[derive(Debug, Clone)]
pub struct EmgFrontSettings {
    config: EmgFrontConfig,
    assembler: EmgAssembler,
    checkers: [E2eChecker; EMG_GROUPS],
}

impl EmgFrontSettings {
    /// Validates `config` once.
    pub fn try_new(config: EmgFrontConfig) -> Result<Self, EmgFrontError> {
        if config.channels == 0 || config.channels > EMG_CHANNELS {
            return Err(EmgFrontError::Channels {
                channels: config.channels,
            });
        }
        let assembler = EmgAssembler::try_new(EmgConfig {
            sample_period_us: config.sample_period_us,
            max_gap_us: config.max_gap_us,
        })?;
        let checker = |p| E2eChecker::try_new(p, config.counter_delta);
        let checkers = [
            checker(EmgSamplesG0::E2E)?,
            checker(EmgSamplesG1::E2E)?,
            checker(EmgSamplesG2::E2E)?,
        ];
        Ok(Self {
            config,
            assembler,
            checkers,
        })
    }

    /// The validated parameters.
    pub fn config(&self) -> &EmgFrontConfig {
        &self.config
    }
}

/// What the front end did with one frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FrameVerdict {
    /// Not an EMG_SAMPLES frame (other id, extended or remote): not looked at.
    NotEmg,
    /// Checked, decoded and handed to the reassembly.
    Accepted,
    /// Same counter as the group's previous frame: dropped.
    Repeated,
    /// Wrong CRC or length: dropped and counted.
    E2eError,
    /// Correct E2E but a payload the codec refuses: dropped and counted.
    Undecodable,
}

/// What the front end counted since it was built.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct FrontCounters {
    /// Samples emitted (bridged ones included).
    pub samples: u64,
    /// Samples emitted with at least one group bridged.
    pub samples_lost: u64,
    /// Frames dropped for a wrong CRC or length.
    pub e2e_errors: u64,
    /// Frames dropped as repeats.
    pub repeated: u64,
    /// Frames dropped because the codec refused the payload.
    pub undecodable: u64,
    /// Channel values at an ADC rail (one per channel and sample, over all the bus's channels:
    /// a railed amplifier input is a fault whether or not the chain uses it).
    pub railed: u64,
    /// Gaps longer than the limit.
    pub gaps: u64,
}

/// One sample as the signal chain takes it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrontSample {
    /// Every channel of the bus in µV; the used ones first.
    uv: [f64; EMG_CHANNELS],
    channels: usize,
    /// Receive time of the newest frame that contributed to or released it, µs.
    pub received_us: u64,
    /// The first sample after a gap over the limit.
    pub after_gap: bool,
    /// The bus's sample counter.
    pub counter: u8,
    /// Railed channels in this sample (all the bus's channels).
    pub railed: u32,
}

impl FrontSample {
    /// The used channels in µV, in channel order.
    pub fn uv(&self) -> &[f64] {
        &self.uv[..self.channels]
    }
}

/// The front end (see the module docs).
#[derive(Debug, Clone)]
pub struct EmgFront {
    channels: usize,
    assembler: EmgAssembler,
    checkers: [E2eChecker; EMG_GROUPS],
    counters: FrontCounters,
}

impl EmgFront {
    /// A front end in start state.
    pub fn new(settings: &EmgFrontSettings) -> Self {
        Self {
            channels: settings.config.channels,
            assembler: settings.assembler.clone(),
            checkers: settings.checkers.clone(),
            counters: FrontCounters::default(),
        }
    }

    /// Feeds one received frame with its own receive time; every sample it completes or
    /// forces out goes to `sink`, in counter order.
    pub fn on_frame(
        &mut self,
        frame: &CanFrame,
        received_us: u64,
        sink: &mut impl FnMut(&FrontSample),
    ) -> FrameVerdict {
        if frame.is_extended() || frame.is_remote() {
            return FrameVerdict::NotEmg;
        }
        let id = frame.raw_id();
        let Some(group) = GROUP_IDS.iter().position(|&g| g == id) else {
            return FrameVerdict::NotEmg;
        };
        let data = frame.data();
        match self.checkers[group].check(Some(data)) {
            // A counter jump is the assembler's business: it bridges or reports a gap. (The
            // checkers resynchronise at once, so `Sync` does not occur here.)
            E2eStatus::Ok | E2eStatus::WrongSequence | E2eStatus::Sync => {}
            E2eStatus::Repeated => {
                self.counters.repeated += 1;
                return FrameVerdict::Repeated;
            }
            E2eStatus::Error | E2eStatus::NoNewData => {
                self.counters.e2e_errors += 1;
                return FrameVerdict::E2eError;
            }
        }
        let Ok(Some(emg)) = EmgFrame::decode(id, data) else {
            self.counters.undecodable += 1;
            return FrameVerdict::Undecodable;
        };
        let (channels, counters) = (self.channels, &mut self.counters);
        self.assembler
            .push(&emg, received_us, &mut |s: &EmgSample| {
                sink(&convert(s, channels, counters));
            });
        self.counters.samples_lost = self.assembler.stats().lost_samples;
        FrameVerdict::Accepted
    }

    /// Emits every pending sample (bridging what is missing), at the end of a log.
    pub fn flush(&mut self, sink: &mut impl FnMut(&FrontSample)) {
        let (channels, counters) = (self.channels, &mut self.counters);
        self.assembler.flush(&mut |s: &EmgSample| {
            sink(&convert(s, channels, counters));
        });
        self.counters.samples_lost = self.assembler.stats().lost_samples;
    }

    /// Counters since start.
    pub fn counters(&self) -> FrontCounters {
        self.counters
    }

    /// Channels per emitted sample.
    pub fn channels(&self) -> usize {
        self.channels
    }
}

/// One reassembled sample in µV, counted.
#[inline]
fn convert(s: &EmgSample, channels: usize, counters: &mut FrontCounters) -> FrontSample {
    // Every channel is converted (a fixed-width loop the compiler vectorises);
    // `FrontSample::uv` hands on the first `channels`.
    let uv = s.raw.map(|raw| f64::from(raw) * EMG_LSB_UV);
    let railed = s.raw.iter().map(|&raw| u32::from(at_rail(raw))).sum();
    counters.samples += 1;
    counters.railed += u64::from(railed);
    counters.gaps += u64::from(s.after_gap);
    FrontSample {
        uv,
        channels,
        received_us: s.received_us,
        after_gap: s.after_gap,
        counter: s.counter,
        railed,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::e2e::E2eProtector;

    fn front() -> EmgFront {
        EmgFront::new(&EmgFrontSettings::try_new(EmgFrontConfig::default()).expect("defaults"))
    }

    /// The three protected frames of one sample, every channel `raw`.
    fn sample_frames(p: &mut [E2eProtector; 3], counter: u8, raw: i16) -> [CanFrame; 3] {
        let mut out = [CanFrame::new_standard(0, &[]).expect("empty"); 3];
        for (g, f) in out.iter_mut().enumerate() {
            let mut data = [0u8; 8];
            data[1] = counter;
            let v = (raw as u16) & 0x0FFF;
            // 12-bit little-endian fields from bit 16.
            let bits = u64::from(v) | u64::from(v) << 12 | u64::from(v) << 24 | u64::from(v) << 36;
            data[2..8].copy_from_slice(&bits.to_le_bytes()[..6]);
            *f = CanFrame::new_standard(GROUP_IDS[g] as u16, &data).expect("valid");
            p[g].protect(f).expect("right length");
        }
        out
    }

    #[test]
    fn checks_decodes_reassembles_and_counts() {
        let mut p =
            [EmgSamplesG0::E2E, EmgSamplesG1::E2E, EmgSamplesG2::E2E].map(E2eProtector::new);
        let mut fe = front();
        let mut out = Vec::new();
        let mut sink = |s: &FrontSample| out.push(*s);
        for (k, raw) in [(0u8, 4i16), (1, 2047), (2, -2048)] {
            for (i, f) in sample_frames(&mut p, k, raw).iter().enumerate() {
                let v = fe.on_frame(f, 1000 * u64::from(k) + i as u64, &mut sink);
                assert_eq!(v, FrameVerdict::Accepted);
            }
        }
        let mut bad = sample_frames(&mut p, 3, 0)[0];
        bad.data_mut()[3] ^= 1;
        assert_eq!(fe.on_frame(&bad, 3000, &mut sink), FrameVerdict::E2eError);
        let other = CanFrame::new_standard(0x300, &[0; 8]).expect("valid");
        assert_eq!(fe.on_frame(&other, 3000, &mut sink), FrameVerdict::NotEmg);
        assert_eq!(out.len(), 3);
        assert_eq!(out[0].uv(), &[10.0; 12][..]);
        assert_eq!(out[1].railed, 12);
        assert_eq!(out[2].uv()[11], -2048.0 * EMG_LSB_UV);
        let c = fe.counters();
        assert_eq!((c.samples, c.railed, c.e2e_errors), (3, 24, 1));
    }

    #[test]
    fn refuses_bad_settings() {
        let bad = |c: EmgFrontConfig| EmgFrontSettings::try_new(c).is_err();
        let d = EmgFrontConfig::default();
        assert!(bad(EmgFrontConfig { channels: 0, ..d }));
        assert!(bad(EmgFrontConfig { channels: 13, ..d }));
        assert!(bad(EmgFrontConfig {
            counter_delta: 0,
            ..d
        }));
        assert!(bad(EmgFrontConfig {
            max_gap_us: 100_000,
            ..d
        }));
        assert!(!bad(EmgFrontConfig::at_rate(1000.0)));
    }
}
