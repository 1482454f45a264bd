//! The simulated sEMG: muscle sources, cross-talk, interference and the ADC.

pub mod biquad;
pub mod config;
pub mod mixing;
pub mod noise;
pub mod synth;

pub use config::{AmplifierConfig, Mains};
pub use mixing::{crosstalk_matrix, extensor, flexor, N_CHANNELS, N_SOURCES};
pub use synth::{
    quantise, Activation, ChannelFaults, EmgSample, EmgSynth, ADC_MAX, ADC_MIN, POP_TAU_US, POP_UV,
};
