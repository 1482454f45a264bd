//! Tick timing statistics with percentiles since start, in fixed memory.
//!
//! Samples in microseconds go into a log-linear histogram (exact below 64 µs, then 32 buckets
//! per power of two, so a percentile is within about 3% of the true value) that never allocates
//! after construction: it is updated in the tick.

/// Buckets per power of two above the linear range.
const SUB: u64 = 32;
/// Values below this are counted exactly.
const LINEAR: u64 = 2 * SUB;
/// Largest power of two covered (2^40 µs is about 12 days).
const OCTAVES: usize = 40;
const N_BUCKETS: usize = LINEAR as usize + (OCTAVES - 6) * SUB as usize;

/// A histogram of microsecond durations.
#[derive(Clone)]
pub struct Histogram {
    counts: Box<[u64; N_BUCKETS]>,
    total: u64,
    max: u64,
    sum: u128,
}

impl std::fmt::Debug for Histogram {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Histogram")
            .field("total", &self.total)
            .field("max", &self.max)
            .finish()
    }
}

impl Default for Histogram {
    fn default() -> Self {
        Self {
            counts: Box::new([0; N_BUCKETS]),
            total: 0,
            max: 0,
            sum: 0,
        }
    }
}

fn bucket_of(v: u64) -> usize {
    if v < LINEAR {
        return v as usize;
    }
    let octave = 63 - v.leading_zeros() as u64; // >= 6
    let shift = octave - 5; // keeps the 6 top bits: 32..63
    let idx = LINEAR + (octave - 6) * SUB + ((v >> shift) - SUB);
    (idx as usize).min(N_BUCKETS - 1)
}

fn bucket_low(i: usize) -> u64 {
    let i = i as u64;
    if i < LINEAR {
        return i;
    }
    let octave = (i - LINEAR) / SUB + 6;
    let mant = (i - LINEAR) % SUB + SUB;
    mant << (octave - 5)
}

impl Histogram {
    /// Count one duration.
    pub fn record(&mut self, us: u64) {
        self.counts[bucket_of(us)] += 1;
        self.total += 1;
        self.max = self.max.max(us);
        self.sum += u128::from(us);
    }

    /// Number of samples.
    pub fn count(&self) -> u64 {
        self.total
    }

    /// Largest sample.
    pub fn max(&self) -> u64 {
        self.max
    }

    /// Mean, or 0 when empty.
    pub fn mean(&self) -> f64 {
        if self.total == 0 {
            0.0
        } else {
            self.sum as f64 / self.total as f64
        }
    }

    /// The `q`-quantile (0..=1), as the lower edge of its bucket (never above the maximum);
    /// 0 when empty.
    pub fn quantile(&self, q: f64) -> u64 {
        if self.total == 0 {
            return 0;
        }
        let rank = ((q.clamp(0.0, 1.0) * self.total as f64).ceil() as u64).max(1);
        let mut seen = 0;
        for (i, c) in self.counts.iter().enumerate() {
            seen += c;
            if seen >= rank {
                return bucket_low(i).min(self.max);
            }
        }
        self.max
    }

    /// Median, p99 and maximum, the figures `handctl status` shows.
    pub fn summary(&self) -> Percentiles {
        Percentiles {
            count: self.total,
            p50_us: self.quantile(0.5),
            p99_us: self.quantile(0.99),
            max_us: self.max,
        }
    }
}

/// A summary of a [`Histogram`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
pub struct Percentiles {
    /// Samples.
    pub count: u64,
    /// Median, µs.
    pub p50_us: u64,
    /// 99th percentile, µs.
    pub p99_us: u64,
    /// Maximum, µs.
    pub max_us: u64,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn buckets_are_monotonic_and_tight() {
        let mut last = 0;
        for v in (0..2_000_000u64).step_by(7) {
            let b = bucket_of(v);
            assert!(b >= last, "bucket order at {v}");
            last = b;
            let lo = bucket_low(b);
            assert!(lo <= v, "{v} below its bucket's low edge {lo}");
            assert!((v - lo) as f64 <= v as f64 / 32.0 + 1.0, "{v} vs {lo}");
        }
    }

    #[test]
    fn quantiles_of_a_known_distribution() {
        let mut h = Histogram::default();
        for v in 1..=1000u64 {
            h.record(v);
        }
        assert_eq!(h.count(), 1000);
        assert_eq!(h.max(), 1000);
        assert!((h.mean() - 500.5).abs() < 1e-9);
        let p50 = h.quantile(0.5) as f64;
        let p99 = h.quantile(0.99) as f64;
        assert!((p50 - 500.0).abs() <= 500.0 / 32.0 + 1.0, "p50 {p50}");
        assert!((p99 - 990.0).abs() <= 990.0 / 32.0 + 1.0, "p99 {p99}");
        // 1000 lies in the bucket [992, 1024).
        assert_eq!(h.quantile(1.0), 992);
        assert_eq!(Histogram::default().quantile(0.5), 0);
    }

    #[test]
    fn huge_values_land_in_the_last_bucket() {
        let mut h = Histogram::default();
        h.record(u64::MAX);
        assert_eq!(h.quantile(0.5), bucket_low(N_BUCKETS - 1));
    }
}
