//! Labelled feature windows: a session cut into the rows a model trains and is scored on.

use super::error::SessionError;
use super::trial::{TrialKind, N_FINGERS};
use super::Session;
use crate::dsp::try_batch_features;

/// How windows are labelled.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct WindowOptions {
    /// The paper's two-point calibration: flexion (+1) and extension (-1) only, rest trials
    /// left out. Without a rest anchor, rest drifts away from zero; kept to reproduce the paper.
    pub two_point: bool,
    /// The paper's labels: during a single-finger trial the other fingers are masked out of the
    /// loss. By default (false) they are trained toward 0, the patient's intent, so a finger
    /// the trial does not move learns to stay still instead of following the one that moves.
    pub mask_others: bool,
}

impl WindowOptions {
    /// The loss mask of a trial's windows: all five fingers, or with
    /// [`WindowOptions::mask_others`] the fingers the trial moves.
    pub fn mask(&self, trial: &super::Trial) -> [bool; N_FINGERS] {
        if self.mask_others {
            trial.involved()
        } else {
            [true; N_FINGERS]
        }
    }
}

/// The label of one window.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WindowLabel {
    /// Index of the trial in [`super::SessionMeta::trials`].
    pub trial: usize,
    /// Per-finger targets: +1 flexion, -1 extension, 0 rest.
    pub targets: [f64; N_FINGERS],
    /// Fingers whose target counts: all five, or with [`WindowOptions::mask_others`] the trial's
    /// finger alone (all five for rest and "all" trials).
    pub mask: [bool; N_FINGERS],
    /// Exclusive end of the window, as a sample index of the recording.
    pub end_sample: usize,
}

/// Feature rows and their labels.
#[derive(Debug, Clone, PartialEq)]
pub struct LabelledWindows {
    /// Features per row.
    pub n_features: usize,
    /// Row-major features, `labels.len() x n_features`.
    pub features: Vec<f64>,
    /// One label per row.
    pub labels: Vec<WindowLabel>,
}

impl LabelledWindows {
    /// Number of windows.
    pub fn len(&self) -> usize {
        self.labels.len()
    }

    /// True when there is no window.
    pub fn is_empty(&self) -> bool {
        self.labels.is_empty()
    }

    /// Features of window `i`.
    pub fn row(&self, i: usize) -> &[f64] {
        &self.features[i * self.n_features..(i + 1) * self.n_features]
    }

    /// The windows whose trial satisfies `keep` (by trial index).
    pub fn filter_trials(&self, keep: impl Fn(usize) -> bool) -> LabelledWindows {
        let mut out = LabelledWindows {
            n_features: self.n_features,
            features: Vec::new(),
            labels: Vec::new(),
        };
        for (i, l) in self.labels.iter().enumerate() {
            if keep(l.trial) {
                out.features.extend_from_slice(self.row(i));
                out.labels.push(*l);
            }
        }
        out
    }
}

impl Session {
    /// Cuts the session into labelled windows. Each segment is filtered on its own from reset
    /// state, exactly as the streaming chain would see it; a window belongs to a trial when it
    /// lies wholly inside the trial, after the onset skip.
    pub fn windows(&self, opts: &WindowOptions) -> Result<LabelledWindows, SessionError> {
        let settings = self.meta.chain.validate()?;
        let skip = (self.meta.onset_skip_ms * settings.sample_rate_hz() / 1000.0).round() as usize;
        let wl = settings.window_len();
        let mut out = LabelledWindows {
            n_features: settings.n_features(),
            features: Vec::new(),
            labels: Vec::new(),
        };
        let used: Vec<usize> = (0..self.meta.trials.len())
            .filter(|&i| !(opts.two_point && self.meta.trials[i].kind == TrialKind::Rest))
            .collect();
        for (seg_index, seg) in self.segment_ranges().into_iter().enumerate() {
            // Sample ranges of the trials in this segment.
            let trials: Vec<(usize, std::ops::Range<usize>)> = used
                .iter()
                .filter(|&&i| self.meta.segment_of(&self.meta.trials[i]) == Some(seg_index))
                .map(|&i| {
                    let t = &self.meta.trials[i];
                    (i, self.recording.range_of(t.start_us, t.end_us))
                })
                .collect();
            if trials.is_empty() {
                continue;
            }
            let m = try_batch_features(&settings, self.recording.slice(seg.clone()))
                .map_err(|e| SessionError::recording(&self.name, e.to_string()))?;
            debug_assert_eq!(m.n_cols, out.n_features);
            for r in 0..m.n_rows {
                let end = seg.start + settings.window_end(r);
                let begin = end - wl;
                let Some((ti, _)) = trials
                    .iter()
                    .find(|(_, range)| begin >= range.start + skip && end <= range.end)
                else {
                    continue;
                };
                if self.recording.breaks.iter().any(|&b| b > begin && b < end) {
                    continue;
                }
                let t = &self.meta.trials[*ti];
                out.features.extend_from_slice(m.row(r));
                out.labels.push(WindowLabel {
                    trial: *ti,
                    targets: t.targets(),
                    mask: opts.mask(t),
                    end_sample: end,
                });
            }
        }
        if out.is_empty() {
            return Err(SessionError::recording(
                &self.name,
                "no window lies inside any trial: trials shorter than a window, or times outside the recording",
            ));
        }
        Ok(out)
    }

    /// Sample ranges of the segments (one covering everything when none is declared).
    pub fn segment_ranges(&self) -> Vec<std::ops::Range<usize>> {
        if self.meta.segments.is_empty() {
            std::iter::once(0..self.recording.len()).collect()
        } else {
            self.meta
                .segments
                .iter()
                .map(|s| self.recording.range_of(s.start_us, s.end_us))
                .collect()
        }
    }
}

impl LabelledWindows {
    /// The windows as a training set for [`crate::model::train`] (trial = index in the
    /// session's trial list, so the model's held-out split is by trial).
    pub fn to_dataset(
        &self,
        chain: &crate::dsp::ChainConfig,
    ) -> Result<crate::model::Dataset, crate::model::TrainError> {
        let mut d = crate::model::Dataset::new(chain.clone())?;
        for (i, l) in self.labels.iter().enumerate() {
            d.push(self.row(i), l.targets, l.mask, l.trial)?;
        }
        Ok(d)
    }
}

impl Session {
    /// Trials held out for testing when a session must serve for both training and testing:
    /// the last repetition of every (finger, kind) that has at least two. Returns a flag per
    /// trial index, true = test.
    pub fn holdout_last_repetition(&self) -> Vec<bool> {
        let trials = &self.meta.trials;
        trials
            .iter()
            .map(|t| {
                let group: Vec<u32> = trials
                    .iter()
                    .filter(|o| o.kind == t.kind && o.finger == t.finger)
                    .map(|o| o.repetition)
                    .collect();
                group.len() >= 2
                    && group.iter().all(|&r| r <= t.repetition)
                    && group.iter().filter(|&&r| r == t.repetition).count() == 1
            })
            .collect()
    }
}
