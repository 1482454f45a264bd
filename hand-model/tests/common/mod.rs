//! Helpers shared by the integration tests: spectra and simple statistics.
#![allow(dead_code)]

/// In-place radix-2 FFT of (re, im); `re.len()` must be a power of two.
pub fn fft(re: &mut [f64], im: &mut [f64]) {
    let n = re.len();
    assert!(n.is_power_of_two() && im.len() == n);
    let mut j = 0;
    for i in 1..n {
        let mut bit = n >> 1;
        while j & bit != 0 {
            j ^= bit;
            bit >>= 1;
        }
        j |= bit;
        if i < j {
            re.swap(i, j);
            im.swap(i, j);
        }
    }
    let mut len = 2;
    while len <= n {
        let ang = -std::f64::consts::TAU / len as f64;
        for start in (0..n).step_by(len) {
            for k in 0..len / 2 {
                let (s, c) = (ang * k as f64).sin_cos();
                let (a, b) = (start + k, start + k + len / 2);
                let tr = re[b] * c - im[b] * s;
                let ti = re[b] * s + im[b] * c;
                re[b] = re[a] - tr;
                im[b] = im[a] - ti;
                re[a] += tr;
                im[a] += ti;
            }
        }
        len <<= 1;
    }
}

/// Welch power spectrum (Hann, `seg` points, 50 % overlap) of `x` after removing its mean.
pub fn welch(x: &[f64], seg: usize) -> Vec<f64> {
    let mean = x.iter().sum::<f64>() / x.len() as f64;
    let win: Vec<f64> = (0..seg)
        .map(|i| 0.5 - 0.5 * (std::f64::consts::TAU * i as f64 / seg as f64).cos())
        .collect();
    let mut psd = vec![0.0; seg / 2 + 1];
    let mut start = 0;
    while start + seg <= x.len() {
        let mut re: Vec<f64> = (0..seg).map(|i| (x[start + i] - mean) * win[i]).collect();
        let mut im = vec![0.0; seg];
        fft(&mut re, &mut im);
        for (k, p) in psd.iter_mut().enumerate() {
            *p += re[k] * re[k] + im[k] * im[k];
        }
        start += seg / 2;
    }
    psd
}

/// Median frequency (Hz) of `x` sampled at `fs`: the frequency splitting the power in half.
pub fn median_frequency(x: &[f64], fs: f64) -> f64 {
    let seg = 256;
    let psd = welch(x, seg);
    let total: f64 = psd[1..].iter().sum();
    let mut acc = 0.0;
    for (k, p) in psd.iter().enumerate().skip(1) {
        acc += p;
        if acc >= total / 2.0 {
            return k as f64 * fs / seg as f64;
        }
    }
    fs / 2.0
}

/// RMS of `x` about its mean.
pub fn rms_ac(x: &[f64]) -> f64 {
    let mean = x.iter().sum::<f64>() / x.len() as f64;
    (x.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / x.len() as f64).sqrt()
}

use hand_model::bus::{MemBus, MemEndpoint, Received};
use hand_model::clock::VirtualClock;
use hand_model::dbc::CanFrame;

/// A virtual-clock bus with a monitor endpoint that records everything.
pub struct Harness {
    pub clock: VirtualClock,
    pub bus: MemBus,
    pub monitor: MemEndpoint,
    pub log: Vec<Received>,
}

impl Harness {
    pub fn new() -> Self {
        let clock = VirtualClock::new();
        let bus = MemBus::with_clock(clock.clone()).with_capacity(1 << 20);
        let monitor = bus.endpoint();
        Self {
            clock,
            bus,
            monitor,
            log: Vec::new(),
        }
    }

    /// Runs `step(t)` every millisecond from the clock's time up to `until_us`, recording
    /// every frame seen by the monitor.
    pub fn run(&mut self, until_us: u64, mut step: impl FnMut(u64)) {
        let mut t = self.clock.now_us_value();
        while t <= until_us {
            self.clock.set_us(t);
            step(t);
            while let Some(r) = self.monitor.receive_timestamped() {
                self.log.push(r);
            }
            t += 1000;
        }
    }

    /// Recorded frames with id `id`, with receive times.
    pub fn with_id(&self, id: u32) -> Vec<(u64, CanFrame)> {
        self.log
            .iter()
            .filter(|r| r.frame.raw_id() == id)
            .map(|r| (r.time_us.expect("the harness bus has a clock"), r.frame))
            .collect()
    }
}

/// `Clock::now_us` without importing the trait in every test.
pub trait NowUs {
    fn now_us_value(&self) -> u64;
}

impl NowUs for VirtualClock {
    fn now_us_value(&self) -> u64 {
        use hand_model::clock::Clock;
        self.now_us()
    }
}
