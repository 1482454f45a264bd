//! The node core: one call per conversion, frames into the queue, the queue into the CAN
//! controller.

use ads1299::{Ads1299, Code, Error, Frame};
use embedded_can::nb::Can;
use embedded_can::Frame as _;
use embedded_hal::spi::SpiDevice;
use hand_dbc_core::e2e::E2eProtector;
use hand_dbc_core::messages::{AmpState, EmgSamplesG0, EmgSamplesG1, EmgSamplesG2, EmgStatus};
use hand_dbc_core::CanFrame;

use crate::decimator::ZERO;
use crate::{BusScale, DcBlock, DcRemoval, Decimator, NodeRate, NodeSettings, TxQueue};

/// EMG channels on the bus: the first chip's 8, then the second chip's channels 1..4.
pub const CHANNELS: usize = 12;

/// Samples between two EMG_STATUS frames (10 Hz at 1 kHz, hand.dbc's cycle time).
pub const STATUS_EVERY: u16 = 100;

/// EMG_STATUS.Faults bit 0: ADC (an SPI error or a frame with a bad header since the last
/// status).
const FAULT_ADC: u8 = 1 << 0;
/// EMG_STATUS.Faults bit 4: transmit overrun (samples dropped in the amplifier).
const FAULT_TX_OVERRUN: u8 = 1 << 4;

/// What one sample period came to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SampleOutcome {
    /// Its three frames are queued.
    Queued,
    /// The queue had no room for all three: the whole sample is dropped (counted, counter
    /// advanced).
    Dropped,
    /// The chips could not be read (SPI error or bad status header): no sample (counted,
    /// counter advanced). At 2 kSPS: a failed read of either conversion of a pair.
    ReadError,
    /// At 2 kSPS, the first conversion of a pair: taken into the decimator, nothing queued.
    Filtering,
}

/// What the node counted since it started.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct NodeCounters {
    /// Bus sample periods (at 1 kSPS every call of [`AmpNode::on_frames`] or
    /// [`AmpNode::on_read_error`]; at 2 kSPS every second one).
    pub periods: u64,
    /// Conversions (every call of [`AmpNode::on_frames`] or [`AmpNode::on_read_error`]).
    pub conversions: u64,
    /// Samples whose frames were queued.
    pub queued: u64,
    /// Samples dropped because the transmit queue was full.
    pub dropped: u64,
    /// Periods without a sample: SPI errors.
    pub spi_errors: u64,
    /// Periods without a sample: a status word without the 1100 header.
    pub bad_headers: u64,
    /// Periods without a sample: conversions the node never read ([`AmpNode::on_missed`]).
    pub missed: u64,
    /// Frames the CAN controller refused with an error (dropped).
    pub tx_errors: u64,
    /// Frames the controller handed back to make room for a higher-priority one (requeued).
    pub displaced: u64,
    /// EMG_STATUS frames not queued for want of room (their masks carry over).
    pub status_dropped: u64,
}

/// The node core. `Q` is the transmit queue's size in frames (at least 4: one sample and a
/// status).
#[derive(Debug, Clone)]
pub struct AmpNode<const Q: usize = 12> {
    settings: NodeSettings,
    scale: BusScale,
    groups: [E2eProtector; 3],
    status: E2eProtector,
    /// The counter of the next sample period.
    counter: u8,
    queue: TxQueue<Q>,
    /// Since the last queued status: channels seen off, channels clipped, faults.
    lead_off: u16,
    saturation: u16,
    faults: u8,
    since_status: u16,
    counters: NodeCounters,
    /// At 2 kSPS: the FIR, the last conversion read (held into the FIR for one that could
    /// not be read), saturation codes and a failed read within the current pair.
    decimator: Option<Decimator<CHANNELS>>,
    last: [Code; CHANNELS],
    pair_saturation: u16,
    pair_failed: bool,
    /// The DC estimates, unless the settings send codes DC-coupled.
    dc_block: Option<DcBlock<CHANNELS>>,
}

impl<const Q: usize> AmpNode<Q> {
    /// A node in start state (counter 0, empty queue).
    pub fn new(settings: &NodeSettings) -> Self {
        Self {
            settings: *settings,
            scale: settings.scale(),
            groups: [
                E2eProtector::new(EmgSamplesG0::E2E),
                E2eProtector::new(EmgSamplesG1::E2E),
                E2eProtector::new(EmgSamplesG2::E2E),
            ],
            status: E2eProtector::new(EmgStatus::E2E),
            counter: 0,
            queue: TxQueue::default(),
            lead_off: 0,
            saturation: 0,
            faults: 0,
            since_status: 0,
            counters: NodeCounters::default(),
            decimator: match settings.rate() {
                NodeRate::Sps1000 => None,
                NodeRate::Sps2000Decimated => Some(Decimator::new()),
            },
            last: [ZERO; CHANNELS],
            pair_saturation: 0,
            pair_failed: false,
            dc_block: match settings.dc_removal() {
                DcRemoval::Off => None,
                DcRemoval::HighPass { shift } => Some(DcBlock::new(shift)),
            },
        }
    }

    /// The settings.
    pub fn settings(&self) -> &NodeSettings {
        &self.settings
    }

    /// What was counted.
    pub fn counters(&self) -> NodeCounters {
        self.counters
    }

    /// The counter the next sample gets.
    pub fn next_counter(&self) -> u8 {
        self.counter
    }

    /// Frames waiting for the controller.
    pub fn queued_frames(&self) -> usize {
        self.queue.len()
    }

    /// Reads both chips (call after DRDY) and hands the frames to [`Self::on_frames`], or
    /// counts the period lost ([`Self::on_read_error`]).
    pub fn sample<A: SpiDevice, B: SpiDevice>(
        &mut self,
        first: &mut Ads1299<A>,
        second: &mut Ads1299<B>,
    ) -> SampleOutcome {
        let a = first.read_frame();
        let b = second.read_frame();
        match (a, b) {
            (Ok(a), Ok(b)) => self.on_frames(&a, &b),
            (a, b) => {
                let bad_header = matches!(a, Err(Error::BadHeader { .. }))
                    || matches!(b, Err(Error::BadHeader { .. }));
                if bad_header {
                    self.counters.bad_headers += 1;
                } else {
                    self.counters.spi_errors += 1;
                }
                self.on_read_error()
            }
        }
    }

    /// One conversion's data frames (first chip, second chip): the bus values, the three
    /// EMG frames queued (or the sample dropped whole), the status when due. At 2 kSPS every
    /// second call does that, on the decimator's output; the first of a pair is
    /// [`SampleOutcome::Filtering`].
    pub fn on_frames(&mut self, first: &Frame, second: &Frame) -> SampleOutcome {
        self.counters.conversions += 1;
        let mut codes = [ZERO; CHANNELS];
        for (c, code) in codes.iter_mut().enumerate() {
            *code = if c < 8 {
                first.codes[c]
            } else {
                second.codes[c - 8]
            };
        }
        self.lead_off |=
            u16::from(first.status.lead_off()) | (u16::from(second.status.lead_off() & 0x0F) << 8);
        if let Some(d) = &mut self.decimator {
            self.last = codes;
            for (c, code) in codes.iter().enumerate() {
                if code.is_saturated() {
                    self.pair_saturation |= 1 << c;
                }
            }
            match d.push(&codes) {
                None => return SampleOutcome::Filtering,
                Some(out) => codes = out,
            }
            self.saturation |= core::mem::take(&mut self.pair_saturation);
            if core::mem::take(&mut self.pair_failed) {
                return self.period_lost();
            }
        }
        let bus = match &mut self.dc_block {
            Some(b) => b.to_bus(&codes, self.scale),
            None => codes.map(|code| self.scale.to_bus(code)),
        };
        let mut raw = [0i16; CHANNELS];
        for (c, (r, v)) in raw.iter_mut().zip(bus).enumerate() {
            *r = v.raw;
            if v.clipped {
                self.saturation |= 1 << c;
            }
        }
        let outcome = match self.emg_frames(&raw) {
            Some(frames) if self.queue.free() >= frames.len() => {
                for f in frames {
                    self.queue.push_back(f);
                }
                self.counters.queued += 1;
                SampleOutcome::Queued
            }
            _ => {
                self.counters.dropped += 1;
                self.faults |= FAULT_TX_OVERRUN;
                SampleOutcome::Dropped
            }
        };
        self.end_period();
        outcome
    }

    /// A conversion whose chips could not be read: no frames, counter advanced, ADC fault on
    /// the next status. At 2 kSPS the last conversion read is held into the decimator in its
    /// place (its history stays in step), and the pair's bus sample is not sent.
    pub fn on_read_error(&mut self) -> SampleOutcome {
        self.counters.conversions += 1;
        self.faults |= FAULT_ADC;
        if let Some(d) = &mut self.decimator {
            if d.push(&self.last).is_none() {
                self.pair_failed = true;
                return SampleOutcome::ReadError;
            }
            self.pair_failed = false;
            self.saturation |= core::mem::take(&mut self.pair_saturation);
        }
        self.period_lost()
    }

    /// A bus period whose conversions the node never read: the firmware was held up past
    /// the chips' next DRDY (a DRDY edge counter tells it how many). No frames; the counter
    /// advances so the daemon's gap rule sees the loss, and the next EMG_STATUS reports it as
    /// samples dropped in the amplifier (Faults bit 4), as a full transmit queue does. At
    /// 2 kSPS the last conversion read stands in for the pair in the decimator's history.
    pub fn on_missed(&mut self) {
        self.counters.missed += 1;
        if let Some(d) = &mut self.decimator {
            let _ = d.push(&self.last);
            let _ = d.push(&self.last);
            self.pair_failed = false;
            self.pair_saturation = 0;
        }
        self.faults |= FAULT_TX_OVERRUN;
        self.end_period();
    }

    /// A bus period without a sample.
    fn period_lost(&mut self) -> SampleOutcome {
        self.faults |= FAULT_ADC;
        self.end_period();
        SampleOutcome::ReadError
    }

    /// Hands queued frames to the controller until it has no room. A frame the controller
    /// refuses with an error is dropped and counted; one it hands back to make room for a
    /// higher-priority frame is requeued at the front.
    pub fn drain<C: Can>(&mut self, can: &mut C) {
        // Each pass removes a frame or stops; a handed-back frame is put back, so bound the
        // passes to keep a misbehaving controller from spinning us.
        for _ in 0..2 * Q {
            let Some(frame) = self.queue.front() else {
                return;
            };
            let Some(out) = C::Frame::new(frame.id(), frame.data()) else {
                self.counters.tx_errors += 1;
                self.queue.pop_front();
                continue;
            };
            match can.transmit(&out) {
                Ok(None) => {
                    self.queue.pop_front();
                }
                Ok(Some(back)) => {
                    self.queue.pop_front();
                    self.counters.displaced += 1;
                    if let Some(back) = CanFrame::new(back.id(), back.data()) {
                        if !self.queue.push_front(back) {
                            self.counters.tx_errors += 1;
                        }
                    }
                }
                Err(nb::Error::WouldBlock) => return,
                Err(nb::Error::Other(_)) => {
                    self.counters.tx_errors += 1;
                    self.queue.pop_front();
                }
            }
        }
    }

    /// Counter and status bookkeeping at the end of every period.
    fn end_period(&mut self) {
        self.counters.periods += 1;
        self.counter = self.counter.wrapping_add(1);
        self.since_status += 1;
        if self.since_status >= STATUS_EVERY {
            // Room first: building the frame advances the status's alive counter.
            match (self.queue.free() > 0)
                .then(|| self.status_frame())
                .flatten()
            {
                Some(f) => {
                    self.queue.push_back(f);
                    self.since_status = 0;
                    self.lead_off = 0;
                    self.saturation = 0;
                    self.faults = 0;
                }
                None => self.counters.status_dropped += 1,
            }
        }
    }

    /// The three EMG frames of the current counter. `None` only if the codec refused a value,
    /// which the clamping to the 12-bit range rules out.
    fn emg_frames(&mut self, raw: &[i16; CHANNELS]) -> Option<[CanFrame; 3]> {
        let mut g0 = EmgSamplesG0::new(0.0, 0.0, 0.0, 0.0).ok()?;
        g0.set_emg0_raw(raw[0]).ok()?;
        g0.set_emg1_raw(raw[1]).ok()?;
        g0.set_emg2_raw(raw[2]).ok()?;
        g0.set_emg3_raw(raw[3]).ok()?;
        let mut g1 = EmgSamplesG1::new(0.0, 0.0, 0.0, 0.0).ok()?;
        g1.set_emg4_raw(raw[4]).ok()?;
        g1.set_emg5_raw(raw[5]).ok()?;
        g1.set_emg6_raw(raw[6]).ok()?;
        g1.set_emg7_raw(raw[7]).ok()?;
        let mut g2 = EmgSamplesG2::new(0.0, 0.0, 0.0, 0.0).ok()?;
        g2.set_emg8_raw(raw[8]).ok()?;
        g2.set_emg9_raw(raw[9]).ok()?;
        g2.set_emg10_raw(raw[10]).ok()?;
        g2.set_emg11_raw(raw[11]).ok()?;
        // The sample counter jumps over dropped and unread periods: the receiver sees the gap.
        for p in &mut self.groups {
            p.set_next_counter(self.counter);
        }
        Some([
            self.groups[0].protect_message(&g0).ok()?,
            self.groups[1].protect_message(&g1).ok()?,
            self.groups[2].protect_message(&g2).ok()?,
        ])
    }

    fn status_frame(&mut self) -> Option<CanFrame> {
        let m = EmgStatus::new(
            AmpState::Running,
            self.settings.amp_sample_rate(),
            self.settings.amp_gain(),
            self.lead_off,
            self.saturation,
            self.faults,
        )
        .ok()?;
        self.status.protect_message(&m).ok()
    }
}
