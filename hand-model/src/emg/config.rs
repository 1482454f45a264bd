//! The amplifier's signal model parameters, checked once.

use serde::{Deserialize, Serialize};

use crate::error::{check_range, SimError};

/// Mains frequency of the country the patient lives in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Mains {
    /// 50 Hz (Europe, most of Asia and Africa).
    Hz50,
    /// 60 Hz (the Americas, parts of Asia).
    Hz60,
}

impl Mains {
    /// The frequency in Hz.
    pub fn hz(self) -> f64 {
        match self {
            Mains::Hz50 => 50.0,
            Mains::Hz60 => 60.0,
        }
    }
}

/// What the simulated amplifier adds up, in µV at the electrode.
///
/// Defaults give, at the DBC's 12-bit resolution, a rest signal of a few LSB RMS and a
/// whole-hand maximal contraction that uses about a quarter of the range (RMS), so that
/// saturation happens only when a fault asks for it or a config turns the gain up.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AmplifierConfig {
    /// Seed of every random stream in the amplifier: same seed, same samples.
    pub seed: u64,
    /// Sample rate in Hz (hand.dbc: 1 kHz).
    pub sample_rate_hz: f64,
    /// ADC resolution: µV per count (hand.dbc's EMG factor).
    pub lsb_uv: f64,
    /// RMS in µV of one muscle source at full activation, seen by an electrode right over it.
    pub max_rms_uv: f64,
    /// Exponent of amplitude vs activation: `rms = max_rms_uv · activation^curvature`.
    /// 1 is linear; sEMG amplitude vs force is near-linear, slightly convex for small muscles.
    pub curvature: f64,
    /// Lower edge (Butterworth, 2nd order) of the muscle signal's band in Hz.
    pub band_low_hz: f64,
    /// Upper edge (Butterworth, 2nd order) of the muscle signal's band in Hz.
    pub band_high_hz: f64,
    /// Cross-talk width in electrode spacings (see [`crate::emg::mixing`]).
    pub crosstalk_width: f64,
    /// Mains frequency.
    pub mains: Mains,
    /// Peak amplitude of the mains residue in µV (scaled per channel by 0.5..1).
    pub mains_uv: f64,
    /// Largest absolute DC offset of a channel in µV (each channel draws one in ±this).
    pub dc_offset_uv: f64,
    /// Peak amplitude of the slow baseline drift in µV.
    pub drift_uv: f64,
    /// Typical drift frequency in Hz (each channel draws one in 0.5..1.5 × this).
    pub drift_hz: f64,
    /// Electrode and amplifier white noise, RMS in µV, on every channel.
    pub noise_floor_uv: f64,
}

impl Default for AmplifierConfig {
    fn default() -> Self {
        Self {
            seed: 1,
            sample_rate_hz: 1000.0,
            lsb_uv: crate::dbc::EMG_LSB_UV,
            max_rms_uv: 160.0 * crate::dbc::EMG_LSB_UV,
            curvature: 1.2,
            band_low_hz: 30.0,
            band_high_hz: 150.0,
            crosstalk_width: 1.0,
            mains: Mains::Hz50,
            mains_uv: 2.0 * crate::dbc::EMG_LSB_UV,
            dc_offset_uv: 20.0 * crate::dbc::EMG_LSB_UV,
            drift_uv: 4.0 * crate::dbc::EMG_LSB_UV,
            drift_hz: 0.1,
            noise_floor_uv: 1.5 * crate::dbc::EMG_LSB_UV,
        }
    }
}

impl AmplifierConfig {
    /// Checks every parameter; the synthesiser is built only from a config that passed.
    pub fn validate(&self) -> Result<(), SimError> {
        check_range(
            "sample_rate_hz",
            self.sample_rate_hz,
            100.0,
            20_000.0,
            "100..=20000 Hz",
        )?;
        check_range("lsb_uv", self.lsb_uv, 1e-6, 1e6, "1e-6..=1e6 µV")?;
        check_range("max_rms_uv", self.max_rms_uv, 0.0, 1e7, "0..=1e7 µV")?;
        check_range("curvature", self.curvature, 0.25, 4.0, "0.25..=4")?;
        let nyq = self.sample_rate_hz / 2.0;
        check_range(
            "band_low_hz",
            self.band_low_hz,
            1.0,
            nyq * 0.9,
            "1 Hz..0.45·fs",
        )?;
        check_range(
            "band_high_hz",
            self.band_high_hz,
            self.band_low_hz * 1.5,
            nyq * 0.9,
            "1.5·band_low_hz..0.45·fs",
        )?;
        check_range(
            "crosstalk_width",
            self.crosstalk_width,
            0.1,
            12.0,
            "0.1..=12 spacings",
        )?;
        check_range("mains_uv", self.mains_uv, 0.0, 1e7, "0..=1e7 µV")?;
        check_range("dc_offset_uv", self.dc_offset_uv, 0.0, 1e7, "0..=1e7 µV")?;
        check_range("drift_uv", self.drift_uv, 0.0, 1e7, "0..=1e7 µV")?;
        check_range("drift_hz", self.drift_hz, 0.0, 5.0, "0..=5 Hz")?;
        check_range(
            "noise_floor_uv",
            self.noise_floor_uv,
            0.0,
            1e7,
            "0..=1e7 µV",
        )?;
        Ok(())
    }

    /// The rest-signal RMS (µV) this config promises on any channel once the DC offset is
    /// removed: noise floor, mains residue, drift, quantisation and the patient's tonic
    /// activity at `tonic` (0..1) summed in power, each at its worst case (full mains and drift
    /// gain, every source's cross-talk gain). The tests hold the measured rest RMS to this.
    pub fn rest_rms_bound_uv(&self, tonic: f64) -> f64 {
        let m = crate::emg::mixing::crosstalk_matrix(self.crosstalk_width, 0.0);
        let max_gain2 = m
            .iter()
            .map(|row| row.iter().map(|g| g * g).sum::<f64>())
            .fold(0.0, f64::max);
        let tonic_rms = self.max_rms_uv * tonic.clamp(0.0, 1.0).powf(self.curvature);
        (self.noise_floor_uv.powi(2)
            + self.mains_uv.powi(2) / 2.0
            + self.drift_uv.powi(2) / 2.0
            + self.lsb_uv.powi(2) / 12.0
            + tonic_rms.powi(2) * max_gain2)
            .sqrt()
    }
}
