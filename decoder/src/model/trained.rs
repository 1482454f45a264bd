//! A trained decoder as deployed: the model, its normalizer, the signal chain configuration its
//! features came from, and what training did. [`Predictor`] runs it in the daemon's tick.

use crate::dsp::{ChainConfig, FEATURES_PER_CHANNEL};

use super::any::AnyModel;
use super::dataset::N_FINGERS;
use super::envelope::Envelope;
use super::error::ModelError;
use super::normalizer::Normalizer;
use super::output::OutputStage;
use super::provenance::Provenance;
use super::rest::RestStage;
use super::spec::ModelSpec;
use super::summary::TrainingSummary;
use super::taught::Taught;
use super::traits::{Model, Scratch, Trainable};
use super::verify::VerificationRecord;

/// Model + normalizer + chain configuration + training summary (what a model file holds), and
/// optionally the verification of its calibration rays, the calibration's rest level, the
/// rest stage applied to the outputs and the calibration's provenance (patient, session, date).
#[derive(Debug, Clone, PartialEq)]
pub struct TrainedModel {
    pub(crate) model: AnyModel,
    pub(crate) spec: ModelSpec,
    pub(crate) normalizer: Normalizer,
    pub(crate) chain: ChainConfig,
    pub(crate) summary: TrainingSummary,
    pub(crate) verification: Option<VerificationRecord>,
    pub(crate) rest_rms_uv: Option<Vec<f64>>,
    pub(crate) rest_stage: Option<RestStage>,
    pub(crate) envelope: Option<Envelope>,
    pub(crate) provenance: Option<Provenance>,
    pub(crate) taught: Taught,
}

impl TrainedModel {
    /// Bundles the parts, checking that they fit together: 5 outputs, the model's tensors match
    /// `spec`, and model input = normalizer length = [`FEATURES_PER_CHANNEL`] × the chain's
    /// channels.
    pub fn new(
        model: AnyModel,
        spec: ModelSpec,
        normalizer: Normalizer,
        chain: ChainConfig,
        summary: TrainingSummary,
    ) -> Result<Self, ModelError> {
        let n_in = FEATURES_PER_CHANNEL * chain.channels;
        let shape = |what: &str, expected: usize, found: usize| {
            if expected == found {
                Ok(())
            } else {
                Err(ModelError::Shape {
                    what: what.to_string(),
                    expected,
                    found,
                })
            }
        };
        shape(
            &format!("model inputs ({FEATURES_PER_CHANNEL} x chain channels)"),
            n_in,
            model.n_inputs(),
        )?;
        shape("normalizer length", n_in, normalizer.len())?;
        shape("model outputs (fingers)", N_FINGERS, model.n_outputs())?;
        let expected = AnyModel::expected_tensors(model.kind(), &spec, n_in, N_FINGERS)?;
        if expected != model.tensors() {
            return Err(ModelError::InvalidSpec(format!(
                "the {} model's tensors do not match its specification",
                model.kind()
            )));
        }
        if summary.kind != model.kind() {
            return Err(ModelError::InvalidSpec(format!(
                "training summary is for a {} model, the model is {}",
                summary.kind,
                model.kind()
            )));
        }
        Ok(TrainedModel {
            model,
            spec,
            normalizer,
            chain,
            summary,
            verification: None,
            rest_rms_uv: None,
            rest_stage: None,
            envelope: None,
            provenance: None,
            taught: Taught::BOTH,
        })
    }

    /// The model with `envelope` applied to its inputs (see [`Envelope`]), or without one (an
    /// older file: inputs beyond the calibration reach the model as they are). Refuses an
    /// envelope of another input count.
    pub fn with_envelope(mut self, envelope: Option<Envelope>) -> Result<Self, ModelError> {
        if let Some(e) = &envelope {
            if e.len() != self.normalizer.len() {
                return Err(ModelError::Shape {
                    what: "envelope (one value per input feature)".into(),
                    expected: self.normalizer.len(),
                    found: e.len(),
                });
            }
        }
        self.envelope = envelope;
        Ok(self)
    }

    /// The calibration's envelope its inputs are held inside (None: an older file).
    pub fn envelope(&self) -> Option<&Envelope> {
        self.envelope.as_ref()
    }

    /// The model with `record` as its verification (replacing any earlier one). Refuses a
    /// record that contradicts itself ([`VerificationRecord::check`]).
    pub fn with_verification(mut self, record: VerificationRecord) -> Result<Self, ModelError> {
        record
            .check()
            .map_err(|e| ModelError::InvalidSpec(format!("verification record: {e}")))?;
        self.verification = Some(record);
        Ok(self)
    }

    /// The model with the calibration's rest level per channel (see
    /// [`TrainedModel::rest_rms_uv`]): one finite, non-negative value per chain channel.
    pub fn with_rest_rms_uv(mut self, levels: Vec<f64>) -> Result<Self, ModelError> {
        if levels.len() != self.chain.channels {
            return Err(ModelError::Shape {
                what: "rest levels (one per channel)".into(),
                expected: self.chain.channels,
                found: levels.len(),
            });
        }
        if let Some((ch, v)) = levels
            .iter()
            .enumerate()
            .find(|(_, v)| !(v.is_finite() && **v >= 0.0))
        {
            return Err(ModelError::InvalidSpec(format!(
                "rest level of channel {ch} is {v}: must be finite and >= 0"
            )));
        }
        self.rest_rms_uv = Some(levels);
        Ok(self)
    }

    /// The model with `record` as its provenance (replacing any earlier one). Refuses a record
    /// that is malformed ([`Provenance::check`]).
    pub fn with_provenance(mut self, record: Provenance) -> Result<Self, ModelError> {
        record
            .check()
            .map_err(|e| ModelError::InvalidSpec(format!("provenance: {e}")))?;
        self.provenance = Some(record);
        Ok(self)
    }

    /// Which patient and session the model was calibrated on (None: an older file, "unknown
    /// patient").
    pub fn provenance(&self) -> Option<&Provenance> {
        self.provenance.as_ref()
    }

    /// The model with `stage` applied to its outputs (see [`RestStage`]), or without a stage.
    pub fn with_rest_stage(mut self, stage: Option<RestStage>) -> Self {
        self.rest_stage = stage;
        self
    }

    /// The rest stage applied to the model's outputs (None: raw outputs, e.g. a two-point
    /// calibration, the paper's training or an older file).
    pub fn rest_stage(&self) -> Option<&RestStage> {
        self.rest_stage.as_ref()
    }

    /// The model with `taught` as the directions its calibration taught: an untaught one is
    /// held at 0 in its outputs (see [`Taught`]).
    pub fn with_taught(mut self, taught: Taught) -> Self {
        self.taught = taught;
        self
    }

    /// The directions the calibration taught ([`Taught::BOTH`] for an older file).
    pub fn taught(&self) -> &Taught {
        &self.taught
    }

    /// What the model does to the network's raw outputs: the rest stage, then the untaught
    /// directions held at 0. The predictor and the verifier both run it.
    pub fn output_stage(&self) -> OutputStage {
        OutputStage {
            rest: self.rest_stage,
            taught: self.taught,
        }
    }

    /// The model.
    pub fn model(&self) -> &AnyModel {
        &self.model
    }
    /// Hyper-parameters the model was built with.
    pub fn spec(&self) -> &ModelSpec {
        &self.spec
    }
    /// The feature scaling.
    pub fn normalizer(&self) -> &Normalizer {
        &self.normalizer
    }
    /// The signal chain configuration the model was trained on (features must come from it).
    pub fn chain(&self) -> &ChainConfig {
        &self.chain
    }
    /// Sample rate of the training data in Hz.
    pub fn sample_rate_hz(&self) -> f64 {
        self.chain.sample_rate_hz
    }
    /// EMG channel count.
    pub fn n_channels(&self) -> usize {
        self.chain.channels
    }
    /// What training did.
    pub fn summary(&self) -> &TrainingSummary {
        &self.summary
    }
    /// The verification of its calibration rays (None: not verified, e.g. an older file).
    pub fn verification(&self) -> Option<&VerificationRecord> {
        self.verification.as_ref()
    }
    /// Per channel, the calibration session's rest level: the RMS of the band-passed signal
    /// averaged over its rest windows, in the recording's units (µV for a session recorded
    /// from the bus). None when the session had no rest trials, or for an older file.
    pub fn rest_rms_uv(&self) -> Option<&[f64]> {
        self.rest_rms_uv.as_deref()
    }

    /// Labels for one raw feature vector (normalized here). Allocates scratch; for offline use
    /// (the daemon uses a [`Predictor`]). Panics if `features` has the wrong length.
    pub fn predict(&self, features: &[f64]) -> [f64; N_FINGERS] {
        self.predictor().run(features)
    }

    /// Labels for many raw feature vectors stored row-major in `rows` (e.g. a
    /// `FeatureMatrix`'s data), reusing one scratch. Panics if `rows.len()` is not a multiple of
    /// the feature count.
    pub fn predict_rows(&self, rows: &[f64]) -> Vec<[f64; N_FINGERS]> {
        let n = self.normalizer.len();
        assert!(
            rows.len().is_multiple_of(n),
            "{} values are not whole rows of {n} features",
            rows.len()
        );
        let mut p = self.predictor();
        rows.chunks_exact(n).map(|r| p.run(r)).collect()
    }

    /// A reusable, allocation-free runner (allocates its buffers once, here).
    pub fn predictor(&self) -> Predictor {
        Predictor {
            model: self.model.clone(),
            normalizer: self.normalizer.clone(),
            stage: self.output_stage(),
            envelope: self.envelope.clone(),
            scratch: self.model.new_scratch(),
            xp: vec![0.0; self.normalizer.len()],
            xn: vec![0.0; self.normalizer.len()],
            last_scale: 1.0,
            last_implausible: false,
        }
    }
}

/// Runs a trained model on raw feature vectors without allocating: the envelope when the model
/// has one, normalize, predict, then the output stage ([`OutputStage`]: the rest stage when the
/// model has one, the untaught directions held at 0).
#[derive(Debug, Clone)]
pub struct Predictor {
    model: AnyModel,
    normalizer: Normalizer,
    stage: OutputStage,
    envelope: Option<Envelope>,
    scratch: Scratch,
    /// The features held inside the envelope.
    xp: Vec<f64>,
    xn: Vec<f64>,
    last_scale: f64,
    last_implausible: bool,
}

impl Predictor {
    /// Features expected per call.
    pub fn n_inputs(&self) -> usize {
        self.xn.len()
    }

    /// Finger labels for `features` (length [`Predictor::n_inputs`], panics otherwise: the chain
    /// that feeds it is built from the same configuration, so a mismatch is a wiring bug).
    /// No allocation, no `Result`. Non-finite features give non-finite labels; the chain
    /// reports such input as a fault before it gets here.
    #[inline]
    pub fn run(&mut self, features: &[f64]) -> [f64; N_FINGERS] {
        match &self.envelope {
            Some(e) => {
                self.last_implausible = e.implausible(features);
                if self.last_implausible {
                    self.last_scale = 0.0;
                    return [0.0; N_FINGERS];
                }
                self.last_scale = e.project(features, &mut self.xp);
                self.normalizer.apply(&self.xp, &mut self.xn);
            }
            None => self.normalizer.apply(features, &mut self.xn),
        }
        let mut y = [0.0; N_FINGERS];
        self.model.predict_with(&self.xn, &mut y, &mut self.scratch);
        self.stage.apply(&mut y);
        y
    }

    /// Sets the spread of the envelope's plausibility check (when the model has an envelope);
    /// see [`Envelope::set_spread`].
    pub fn set_plausible_spread(&mut self, spread: f64) {
        if let Some(e) = &mut self.envelope {
            e.set_spread(spread);
        }
    }

    /// Sets the margin of the envelope's *off the patterns* test (when the model records the
    /// calibration's channel patterns); see [`Envelope::set_pattern_margin`].
    pub fn set_pattern_margin(&mut self, margin: f64) {
        if let Some(e) = &mut self.envelope {
            e.set_pattern_margin(margin);
        }
    }

    /// The signal scale the envelope applied to the last window (1: inside the calibration,
    /// or no envelope).
    pub fn last_scale(&self) -> f64 {
        self.last_scale
    }

    /// Whether the last window was implausible (one channel standing alone, or a shape off the
    /// calibration's channel patterns: see [`Envelope::implausible`]); its output was rest.
    pub fn last_implausible(&self) -> bool {
        self.last_implausible
    }
}
