//! One monitor fed by any source: events in, [`MonitorState`] out.

use decoder::dsp::ChainSettings;
use hand_dbc::CanFrame;

use super::frames::FrameDecoder;
use super::live::Live;
use super::state::MonitorState;

/// What a source delivers.
#[derive(Debug)]
pub enum Event {
    /// One line of the daemon's subscription.
    Live(Box<Live>),
    /// One frame with its receive time, µs.
    Frame(u64, CanFrame),
    /// The source ended, and why.
    End(String),
}

/// The state and, for frame sources, the decoder that fills it.
#[derive(Debug, Clone)]
pub struct Monitor {
    /// What is shown.
    pub state: MonitorState,
    decoder: FrameDecoder,
}

impl Monitor {
    /// A monitor titled `source`, decoding EMG with the chain `settings`.
    pub fn new(source: impl Into<String>, settings: &ChainSettings) -> Self {
        Self {
            state: MonitorState::new(source, settings.n_channels()),
            decoder: FrameDecoder::new(settings),
        }
    }

    /// Follows these CiA 402 drives' frames too (the bus and log sources).
    pub fn set_drives(&mut self, drives: super::drives::BusDrives) {
        self.decoder.set_drives(drives);
    }

    /// Takes one event.
    pub fn apply(&mut self, e: Event) {
        match e {
            Event::Live(l) => self.state.apply_live(&l),
            Event::Frame(t, f) => self.decoder.on_frame(&mut self.state, &f, t),
            Event::End(why) => {
                if let (Some(t), None) = (self.decoder.last_frame_us(), &self.state.ended) {
                    // The last values of a log, up to its last frame.
                    self.decoder.refresh(&mut self.state, t);
                }
                self.state.ended = Some(why);
            }
        }
    }

    /// Source time since the first data, s.
    pub fn elapsed_s(&self) -> f64 {
        self.state.elapsed_s()
    }
}
