//! The sEMG amplifier node: the simulated patient's EMG through the firmware's own node core
//! ([`AmpBoard`]: two simulated ADS1299 read by `amp-node`), which makes EMG_SAMPLES_G0..G2 at
//! 1 kHz and EMG_STATUS every 100 samples; the bus faults of the plan act on its frames.

use hand_dbc::e2e::E2eProfile;
use hand_dbc::messages::{EmgSamplesG0, EmgSamplesG1, EmgSamplesG2, EmgStatus};

use super::{std_id, AmpBoard, Bus, NodeStats};
use crate::dbc::{seal, CanFrame};
use crate::emg::mixing::N_CHANNELS;
use crate::emg::{AmplifierConfig, ChannelFaults, EmgSynth};
use crate::error::SimError;
use crate::faults::{CrcTarget, Fault, FaultPlan};
use crate::patient::{Intent, MuscleDrive};

/// The bus's EMG sample rate, Hz: the firmware's node core puts 1 kHz on the bus.
pub const NODE_RATE_HZ: f64 = 1000.0;

/// Node-level settings around the signal model.
#[derive(Debug, Clone, PartialEq)]
pub struct AmplifierNodeConfig {
    /// The signal model (its rate must be the node's, [`NODE_RATE_HZ`]).
    pub signal: AmplifierConfig,
    /// How intents drive the muscles.
    pub drive: MuscleDrive,
    /// Time of the first sample, µs.
    pub start_us: u64,
    /// If a poll finds the node more than this far behind (a stalled process), the backlog is
    /// skipped: the node counts those periods missed, its counter jumps over them and its
    /// next EMG_STATUS reports samples dropped, instead of a burst of stale samples.
    pub max_backlog_us: u64,
}

impl Default for AmplifierNodeConfig {
    fn default() -> Self {
        Self {
            signal: AmplifierConfig::default(),
            drive: MuscleDrive::default(),
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
    board: AmpBoard,
    intent: Intent,
    faults: FaultPlan,
    period_us: u64,
    next_sample_us: u64,
    /// Added to the node's sample counter on the bus (the counter-jump fault).
    counter_jump: u8,
    emg_frames: u64,
    status_frames: u64,
    samples_dropped: u64,
    held_back: Option<[CanFrame; 3]>,
    one_shots: u64,
    /// The board's frames of the current period (reused: no allocation per sample).
    out: Vec<CanFrame>,
    stats: NodeStats,
}

impl AmplifierNode {
    /// Builds the node; the signal's sample rate must be the node's ([`NODE_RATE_HZ`]).
    pub fn try_new(cfg: AmplifierNodeConfig) -> Result<Self, SimError> {
        cfg.drive.validate()?;
        let synth = EmgSynth::try_new(cfg.signal.clone())?;
        if cfg.signal.sample_rate_hz != NODE_RATE_HZ {
            return Err(SimError::OutOfRange {
                name: "sample_rate_hz",
                value: cfg.signal.sample_rate_hz,
                allowed: "1000 Hz (the amplifier node's firmware puts 1 kHz on the bus)",
            });
        }
        let period_us = (1e6 / cfg.signal.sample_rate_hz).round() as u64;
        Ok(Self {
            next_sample_us: cfg.start_us,
            synth,
            board: AmpBoard::try_new()?,
            intent: Intent::REST,
            faults: FaultPlan::new(),
            period_us,
            counter_jump: 0,
            emg_frames: 0,
            status_frames: 0,
            samples_dropped: 0,
            held_back: None,
            one_shots: 0,
            out: Vec::with_capacity(8),
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

    /// The firmware's node core on the simulated board.
    pub fn board(&self) -> &AmpBoard {
        &self.board
    }

    /// Generates and sends every sample (and the status the node makes every 100) due by
    /// `now_us`.
    pub fn poll<B: Bus>(&mut self, now_us: u64, bus: &mut B) {
        // The amplifier listens to nothing; drain so a SocketCAN receive queue cannot fill.
        while self.stats.receive(bus).is_some() {}
        if now_us > self.next_sample_us + self.cfg.max_backlog_us {
            let skipped = (now_us - self.next_sample_us) / self.period_us;
            self.samples_dropped += skipped;
            self.next_sample_us += skipped * self.period_us;
            self.board.skip(skipped);
            self.send_board_frames(self.next_sample_us, bus);
        }
        while self.next_sample_us <= now_us {
            let t = self.next_sample_us;
            self.send_sample(t, bus);
            self.next_sample_us += self.period_us;
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
        let cf = self.channel_faults(t);
        let mut uv = [0.0; N_CHANNELS];
        self.synth.next_uv(&act, cf, &mut uv);
        self.board.convert(&uv, cf.lead_off, cf.saturated);
        for (i, f) in self.faults.active(t) {
            if let Fault::CounterJump { by } = f {
                if self.one_shots & (1 << i) == 0 {
                    self.one_shots |= 1 << i;
                    self.counter_jump = self.counter_jump.wrapping_add(by);
                }
            }
        }
        self.send_board_frames(t, bus);
    }

    /// Sends what the node made this period, through the plan's bus faults: a sample's three
    /// EMG frames (or none, if the node dropped it) and a status when one was due.
    fn send_board_frames<B: Bus>(&mut self, t: u64, bus: &mut B) {
        let mut out = std::mem::take(&mut self.out);
        out.clear();
        out.extend(self.board.take_frames());
        let mut sample: [Option<CanFrame>; 3] = [None; 3];
        for frame in &out {
            match std_id(frame) {
                EmgSamplesG0::ID => sample[0] = Some(*frame),
                EmgSamplesG1::ID => sample[1] = Some(*frame),
                EmgSamplesG2::ID => sample[2] = Some(*frame),
                EmgStatus::ID => {}
                _ => self.stats.tx_errors += 1,
            }
        }
        if let [Some(g0), Some(g1), Some(g2)] = sample {
            self.send_emg(t, [g0, g1, g2], bus);
        }
        // The node queues a status after the period's sample: in that order on the bus.
        for frame in out.iter().filter(|f| std_id(f) == EmgStatus::ID) {
            self.send_status(t, *frame, bus);
        }
        self.out = out;
    }

    /// One sample's EMG frames through the plan's faults.
    fn send_emg<B: Bus>(&mut self, t: u64, mut frames: [CanFrame; 3], bus: &mut B) {
        if self.counter_jump != 0 {
            for (f, p) in frames.iter_mut().zip(EMG_PROFILES) {
                let counter = f.data()[1] & counter_mask(p);
                seal(f, p, counter.wrapping_add(self.counter_jump), false);
            }
        }
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

    /// The node's EMG_STATUS through the plan's faults (silence, a bad CRC).
    fn send_status<B: Bus>(&mut self, t: u64, mut frame: CanFrame, bus: &mut B) {
        let mut silent = false;
        let mut bad_crc = false;
        self.status_frames += 1;
        for (_, f) in self.faults.active(t) {
            match f {
                Fault::AmplifierSilence => silent = true,
                Fault::BadCrc {
                    target: CrcTarget::EmgStatus,
                    every,
                } => bad_crc |= self.status_frames.is_multiple_of(u64::from(every)),
                _ => {}
            }
        }
        if silent {
            return;
        }
        if bad_crc {
            frame.data_mut()[0] ^= 0xFF;
        }
        self.stats.transmit(bus, &frame);
    }
}

/// The E2E profiles of EMG_SAMPLES_G0..G2, in the node's order.
const EMG_PROFILES: [E2eProfile; 3] = [EmgSamplesG0::E2E, EmgSamplesG1::E2E, EmgSamplesG2::E2E];

/// The alive counter's bits in byte 1 under `profile`.
fn counter_mask(profile: E2eProfile) -> u8 {
    if profile.counter_bits() == 8 {
        0xFF
    } else {
        0x0F
    }
}
