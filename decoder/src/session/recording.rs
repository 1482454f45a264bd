//! The raw multi-channel signal of a session, from a candump log or a sample file.

/// Raw samples with their times.
#[derive(Debug, Clone, PartialEq)]
pub struct Recording {
    /// Channels per sample.
    pub channels: usize,
    /// Row-major `n x channels` raw values (µV for candump logs, file units for sample files).
    pub samples: Vec<f64>,
    /// Time of each sample, µs, non-decreasing.
    pub time_us: Vec<u64>,
    /// Samples the bus lost and the assembler bridged (0 for sample files).
    pub lost_samples: u64,
    /// Sample indices that follow a gap too long to bridge (over 20 ms): no window may span
    /// one, as the daemon would have marked it invalid.
    pub breaks: Vec<usize>,
    /// Frames dropped by the E2E check (wrong CRC or length) or refused by the codec (0 for
    /// sample files).
    pub bad_frames: u64,
    /// Sample units per stored raw unit: µV per LSB for a candump log, 1 for sample files
    /// (what `full_scale` is multiplied by).
    pub unit_per_raw: f64,
}

impl Recording {
    /// Builds a recording from evenly spaced samples (sample `i` at `i * 1e6 / rate` µs).
    pub fn from_samples(
        channels: usize,
        samples: Vec<f64>,
        sample_rate_hz: f64,
    ) -> Result<Self, String> {
        if channels == 0 || !samples.len().is_multiple_of(channels) {
            return Err(format!(
                "{} values is not a whole number of samples of {channels} channels",
                samples.len()
            ));
        }
        if let Some(i) = samples.iter().position(|v| !v.is_finite()) {
            return Err(format!(
                "sample {} channel {} is not finite",
                i / channels,
                i % channels
            ));
        }
        let n = samples.len() / channels;
        let time_us = (0..n)
            .map(|i| (i as f64 * 1e6 / sample_rate_hz).round() as u64)
            .collect();
        Ok(Recording {
            channels,
            samples,
            time_us,
            lost_samples: 0,
            breaks: Vec::new(),
            bad_frames: 0,
            unit_per_raw: 1.0,
        })
    }

    /// Number of multi-channel samples.
    pub fn len(&self) -> usize {
        self.time_us.len()
    }

    /// True when there is no sample.
    pub fn is_empty(&self) -> bool {
        self.time_us.is_empty()
    }

    /// Sample index range `[start, end)` of the samples timed in `[start_us, end_us)`.
    pub fn range_of(&self, start_us: u64, end_us: u64) -> std::ops::Range<usize> {
        let a = self.time_us.partition_point(|&t| t < start_us);
        let b = self.time_us.partition_point(|&t| t < end_us);
        a..b.max(a)
    }

    /// Samples `range` as a row-major slice.
    pub fn slice(&self, range: std::ops::Range<usize>) -> &[f64] {
        &self.samples[range.start * self.channels..range.end * self.channels]
    }
}
