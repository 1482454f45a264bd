//! The sEMG synthesiser: muscle activations in, one quantised 12-channel sample out.
//!
//! Per sample: each of the 10 sources draws white Gaussian noise, shapes it with a 2nd-order
//! Butterworth high-pass and low-pass (defaults 30 and 150 Hz, giving a median frequency near
//! 97 Hz, inside the 60..150 Hz of real forearm sEMG), scales it to unit RMS and then to
//! `max_rms_uv · activation^curvature`. The cross-talk matrix mixes the sources into the 12
//! channels; each channel then gets its mains residue, DC offset, slow drift and white noise
//! floor, and the ADC rounds to the LSB and clips to the signed 12-bit range, reporting which
//! channels clipped.

use super::biquad::{Biquad, BiquadKind};
use super::config::AmplifierConfig;
use super::mixing::{crosstalk_matrix, N_CHANNELS, N_SOURCES};
use super::noise::GaussianNoise;
use crate::error::SimError;

/// Smallest and largest ADC count (signed 12-bit), from hand.dbc.
pub use hand_dbc::hand::{ADC_MAX, ADC_MIN};

/// Activation of the 10 muscle sources, each in 0..=1 (see [`super::mixing::flexor`]).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Activation(pub [f64; N_SOURCES]);

/// One quantised sample of all channels.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct EmgSample {
    /// ADC counts per channel.
    pub counts: [i16; N_CHANNELS],
    /// Bit `c` set: channel `c` clipped at a rail in this sample.
    pub saturated: u16,
}

#[derive(Debug, Clone)]
struct MuscleSource {
    hp: Biquad,
    lp: Biquad,
    /// Makes the shaped noise unit-RMS, so `max_rms_uv` means what it says.
    norm: f64,
    noise: GaussianNoise,
}

impl MuscleSource {
    fn new(cfg: &AmplifierConfig, stream: u64) -> Self {
        let hp = Biquad::butterworth(BiquadKind::HighPass, cfg.band_low_hz, cfg.sample_rate_hz);
        let lp = Biquad::butterworth(BiquadKind::LowPass, cfg.band_high_hz, cfg.sample_rate_hz);
        // Output variance for unit white input = energy of the impulse response; both poles
        // are well inside the unit circle for validated cut-offs, so 2^15 taps converge.
        let (mut h, mut l) = (hp, lp);
        let mut energy = 0.0;
        for i in 0..(1 << 15) {
            let y = l.process(h.process(if i == 0 { 1.0 } else { 0.0 }));
            energy += y * y;
        }
        Self {
            hp,
            lp,
            norm: 1.0 / energy.sqrt(),
            noise: GaussianNoise::new(cfg.seed, stream),
        }
    }

    #[inline]
    fn next(&mut self) -> f64 {
        self.norm * self.lp.process(self.hp.process(self.noise.next_std()))
    }
}

/// Per-channel faults the synthesiser applies after mixing (set by the amplifier node's
/// fault plan).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct ChannelFaults {
    /// Bit `c`: electrode `c` has lost skin contact; the open input picks up mains at several
    /// times full scale, so the channel shows a clipped 50/60 Hz square wave.
    pub lead_off: u16,
    /// Bit `c`: channel `c` is driven into the positive rail (e.g. a large motion artefact).
    pub saturated: u16,
    /// Beyond the calibration (issue 25): every muscle contracts this many percent of what the
    /// calibration's full effort gave (a stronger grip than the technician recorded); `None`
    /// or 100 is as calibrated.
    pub effort_pct: Option<u16>,
    /// An electrode pop or a knock on one channel: `(channel, µs since it happened)`; the
    /// channel gets a step of [`POP_UV`] that decays with [`POP_TAU_US`].
    pub pop: Option<(u8, u64)>,
    /// The electrode band turned around the forearm by this many tenths of an electrode
    /// spacing (a sleeve that slipped): every muscle is seen through the shifted geometry.
    pub shift_tenths: i8,
}

/// An electrode pop's step, µV: 7.5 times a channel's full-effort RMS (160 counts) and below
/// the ADC's rail, so it reaches the decoder as signal, not as a saturation flag; a knocked
/// electrode's half-cell potential jumps like this.
pub const POP_UV: f64 = 1_200.0 * crate::dbc::EMG_LSB_UV;
/// How fast a pop's step decays back (the electrode's charge settling), µs.
pub const POP_TAU_US: f64 = 80_000.0;

/// The 12-channel sEMG generator. Allocation-free per sample.
#[derive(Debug, Clone)]
pub struct EmgSynth {
    cfg: AmplifierConfig,
    sources: [MuscleSource; N_SOURCES],
    mix: [[f64; N_SOURCES]; N_CHANNELS],
    /// The cross-talk matrix of a shifted band, and its shift (tenths of a spacing); built
    /// when a shift starts, so a sample never computes it.
    shifted: (i8, [[f64; N_SOURCES]; N_CHANNELS]),
    floor: [GaussianNoise; N_CHANNELS],
    offset_uv: [f64; N_CHANNELS],
    drift_w: [f64; N_CHANNELS],
    drift_phase: [f64; N_CHANNELS],
    mains_gain: [f64; N_CHANNELS],
    mains_phase: [f64; N_CHANNELS],
    n: u64,
}

impl EmgSynth {
    /// Builds the generator from a config that passes [`AmplifierConfig::validate`].
    pub fn try_new(cfg: AmplifierConfig) -> Result<Self, SimError> {
        cfg.validate()?;
        // Stream numbers: sources 0..10, channel floors 100..112, channel constants 200.
        let sources = std::array::from_fn(|s| MuscleSource::new(&cfg, s as u64));
        let floor = std::array::from_fn(|c| GaussianNoise::new(cfg.seed, 100 + c as u64));
        let mut consts = GaussianNoise::new(cfg.seed, 200);
        let mut offset_uv = [0.0; N_CHANNELS];
        let mut drift_w = [0.0; N_CHANNELS];
        let mut drift_phase = [0.0; N_CHANNELS];
        let mut mains_gain = [0.0; N_CHANNELS];
        let mut mains_phase = [0.0; N_CHANNELS];
        let tau = std::f64::consts::TAU;
        for c in 0..N_CHANNELS {
            offset_uv[c] = consts.uniform(-cfg.dc_offset_uv, cfg.dc_offset_uv);
            drift_w[c] = tau * cfg.drift_hz * consts.uniform(0.5, 1.5);
            drift_phase[c] = consts.uniform(0.0, tau);
            mains_gain[c] = consts.uniform(0.5, 1.0);
            mains_phase[c] = consts.uniform(0.0, tau);
        }
        let mix = crosstalk_matrix(cfg.crosstalk_width, 0.0);
        Ok(Self {
            mix,
            shifted: (0, mix),
            cfg,
            sources,
            floor,
            offset_uv,
            drift_w,
            drift_phase,
            mains_gain,
            mains_phase,
            n: 0,
        })
    }

    /// The config this generator was built from.
    pub fn config(&self) -> &AmplifierConfig {
        &self.cfg
    }

    /// The cross-talk matrix in use (row = channel, column = source).
    pub fn mixing(&self) -> &[[f64; N_SOURCES]; N_CHANNELS] {
        &self.mix
    }

    /// Samples produced so far.
    pub fn samples(&self) -> u64 {
        self.n
    }

    /// The next sample, in µV before quantisation, written into `uv`.
    pub fn next_uv(&mut self, act: &Activation, faults: ChannelFaults, uv: &mut [f64; N_CHANNELS]) {
        let t = self.n as f64 / self.cfg.sample_rate_hz;
        self.n += 1;
        let effort = f64::from(faults.effort_pct.unwrap_or(100)) / 100.0;
        if faults.shift_tenths != self.shifted.0 {
            let by = f64::from(faults.shift_tenths) / 10.0;
            self.shifted = (
                faults.shift_tenths,
                crosstalk_matrix(self.cfg.crosstalk_width, by),
            );
        }
        let mix = if faults.shift_tenths == 0 {
            &self.mix
        } else {
            &self.shifted.1
        };
        let mut src = [0.0; N_SOURCES];
        for (s, (out, a)) in src.iter_mut().zip(act.0.iter()).enumerate() {
            let amp = effort * self.cfg.max_rms_uv * a.clamp(0.0, 1.0).powf(self.cfg.curvature);
            // Every source draws its noise even at zero amplitude, so the random streams stay
            // aligned whatever the intents: same seed, same noise, different scripts comparable.
            *out = amp * self.sources[s].next();
        }
        let mains_w = std::f64::consts::TAU * self.cfg.mains.hz();
        let full_scale = f64::from(ADC_MAX) * self.cfg.lsb_uv;
        for (c, out) in uv.iter_mut().enumerate() {
            let emg: f64 = mix[c].iter().zip(src.iter()).map(|(g, x)| g * x).sum();
            let mains =
                self.cfg.mains_uv * self.mains_gain[c] * (mains_w * t + self.mains_phase[c]).sin();
            let drift = self.cfg.drift_uv * (self.drift_w[c] * t + self.drift_phase[c]).sin();
            let noise = self.cfg.noise_floor_uv * self.floor[c].next_std();
            let mut v = emg + mains + drift + noise + self.offset_uv[c];
            if let Some((ch, age_us)) = faults.pop {
                if usize::from(ch) == c {
                    v += POP_UV * (-(age_us as f64) / POP_TAU_US).exp();
                }
            }
            let bit = 1u16 << c;
            if faults.lead_off & bit != 0 {
                v = 4.0 * full_scale * (mains_w * t + self.mains_phase[c]).sin();
            }
            if faults.saturated & bit != 0 {
                v = 2.0 * full_scale;
            }
            *out = v;
        }
    }

    /// The next sample, quantised to the ADC's LSB and clipped to its range.
    pub fn next_sample(&mut self, act: &Activation, faults: ChannelFaults) -> EmgSample {
        let mut uv = [0.0; N_CHANNELS];
        self.next_uv(act, faults, &mut uv);
        quantise(&uv, self.cfg.lsb_uv)
    }
}

/// Rounds µV to ADC counts and clips to the signed 12-bit range, flagging clipped channels.
pub fn quantise(uv: &[f64; N_CHANNELS], lsb_uv: f64) -> EmgSample {
    let mut out = EmgSample::default();
    for (c, (&v, q)) in uv.iter().zip(out.counts.iter_mut()).enumerate() {
        let x = (v / lsb_uv).round();
        if x >= f64::from(ADC_MAX) {
            *q = ADC_MAX;
            out.saturated |= u16::from(x > f64::from(ADC_MAX)) << c;
        } else if x <= f64::from(ADC_MIN) {
            *q = ADC_MIN;
            out.saturated |= u16::from(x < f64::from(ADC_MIN)) << c;
        } else {
            *q = x as i16;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantiser_rounds_and_reports_clipping() {
        let mut uv = [0.0; N_CHANNELS];
        uv[0] = 1.4;
        uv[1] = -1.6;
        uv[2] = 1e9;
        uv[3] = -1e9;
        uv[4] = 2047.0;
        let s = quantise(&uv, 1.0);
        assert_eq!(&s.counts[..5], &[1, -2, 2047, -2048, 2047]);
        assert_eq!(
            s.saturated, 0b1100,
            "exactly-at-rail values are not clipping"
        );
    }

    /// RMS of channel `c` over `n` samples of `act` with `faults` (a fresh synthesiser, so
    /// runs with different faults see the same noise).
    fn rms(act: &Activation, faults: ChannelFaults, c: usize, n: usize) -> Vec<f64> {
        let mut s = EmgSynth::try_new(AmplifierConfig::default()).expect("config");
        let mut uv = [0.0; N_CHANNELS];
        (0..n)
            .map(|_| {
                s.next_uv(act, faults, &mut uv);
                uv[c]
            })
            .collect()
    }

    #[test]
    fn over_effort_scales_the_muscles_and_a_pop_decays_on_its_channel_alone() {
        let mut act = Activation::default();
        act.0[super::super::mixing::flexor(1)] = 1.0;
        let base = rms(&act, ChannelFaults::default(), 1, 2000);
        let twice = rms(
            &act,
            ChannelFaults {
                effort_pct: Some(200),
                ..ChannelFaults::default()
            },
            1,
            2000,
        );
        let as_calibrated = rms(
            &act,
            ChannelFaults {
                effort_pct: Some(100),
                ..ChannelFaults::default()
            },
            1,
            2000,
        );
        assert_eq!(base, as_calibrated, "100 % is the calibration, bit for bit");
        let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
        let ac = |v: &[f64]| {
            let m = mean(v);
            (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / v.len() as f64).sqrt()
        };
        let ratio = ac(&twice) / ac(&base);
        assert!(
            (1.9..=2.05).contains(&ratio),
            "2x effort gave {ratio:.3}x the RMS"
        );
        // A pop 20 ms old on channel 3: its step, decayed, on channel 3 only.
        let pop = ChannelFaults {
            pop: Some((3, 20_000)),
            ..ChannelFaults::default()
        };
        let quiet = Activation::default();
        let with = rms(&quiet, pop, 3, 1);
        let without = rms(&quiet, ChannelFaults::default(), 3, 1);
        let step = POP_UV * (-20_000.0 / POP_TAU_US).exp();
        assert!((with[0] - without[0] - step).abs() < 1e-9);
        assert_eq!(
            rms(&quiet, pop, 4, 1),
            rms(&quiet, ChannelFaults::default(), 4, 1)
        );
    }

    #[test]
    fn a_shifted_band_changes_what_each_channel_sees() {
        let mut act = Activation::default();
        act.0[super::super::mixing::flexor(0)] = 1.0;
        let shifted = ChannelFaults {
            shift_tenths: 5,
            ..ChannelFaults::default()
        };
        // Half a spacing on, channel 0 sits over the thumb flexor: it sees more of it.
        let a = rms(&act, ChannelFaults::default(), 0, 2000);
        let b = rms(&act, shifted, 0, 2000);
        let p = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>();
        assert!(p(&b) > 1.15 * p(&a), "{} vs {}", p(&b), p(&a));
    }
}
