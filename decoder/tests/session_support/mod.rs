//! A synthetic calibration session for the session and evaluation tests: 4 channels at
//! 1 kHz; flexion of finger 0 drives channel 0, its extension channel 1; finger 1 drives
//! channels 2 and 3; rest is low noise everywhere.

#![allow(dead_code)]

use std::path::{Path, PathBuf};

use decoder::dsp::ChainConfig;
use decoder::session::{
    write_npy_f64, RecordingFormat, RecordingSpec, SessionMeta, Trial, TrialKind,
};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

pub const CHANNELS: usize = 4;
pub const RATE: f64 = 1000.0;
pub const TRIAL_SAMPLES: usize = 2000;
pub const REST_AMP: f64 = 5.0;
pub const ACTIVE_AMP: f64 = 100.0;

/// One synthetic trial: what it is and how each channel is scaled.
#[derive(Clone, Debug)]
pub struct SynthTrial {
    pub finger: Option<usize>,
    pub kind: TrialKind,
    pub repetition: u32,
    pub amps: [f64; CHANNELS],
}

/// The clean protocol: rest, then flexion and extension of fingers 0 and 1, twice each.
pub fn clean_protocol() -> Vec<SynthTrial> {
    let mut v = Vec::new();
    for rep in 1..=2 {
        v.push(SynthTrial {
            finger: None,
            kind: TrialKind::Rest,
            repetition: rep,
            amps: [REST_AMP; 4],
        });
        for f in 0..2 {
            for (k, kind) in [TrialKind::Flexion, TrialKind::Extension]
                .into_iter()
                .enumerate()
            {
                let mut amps = [REST_AMP; 4];
                amps[2 * f + k] = ACTIVE_AMP;
                // Cross-talk into the antagonist channel, as real forearms show.
                amps[2 * f + 1 - k] = 0.3 * ACTIVE_AMP;
                v.push(SynthTrial {
                    finger: Some(f),
                    kind,
                    repetition: rep,
                    amps,
                });
            }
        }
    }
    v
}

fn gauss(rng: &mut ChaCha8Rng) -> f64 {
    let u1: f64 = rng.gen_range(1e-12..1.0);
    let u2: f64 = rng.gen_range(0.0..1.0);
    (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
}

/// Samples (row-major) and metadata for `trials`, laid end to end in one recording.
pub fn synth(trials: &[SynthTrial], seed: u64) -> (Vec<f64>, SessionMeta) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut samples = Vec::new();
    let mut meta_trials = Vec::new();
    for (i, t) in trials.iter().enumerate() {
        let start = i * TRIAL_SAMPLES;
        for _ in 0..TRIAL_SAMPLES {
            for a in t.amps {
                samples.push((a * gauss(&mut rng)).round());
            }
        }
        meta_trials.push(Trial {
            id: i as u32 + 1,
            finger: t.finger,
            kind: t.kind,
            repetition: t.repetition,
            start_us: (start as f64 * 1e6 / RATE) as u64,
            end_us: ((start + TRIAL_SAMPLES) as f64 * 1e6 / RATE) as u64,
        });
    }
    let meta = SessionMeta {
        chain: ChainConfig {
            channels: CHANNELS,
            sample_rate_hz: RATE,
            ..ChainConfig::default()
        },
        onset_skip_ms: 0.0,
        recording: RecordingSpec {
            format: RecordingFormat::Npy,
            file: PathBuf::from("samples.npy"),
            full_scale: Some(2047.0),
        },
        segments: Vec::new(),
        trials: meta_trials,
        reference: None,
        recorded_utc: None,
    };
    (samples, meta)
}

/// Writes a session directory and returns it.
pub fn write_session(dir: &Path, trials: &[SynthTrial], seed: u64) -> SessionMeta {
    let (samples, meta) = synth(trials, seed);
    std::fs::create_dir_all(dir).unwrap();
    write_npy_f64(
        &dir.join("samples.npy"),
        samples.len() / CHANNELS,
        CHANNELS,
        &samples,
    )
    .unwrap();
    meta.write(dir).unwrap();
    meta
}

/// A fresh empty temporary directory for one test.
pub fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("handstack-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}
