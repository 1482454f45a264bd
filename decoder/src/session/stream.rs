//! Every feature window of a session's recording, labelled or not: what `handctl decode` runs a
//! model on. The same path as the labelled windows ([`Session::windows`]): each segment through
//! [`try_batch_features`] from reset state, and no window that spans a break in the recording.

use super::error::SessionError;
use super::Session;
use crate::dsp::try_batch_features;

/// Feature rows of the whole recording, in time order.
#[derive(Debug, Clone, PartialEq)]
pub struct StreamWindows {
    /// Features per row.
    pub n_features: usize,
    /// Samples per window.
    pub window_len: usize,
    /// Row-major features, `len() x n_features`.
    pub features: Vec<f64>,
    /// Exclusive end of each window, as a sample index of the recording.
    pub end_sample: Vec<usize>,
    /// Time of each window's newest sample (`end_sample - 1`), µs: when the daemon would have
    /// computed this output.
    pub time_us: Vec<u64>,
}

impl StreamWindows {
    /// Number of windows.
    pub fn len(&self) -> usize {
        self.end_sample.len()
    }

    /// True when there is no window.
    pub fn is_empty(&self) -> bool {
        self.end_sample.is_empty()
    }
}

impl Session {
    /// Every window of the recording, one per step once a segment's first window is full.
    pub fn stream_windows(&self) -> Result<StreamWindows, SessionError> {
        let settings = self.meta.chain.validate()?;
        let wl = settings.window_len();
        let mut out = StreamWindows {
            n_features: settings.n_features(),
            window_len: wl,
            features: Vec::new(),
            end_sample: Vec::new(),
            time_us: Vec::new(),
        };
        for seg in self.segment_ranges() {
            let m = try_batch_features(&settings, self.recording.slice(seg.clone()))
                .map_err(|e| SessionError::recording(&self.name, e.to_string()))?;
            for r in 0..m.n_rows {
                let end = seg.start + settings.window_end(r);
                let begin = end - wl;
                if self.recording.breaks.iter().any(|&b| b > begin && b < end) {
                    continue;
                }
                out.features.extend_from_slice(m.row(r));
                out.end_sample.push(end);
                out.time_us.push(self.recording.time_us[end - 1]);
            }
        }
        if out.is_empty() {
            return Err(SessionError::recording(
                &self.name,
                format!(
                    "the recording ({} samples) is shorter than one window ({wl} samples)",
                    self.recording.len()
                ),
            ));
        }
        Ok(out)
    }
}
