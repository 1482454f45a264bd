//! The simulated amplifier board: two simulated ADS1299 behind the firmware's own node core
//! (`amp-node`), so the simulator's EMG_SAMPLES and EMG_STATUS frames are made by the code that
//! runs on the node's microcontroller, bit for bit. One path, as for the daemon's front end:
//! every in-memory and vcan test exercises the firmware.
//!
//! The patient's µV become the chips' 24-bit codes at the reference gain (x8: 67 nV per code,
//! 37 times finer than the bus's 2.5 µV); the node reads them through the ADS1299 driver over
//! a simulated SPI, takes out their DC (the reference's 2.5 Hz DC blocker), scales them to the
//! bus in its exact integer arithmetic, packs and protects
//! the frames (`hand-dbc-core`) and reports lead-off (from the chips' status words) and
//! clipping in EMG_STATUS every 100 samples.

use ads1299::{Ads1299, Code, Frame, Gain, LeadOff, Status};
use ads1299_sim::{SimAds1299, TakeAll};
use amp_node::{AmpNode, BusScale, DcRemoval, NodeCounters, NodeSettings, CHANNELS};

use crate::dbc::CanFrame;
use crate::error::SimError;

/// The node's transmit queue, frames: a sample's three EMG frames and a status, with room.
/// The simulated controller takes every frame at once, so it never fills.
const QUEUE: usize = 12;

/// Code 0 (the second chip's powered-down channels 5..8).
const ZERO: Code = Code::from_be_bytes([0; 3]);

/// The gain the board runs at (the firmware README's reference).
pub const BOARD_GAIN: Gain = Gain::X8;

/// Two simulated ADS1299 and the node core reading them.
#[derive(Debug)]
pub struct AmpBoard {
    node: AmpNode<QUEUE>,
    chips: (Ads1299<SimAds1299>, Ads1299<SimAds1299>),
    /// The test side of the chips: where their conversions are served.
    sims: (SimAds1299, SimAds1299),
    /// What the node handed to its CAN controller since the last [`AmpBoard::take_frames`].
    out: TakeAll<CanFrame>,
}

impl Clone for AmpBoard {
    /// A board with the same node state over chips of its own (a clone of the driver would
    /// share the simulated chips with the original).
    fn clone(&self) -> Self {
        let sims = (
            SimAds1299::from_state(self.sims.0.state().clone()),
            SimAds1299::from_state(self.sims.1.state().clone()),
        );
        Self {
            node: self.node.clone(),
            chips: (Ads1299::new(sims.0.clone()), Ads1299::new(sims.1.clone())),
            sims,
            out: self.out.clone(),
        }
    }
}

impl AmpBoard {
    /// The reference board (the firmware's DC removal on): powers the chips and runs the
    /// firmware's start-up on them (reset, id check, registers written and read back, RDATAC,
    /// START).
    pub fn try_new() -> Result<Self, SimError> {
        Self::try_with(DcRemoval::REFERENCE)
    }

    /// [`AmpBoard::try_new`] with the node's DC removal as given (`Off`: the codes reach the
    /// bus DC-coupled, to compare a recording with the bus to the LSB).
    pub fn try_with(dc: DcRemoval) -> Result<Self, SimError> {
        let settings = NodeSettings::try_new(BOARD_GAIN, LeadOff::Dc6nA)?.with_dc_removal(dc)?;
        let sims = (SimAds1299::new(), SimAds1299::new());
        let mut chips = (Ads1299::new(sims.0.clone()), Ads1299::new(sims.1.clone()));
        chips.0.init(settings.first_chip())?;
        chips.1.init(settings.second_chip())?;
        chips.0.start()?;
        chips.1.start()?;
        Ok(Self {
            node: AmpNode::new(&settings),
            chips,
            sims,
            out: TakeAll::default(),
        })
    }

    /// One conversion: the 12 channels' µV (bus channel order) with the channels whose
    /// electrodes are off (`lead_off`, bit c = channel c; the chips' comparators report them on
    /// the P side) and those whose ADC is driven into saturation (`saturated`: the chip's
    /// positive full-scale code), read by the node; its frames are queued for
    /// [`AmpBoard::take_frames`].
    pub fn convert(&mut self, uv: &[f64; CHANNELS], lead_off: u16, saturated: u16) {
        let code = |c: usize| {
            if saturated & (1 << c) != 0 {
                Code::POSITIVE_FULL_SCALE
            } else {
                Self::code(uv[c])
            }
        };
        let first = Frame {
            status: Status::new(lead_off as u8, 0, 0),
            codes: std::array::from_fn(code),
        };
        let second = Frame {
            status: Status::new((lead_off >> 8) as u8 & 0x0F, 0, 0),
            codes: std::array::from_fn(|c| if c < 4 { code(8 + c) } else { ZERO }),
        };
        self.sims.0.serve(&first);
        self.sims.1.serve(&second);
        self.node.sample(&mut self.chips.0, &mut self.chips.1);
        self.node.drain(&mut self.out);
    }

    /// `periods` sample periods whose conversions the node never read (the simulator's
    /// process stalled, as a firmware held up past DRDY): the node's counter jumps over them
    /// and its next EMG_STATUS reports samples dropped in the amplifier (Faults bit 4), with
    /// the statuses that fell due among them.
    pub fn skip(&mut self, periods: u64) {
        for _ in 0..periods {
            self.node.on_missed();
            self.node.drain(&mut self.out);
        }
    }

    /// The frames the node sent since the last call, in its order.
    pub fn take_frames(&mut self) -> std::vec::Drain<'_, CanFrame> {
        self.out.0.drain(..)
    }

    /// The node's own counts.
    pub fn counters(&self) -> NodeCounters {
        self.node.counters()
    }

    /// The chip's code for `uv` at the board's gain: rounded, at full scale beyond it.
    pub fn code(uv: f64) -> Code {
        let c = (uv / BusScale::new(BOARD_GAIN).uv_per_code()).round();
        if c >= f64::from(Code::POSITIVE_FULL_SCALE.get()) {
            Code::POSITIVE_FULL_SCALE
        } else if c <= f64::from(Code::NEGATIVE_FULL_SCALE.get()) {
            Code::NEGATIVE_FULL_SCALE
        } else {
            Code::new(c as i32).unwrap_or(ZERO)
        }
    }
}
