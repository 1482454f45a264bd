//! Per-channel fault counters of a [`super::Chain`].

/// Largest magnitude a sample may have. Anything beyond is no EMG (an amplifier's full scale is
/// a few 1e5 µV) and would risk overflowing the squared sums of the features, so it is treated
/// like a non-finite sample.
pub const MAX_ABS_SAMPLE: f64 = 1e12;

/// What went wrong on which channel since the last [`super::Chain::reset`].
///
/// A bad sample (NaN, infinite, or beyond [`MAX_ABS_SAMPLE`]) is counted here, resets that
/// channel's filter state and enters the filter as 0. The features stay finite throughout;
/// [`Faults::in_window`] tells whether the current window of a channel still contains one.
///
/// Known limit: the filters restart from rest, so on a channel with a large DC offset the
/// restart is a step that the 1 Hz DC high-pass takes about a second to forget, longer than
/// the window flag lasts. Upstream, lost samples are better bridged (held) than sent as NaN.
#[derive(Debug, Clone, PartialEq)]
pub struct Faults {
    non_finite: Vec<u64>,
    out_of_range: Vec<u64>,
    /// Sample number (1-based, since reset) of the channel's last bad sample; 0 = none.
    last_bad: Vec<u64>,
    /// Number of the sample being pushed.
    now: u64,
    window_len: usize,
    wrong_length: u64,
}

impl Faults {
    pub(crate) fn new(n_channels: usize, window_len: usize) -> Self {
        Faults {
            non_finite: vec![0; n_channels],
            out_of_range: vec![0; n_channels],
            last_bad: vec![0; n_channels],
            now: 0,
            window_len,
            wrong_length: 0,
        }
    }

    pub(crate) fn clear(&mut self) {
        self.non_finite.fill(0);
        self.out_of_range.fill(0);
        self.last_bad.fill(0);
        self.now = 0;
        self.wrong_length = 0;
    }

    /// Sets the number (1-based) of the sample being pushed, before anything is recorded.
    #[inline]
    pub(crate) fn set_now(&mut self, now: u64) {
        self.now = now;
    }

    /// Whether a bad sample numbered `at` is among the last `window_len` samples.
    fn is_recent(&self, at: u64) -> bool {
        at != 0 && self.now - at < self.window_len as u64
    }

    #[inline]
    pub(crate) fn record_non_finite(&mut self, ch: usize) {
        self.non_finite[ch] += 1;
        self.last_bad[ch] = self.now;
    }

    #[inline]
    pub(crate) fn record_out_of_range(&mut self, ch: usize) {
        self.out_of_range[ch] += 1;
        self.last_bad[ch] = self.now;
    }

    #[inline]
    pub(crate) fn record_wrong_length(&mut self) {
        self.wrong_length += 1;
    }

    /// NaN or infinite samples on channel `ch` (0 for a channel that does not exist).
    pub fn non_finite(&self, ch: usize) -> u64 {
        self.non_finite.get(ch).copied().unwrap_or(0)
    }

    /// Finite samples beyond [`MAX_ABS_SAMPLE`] on channel `ch`.
    pub fn out_of_range(&self, ch: usize) -> u64 {
        self.out_of_range.get(ch).copied().unwrap_or(0)
    }

    /// All bad samples on channel `ch`.
    pub fn bad_samples(&self, ch: usize) -> u64 {
        self.non_finite(ch) + self.out_of_range(ch)
    }

    /// Per-channel counts of NaN or infinite samples.
    pub fn non_finite_counts(&self) -> &[u64] {
        &self.non_finite
    }

    /// Per-channel counts of out-of-range samples.
    pub fn out_of_range_counts(&self) -> &[u64] {
        &self.out_of_range
    }

    /// Pushes whose slice did not have one value per channel (missing values count as
    /// non-finite on their channel, extra values are ignored).
    pub fn wrong_length(&self) -> u64 {
        self.wrong_length
    }

    /// Every bad sample on every channel, plus wrong-length pushes.
    pub fn total(&self) -> u64 {
        self.non_finite.iter().sum::<u64>()
            + self.out_of_range.iter().sum::<u64>()
            + self.wrong_length
    }

    /// Whether the current window of channel `ch` still holds a bad sample (its features are
    /// finite but describe a patched signal).
    pub fn in_window(&self, ch: usize) -> bool {
        self.last_bad.get(ch).is_some_and(|&at| self.is_recent(at))
    }

    /// Whether any channel's current window holds a bad sample.
    pub fn any_in_window(&self) -> bool {
        self.last_bad.iter().any(|&at| self.is_recent(at))
    }
}
