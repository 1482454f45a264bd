//! The sEMG amplifier node: EMG_SAMPLES_G0..G2 at the sample rate, EMG_STATUS at 10 Hz.

use hand_dbc::messages::{
    AmpGain, AmpSampleRate, AmpState, EmgSamplesG0, EmgSamplesG1, EmgSamplesG2, EmgStatus,
};

use super::{Bus, NodeStats};
use crate::dbc::{seal, CanFrame};
use crate::emg::{AmplifierConfig, ChannelFaults, EmgSample, EmgSynth};
use crate::error::SimError;
use crate::faults::{CrcTarget, Fault, FaultPlan};
use crate::patient::{Intent, MuscleDrive};

/// EMG_STATUS fault bit 4: samples dropped in the amplifier (transmit overrun).
pub const AMP_FAULT_TX_OVERRUN: u8 = 1 << 4;

/// Node-level settings around the signal model.
#[derive(Debug, Clone, PartialEq)]
pub struct AmplifierNodeConfig {
    /// The signal model.
    pub signal: AmplifierConfig,
    /// How intents drive the muscles.
    pub drive: MuscleDrive,
    /// EMG_STATUS period, µs (hand.dbc: 100 ms).
    pub status_period_us: u64,
    /// Time of the first sample, µs.
    pub start_us: u64,
    /// If a poll finds the node more than this far behind (a stalled process), the backlog is
    /// dropped, counted and flagged in EMG_STATUS instead of being sent as one burst.
    pub max_backlog_us: u64,
}

impl Default for AmplifierNodeConfig {
    fn default() -> Self {
        Self {
            signal: AmplifierConfig::default(),
            drive: MuscleDrive::default(),
            status_period_us: 100_000,
            start_us: 0,
            max_backlog_us: 100_000,
        }
    }
}

/// The amplifier on the bus. Its muscles follow the intent last given with
/// [`AmplifierNode::set_intent`].
#[derive(Debug, Clone)]
pub struct AmplifierNode {
    cfg: AmplifierNodeConfig,
    synth: EmgSynth,
    intent: Intent,
    faults: FaultPlan,
    period_us: u64,
    next_sample_us: u64,
    next_status_us: u64,
    sample_counter: u8,
    status_counter: u8,
    emg_frames: u64,
    status_frames: u64,
    saturation_since_status: u16,
    overrun_since_status: bool,
    samples_dropped: u64,
    held_back: Option<[CanFrame; 3]>,
    one_shots: u64,
    stats: NodeStats,
}

impl AmplifierNode {
    /// Builds the node; the sample rate must be one hand.dbc can announce (500, 1000 or 2000
    /// Hz).
    pub fn try_new(cfg: AmplifierNodeConfig) -> Result<Self, SimError> {
        cfg.drive.validate()?;
        let synth = EmgSynth::try_new(cfg.signal.clone())?;
        if sample_rate_code(cfg.signal.sample_rate_hz).is_none() {
            return Err(SimError::OutOfRange {
                name: "sample_rate_hz",
                value: cfg.signal.sample_rate_hz,
                allowed: "500, 1000 or 2000 Hz (hand.dbc EMG_STATUS SampleRate)",
            });
        }
        if !(1_000..=10_000_000).contains(&cfg.status_period_us) {
            return Err(SimError::OutOfRange {
                name: "status_period_us",
                value: cfg.status_period_us as f64,
                allowed: "1 ms..=10 s",
            });
        }
        let period_us = (1e6 / cfg.signal.sample_rate_hz).round() as u64;
        Ok(Self {
            next_sample_us: cfg.start_us,
            next_status_us: cfg.start_us,
            synth,
            intent: Intent::REST,
            faults: FaultPlan::new(),
            period_us,
            sample_counter: 0,
            status_counter: 0,
            emg_frames: 0,
            status_frames: 0,
            saturation_since_status: 0,
            overrun_since_status: false,
            samples_dropped: 0,
            held_back: None,
            one_shots: 0,
            stats: NodeStats::default(),
            cfg,
        })
    }

    /// Sets what the patient intends from now on.
    pub fn set_intent(&mut self, intent: Intent) {
        self.intent = intent.clamped();
    }

    /// The current intent.
    pub fn intent(&self) -> Intent {
        self.intent
    }

    /// Replaces the fault plan.
    pub fn set_faults(&mut self, faults: FaultPlan) {
        self.faults = faults;
    }

    /// Transmit and receive counts.
    pub fn stats(&self) -> NodeStats {
        self.stats
    }

    /// Samples generated so far (sent or not).
    pub fn samples(&self) -> u64 {
        self.synth.samples()
    }

    /// Samples skipped because a poll came more than `max_backlog_us` late.
    pub fn samples_dropped(&self) -> u64 {
        self.samples_dropped
    }

    /// The signal model.
    pub fn synth(&self) -> &EmgSynth {
        &self.synth
    }

    /// Generates and sends every sample and status due by `now_us`.
    pub fn poll<B: Bus>(&mut self, now_us: u64, bus: &mut B) {
        // The amplifier listens to nothing; drain so a SocketCAN receive queue cannot fill.
        while self.stats.receive(bus).is_some() {}
        if now_us > self.next_sample_us + self.cfg.max_backlog_us {
            let skipped = (now_us - self.next_sample_us) / self.period_us;
            self.samples_dropped += skipped;
            self.next_sample_us += skipped * self.period_us;
            self.sample_counter = self.sample_counter.wrapping_add(skipped as u8);
            self.overrun_since_status = true;
        }
        while self.next_sample_us <= now_us {
            let t = self.next_sample_us;
            self.send_sample(t, bus);
            self.next_sample_us += self.period_us;
        }
        while self.next_status_us <= now_us {
            let t = self.next_status_us;
            self.send_status(t, bus);
            self.next_status_us += self.cfg.status_period_us;
        }
    }

    fn channel_faults(&self, t: u64) -> ChannelFaults {
        let mut cf = ChannelFaults::default();
        for (_, s) in self.faults.iter().filter(|(_, s)| s.active(t)) {
            match s.fault {
                Fault::LeadOff { channels } => cf.lead_off |= channels,
                Fault::Saturation { channels } => cf.saturated |= channels,
                Fault::OverEffort { pct } => cf.effort_pct = Some(pct),
                Fault::ElectrodePop { channel } => cf.pop = Some((channel, t - s.from_us)),
                Fault::ElectrodeShift { tenths } => cf.shift_tenths = tenths,
                _ => {}
            }
        }
        cf
    }

    fn send_sample<B: Bus>(&mut self, t: u64, bus: &mut B) {
        let act = self.cfg.drive.activation(&self.intent);
        let sample = self.synth.next_sample(&act, self.channel_faults(t));
        self.saturation_since_status |= sample.saturated;
        let mut counter = self.sample_counter;
        for (i, f) in self.faults.active(t) {
            if let Fault::CounterJump { by } = f {
                if self.one_shots & (1 << i) == 0 {
                    self.one_shots |= 1 << i;
                    counter = counter.wrapping_add(by);
                }
            }
        }
        self.sample_counter = counter.wrapping_add(1);
        let Some(mut frames) = emg_frames(&sample, counter) else {
            // Unreachable while the quantiser clips to the DBC range; counted, never hidden.
            self.stats.tx_errors += 3;
            return;
        };
        let silent = self
            .faults
            .active(t)
            .any(|(_, f)| f == Fault::AmplifierSilence);
        if silent {
            self.emg_frames += 3;
            return;
        }
        let sample_index = self.synth.samples() - 1;
        let mut reorder = false;
        for (_, f) in self.faults.active(t) {
            if let Fault::ReorderEmgFrames { every } = f {
                reorder |= sample_index.is_multiple_of(u64::from(every));
            }
        }
        for frame in frames.iter_mut() {
            self.emg_frames += 1;
            let n = self.emg_frames;
            let hit = |every: u32| n.is_multiple_of(u64::from(every));
            let mut bad_crc = false;
            for (_, f) in self.faults.active(t) {
                if let Fault::BadCrc {
                    target: CrcTarget::Emg,
                    every,
                } = f
                {
                    bad_crc |= hit(every);
                }
            }
            if bad_crc {
                frame.data_mut()[0] ^= 0xFF;
            }
        }
        if reorder && self.held_back.is_none() {
            self.held_back = Some(frames);
            return;
        }
        let first = self.emg_frames - 2;
        for (k, frame) in frames.iter().enumerate() {
            let n = first + k as u64;
            let mut drop = false;
            let mut repeat = false;
            for (_, f) in self.faults.active(t) {
                match f {
                    Fault::DropEmgFrames { every } => drop |= n.is_multiple_of(u64::from(every)),
                    Fault::RepeatEmgFrames { every } => {
                        repeat |= n.is_multiple_of(u64::from(every))
                    }
                    _ => {}
                }
            }
            if drop {
                continue;
            }
            self.stats.transmit(bus, frame);
            if repeat {
                self.stats.transmit(bus, frame);
            }
        }
        if let Some(held) = self.held_back.take() {
            for frame in &held {
                self.stats.transmit(bus, frame);
            }
        }
    }

    fn send_status<B: Bus>(&mut self, t: u64, bus: &mut B) {
        let mut lead_off = 0u16;
        let mut silent = false;
        let mut bad_crc = false;
        self.status_frames += 1;
        for (_, f) in self.faults.active(t) {
            match f {
                Fault::LeadOff { channels } => lead_off |= channels,
                Fault::AmplifierSilence => silent = true,
                Fault::BadCrc {
                    target: CrcTarget::EmgStatus,
                    every,
                } => bad_crc |= self.status_frames.is_multiple_of(u64::from(every)),
                _ => {}
            }
        }
        let faults = if self.overrun_since_status {
            AMP_FAULT_TX_OVERRUN
        } else {
            0
        };
        let saturation = self.saturation_since_status;
        self.saturation_since_status = 0;
        self.overrun_since_status = false;
        let counter = self.status_counter;
        self.status_counter = (counter + 1) & 0x0F;
        if silent {
            return;
        }
        let rate =
            sample_rate_code(self.cfg.signal.sample_rate_hz).unwrap_or(AmpSampleRate::Sr1000Hz);
        let state = if lead_off != 0 {
            AmpState::Fault
        } else {
            AmpState::Running
        };
        let Ok(msg) = EmgStatus::new(state, rate, AmpGain::Gain1, lead_off, saturation, faults)
        else {
            self.stats.tx_errors += 1;
            return;
        };
        let mut frame = msg.to_frame();
        seal(&mut frame, EmgStatus::E2E, counter, bad_crc);
        self.stats.transmit(bus, &frame);
    }
}

/// hand.dbc's code for a sample rate.
fn sample_rate_code(hz: f64) -> Option<AmpSampleRate> {
    match hz.round() as u32 {
        500 => Some(AmpSampleRate::Sr500Hz),
        1000 => Some(AmpSampleRate::Sr1000Hz),
        2000 => Some(AmpSampleRate::Sr2000Hz),
        _ => None,
    }
}

/// The three sealed EMG frames of one sample. `None` only if a count were outside the DBC's
/// range, which the quantiser rules out.
pub fn emg_frames(sample: &EmgSample, counter: u8) -> Option<[CanFrame; 3]> {
    let uv = |c: usize| f64::from(sample.counts[c]) * EmgSamplesG0::EMG0_FACTOR;
    let g0 = EmgSamplesG0::new(uv(0), uv(1), uv(2), uv(3))
        .ok()?
        .to_frame();
    let g1 = EmgSamplesG1::new(uv(4), uv(5), uv(6), uv(7))
        .ok()?
        .to_frame();
    let g2 = EmgSamplesG2::new(uv(8), uv(9), uv(10), uv(11))
        .ok()?
        .to_frame();
    let mut frames = [g0, g1, g2];
    let profiles = [EmgSamplesG0::E2E, EmgSamplesG1::E2E, EmgSamplesG2::E2E];
    for (f, p) in frames.iter_mut().zip(profiles) {
        seal(f, p, counter, false);
    }
    Some(frames)
}
