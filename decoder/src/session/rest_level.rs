//! The calibration's rest level: per channel, the RMS of the band-passed signal averaged over
//! the rest windows. A model file keeps it so that a live monitor can draw the patient's
//! relaxed baseline beside the signal.

use super::trial::{Trial, TrialKind};
use super::windows::LabelledWindows;
use crate::dsp::{FEATURES_PER_CHANNEL, RMS_FEATURE};

impl LabelledWindows {
    /// Per channel, the mean of the RMS feature over the windows of rest trials, in the
    /// recording's units (µV for a session recorded from the bus). None when no window
    /// belongs to a rest trial (a session without rest, or two-point windows). `trials` are
    /// the session's, indexed as the labels index them; a label naming no trial is skipped.
    pub fn rest_rms(&self, trials: &[Trial]) -> Option<Vec<f64>> {
        let channels = self.n_features / FEATURES_PER_CHANNEL;
        let mut sum = vec![0.0; channels];
        let mut n = 0usize;
        for (i, l) in self.labels.iter().enumerate() {
            if trials.get(l.trial).map(|t| t.kind) != Some(TrialKind::Rest) {
                continue;
            }
            let row = self.row(i);
            for (c, s) in sum.iter_mut().enumerate() {
                *s += row[c * FEATURES_PER_CHANNEL + RMS_FEATURE];
            }
            n += 1;
        }
        (n > 0).then(|| sum.into_iter().map(|s| s / n as f64).collect())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::session::WindowLabel;

    fn trial(id: u32, kind: TrialKind) -> Trial {
        Trial {
            id,
            finger: None,
            kind,
            repetition: 1,
            start_us: 0,
            end_us: 1,
        }
    }

    /// Two channels; window `i` has RMS `rms[i]` on both channels scaled by (1, 10) and every
    /// other feature 1000 (never averaged).
    fn windows(trials: &[usize], rms: &[f64]) -> LabelledWindows {
        let mut features = Vec::new();
        for r in rms {
            for scale in [1.0, 10.0] {
                let mut ch = [1000.0; FEATURES_PER_CHANNEL];
                ch[RMS_FEATURE] = r * scale;
                features.extend_from_slice(&ch);
            }
        }
        LabelledWindows {
            n_features: 2 * FEATURES_PER_CHANNEL,
            features,
            labels: trials
                .iter()
                .map(|&trial| WindowLabel {
                    trial,
                    targets: [0.0; 5],
                    mask: [true; 5],
                    end_sample: 0,
                })
                .collect(),
        }
    }

    #[test]
    fn the_mean_rms_of_the_rest_windows_per_channel() {
        let trials = [
            trial(1, TrialKind::Rest),
            trial(2, TrialKind::Flexion),
            trial(3, TrialKind::Rest),
        ];
        let w = windows(&[0, 1, 2, 0, 1], &[2.0, 500.0, 5.0, 8.0, 700.0]);
        let got = w.rest_rms(&trials).expect("rest windows");
        assert_eq!(got, vec![5.0, 50.0]);
        let no_rest = windows(&[1, 1], &[500.0, 700.0]);
        assert_eq!(no_rest.rest_rms(&trials), None);
    }
}
