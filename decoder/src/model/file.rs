//! The model file: versioned, self-describing, checksummed, written atomically.
//!
//! Layout (all integers little-endian):
//!
//! | bytes | content |
//! |---|---|
//! | 8 | magic `HSMODEL\n` |
//! | 4 | format version (u32, currently [`FORMAT_VERSION`]) |
//! | 4 | CRC-32 (IEEE) of the body |
//! | 8 | body length in bytes (u64) |
//! | body | u64 metadata length, metadata (UTF-8 JSON), parameters (f64), normalizer scales (f64) |
//!
//! The JSON metadata names everything a reader needs: model kind and hyper-parameters, input and
//! output sizes, sample rate, channel count, feature names, the full signal chain configuration,
//! the list of parameter tensors (name and shape, in storage order), the normalizer's shape and
//! the training summary; then, when known, the verification of the calibration rays
//! (`verification`, see [`VerificationRecord`]) and the calibration's rest level per channel
//! (`rest_rms_uv`), and which patient and session it was calibrated on (`provenance`, see
//! [`Provenance`]: patient id, session id, calibration date, the quality gates bypassed). Files
//! written before those existed lack them and still load ("not verified", "unknown patient").
//! Everything in the body, these included, is covered by the checksum. Weights are raw
//! IEEE-754 doubles so they load bit for bit.
//!
//! Versions. Version 2 lists in `required` every metadata section present that changes what
//! the model outputs (today `rest_stage`, the dead zone at rest, `envelope`, the
//! calibration's envelope its inputs are held inside: [`super::Envelope`], `envelope_alone`,
//! the calibration's largest top-over-next channel ratio its plausibility check's *alone*
//! test is relative to, and `taught`, per
//! finger the directions the calibration taught, an untaught one held at 0: [`super::Taught`],
//! written only when some direction was not taught); a reader refuses a
//! file whose `required` names a section it does not know ([`FileError::UnknownRequired`]), so
//! a newer file is never run with part of its behaviour silently dropped. Sections that only
//! describe the model (`verification`, `rest_rms_uv`, `provenance`, the summary) are not
//! required: an older reader may
//! ignore them. A new section that changes the outputs goes into `required` (and this build's
//! [`KNOWN_REQUIRED`]); a change of the layout itself bumps [`FORMAT_VERSION`]. This build
//! reads versions 1 (written before `required` existed; its optional sections are read as
//! before) and 2, and writes 2. A build from before version 2 refuses a version 2 file by its
//! version, instead of dropping its dead zone as it did with version 1 files that carried one.
//!
//! Loading checks, in this order, each with its own [`FileError`]: magic, version, length,
//! checksum, metadata, tensor shapes against the kind and spec, finite weights, the chain
//! configuration against the one in use.

use std::fs;
use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::dsp::{ChainConfig, FEATURES_PER_CHANNEL, FEATURE_NAMES};
use crate::fsio::write_atomic;

use super::any::AnyModel;
use super::dataset::N_FINGERS;
use super::error::FileError;
use super::kind::ModelKind;
use super::normalizer::Normalizer;
use super::provenance::Provenance;
use super::rest::RestStage;
use super::spec::ModelSpec;
use super::summary::TrainingSummary;
use super::taught::Taught;
use super::trained::TrainedModel;
use super::traits::{Model, TensorInfo, Trainable};
use super::verify::VerificationRecord;

/// Magic bytes at the start of every model file.
pub const MAGIC: [u8; 8] = *b"HSMODEL\n";
/// The format version this build writes (it reads this one and the ones before it, from
/// [`OLDEST_VERSION`]).
pub const FORMAT_VERSION: u32 = 2;
/// The oldest format version this build reads.
pub const OLDEST_VERSION: u32 = 1;
/// The metadata sections this build knows how to apply, of those a file may mark `required`.
pub const KNOWN_REQUIRED: &[&str] = &[
    "rest_stage",
    "envelope",
    "envelope_alone",
    "envelope_patterns",
    "taught",
];
/// Header length in bytes.
pub const HEADER_LEN: usize = 24;
/// Name of the normalizer tensor in the metadata and in errors.
pub const NORMALIZER_TENSOR: &str = "normalizer.scale";

/// Name and shape of one stored tensor.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
struct TensorMeta {
    name: String,
    shape: Vec<usize>,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
struct Meta {
    format: String,
    kind: ModelKind,
    spec: ModelSpec,
    n_inputs: usize,
    n_outputs: usize,
    sample_rate_hz: f64,
    n_channels: usize,
    feature_names: Vec<String>,
    chain: serde_json::Value,
    tensors: Vec<TensorMeta>,
    normalizer: TensorMeta,
    summary: TrainingSummary,
    /// Absent in files written before verification was recorded.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    verification: Option<VerificationRecord>,
    /// Absent in older files, and when the calibration had no rest trials.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    rest_rms_uv: Option<Vec<f64>>,
    /// Absent in older files, and for a model without a rest stage (raw outputs).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    rest_stage: Option<RestStage>,
    /// Per input feature, the calibration's largest value (absent in older files).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    envelope: Option<Vec<f64>>,
    /// The calibration's largest top-over-next channel ratio (absent in older files, and with
    /// one channel): the plausibility check's *alone* test ([`super::Envelope::implausible`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    envelope_alone: Option<f64>,
    /// The calibration's channel patterns (absent in older files, and when the calibration
    /// had more movements than a cone holds): the plausibility check's *off the patterns*
    /// test ([`super::PatternCone`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    envelope_patterns: Option<PatternRecord>,
    /// The directions the calibration taught, per finger (absent in older files, and when both
    /// directions of every finger were taught: the stage is then the identity).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    taught: Option<Taught>,
    /// Absent in older files: which patient and session (descriptive, never required).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    provenance: Option<Provenance>,
    /// The sections present that change the outputs (version 2 on; see the module docs).
    #[serde(default)]
    required: Vec<String>,
}

/// The channel patterns as a file holds them.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct PatternRecord {
    /// One per movement, a power per channel (unit length).
    patterns: Vec<Vec<f64>>,
    /// The calibration's own worst misfit.
    worst: f64,
}

const FORMAT_NAME: &str = "handstack-model";

fn io_err<'a>(op: &'static str, path: &'a Path) -> impl FnOnce(std::io::Error) -> FileError + 'a {
    move |source| FileError::Io {
        op,
        path: path.to_path_buf(),
        source,
    }
}

/// Top-level fields of two JSON objects that differ (both directions).
fn differing_fields(a: &serde_json::Value, b: &serde_json::Value) -> Vec<String> {
    match (a.as_object(), b.as_object()) {
        (Some(x), Some(y)) => {
            let mut keys: Vec<&String> = x.keys().chain(y.keys()).collect();
            keys.sort();
            keys.dedup();
            keys.into_iter()
                .filter(|k| x.get(*k) != y.get(*k))
                .map(|k| k.to_string())
                .collect()
        }
        _ => vec!["<whole configuration>".into()],
    }
}

/// The first non-finite value of `params`, as an error naming its tensor.
fn check_finite(params: &[f64], tensors: &[TensorInfo]) -> Result<(), FileError> {
    for t in tensors {
        if let Some(index) = params[t.offset..t.offset + t.len()]
            .iter()
            .position(|p| !p.is_finite())
        {
            return Err(FileError::NonFiniteWeight {
                tensor: t.name.clone(),
                index,
            });
        }
    }
    Ok(())
}

/// The version and the body of a file, after checking the header: magic, version, length,
/// checksum.
fn checked_body(bytes: &[u8]) -> Result<(u32, &[u8]), FileError> {
    if bytes.len() < HEADER_LEN || bytes[..8] != MAGIC {
        return Err(FileError::NotAModelFile);
    }
    let word = |r: std::ops::Range<usize>| -> [u8; 4] { bytes[r].try_into().expect("4 bytes") };
    let version = u32::from_le_bytes(word(8..12));
    if !(OLDEST_VERSION..=FORMAT_VERSION).contains(&version) {
        return Err(FileError::UnknownVersion {
            found: version,
            supported: FORMAT_VERSION,
        });
    }
    let stored_crc = u32::from_le_bytes(word(12..16));
    let body_len = u64::from_le_bytes(bytes[16..24].try_into().expect("8 bytes"));
    let body = &bytes[HEADER_LEN..];
    if body.len() as u64 != body_len {
        return Err(FileError::Length {
            expected: body_len,
            found: body.len() as u64,
        });
    }
    let computed = crc32fast::hash(body);
    if computed != stored_crc {
        return Err(FileError::BadChecksum {
            stored: stored_crc,
            computed,
        });
    }
    Ok((version, body))
}

/// The body's JSON metadata, and the weight data that follows it, for a file of `version`.
fn read_meta(version: u32, body: &[u8]) -> Result<(Meta, &[u8]), FileError> {
    let malformed = |m: String| FileError::Malformed(m);
    if body.len() < 8 {
        return Err(malformed("body too short for the metadata length".into()));
    }
    let meta_len = u64::from_le_bytes(body[..8].try_into().expect("8 bytes"));
    let rest = &body[8..];
    if meta_len > rest.len() as u64 {
        return Err(malformed(format!(
            "metadata length {meta_len} exceeds the {} bytes present",
            rest.len()
        )));
    }
    let (meta_bytes, data) = rest.split_at(meta_len as usize);
    let meta: Meta =
        serde_json::from_slice(meta_bytes).map_err(|e| malformed(format!("metadata: {e}")))?;
    if meta.format != FORMAT_NAME {
        return Err(malformed(format!(
            "format name {:?}, expected {FORMAT_NAME:?}",
            meta.format
        )));
    }
    let unknown: Vec<String> = meta
        .required
        .iter()
        .filter(|r| !KNOWN_REQUIRED.contains(&r.as_str()))
        .cloned()
        .collect();
    if !unknown.is_empty() {
        return Err(FileError::UnknownRequired { sections: unknown });
    }
    check_listed(&meta, version)?;
    Ok((meta, data))
}

/// Every section present that changes the outputs is listed in `required` (version 2 on; a
/// `taught` section in any version: it came after `required`), and an envelope's parts have
/// their envelope.
fn check_listed(meta: &Meta, version: u32) -> Result<(), FileError> {
    let sections = [
        ("taught", meta.taught.is_some(), true),
        ("rest_stage", meta.rest_stage.is_some(), version >= 2),
        (
            "envelope_alone",
            meta.envelope_alone.is_some(),
            version >= 2,
        ),
        (
            "envelope_patterns",
            meta.envelope_patterns.is_some(),
            version >= 2,
        ),
    ];
    for (name, present, must_list) in sections {
        if present && must_list && !meta.required.iter().any(|r| r == name) {
            return Err(FileError::Malformed(format!(
                "{name} present but not listed in required"
            )));
        }
    }
    for (name, present) in [
        ("envelope_alone", meta.envelope_alone.is_some()),
        ("envelope_patterns", meta.envelope_patterns.is_some()),
    ] {
        if present && meta.envelope.is_none() {
            return Err(FileError::Malformed(format!("{name} without an envelope")));
        }
    }
    Ok(())
}

/// The metadata's signal chain configuration: valid, and agreeing with the header fields.
fn meta_chain(meta: &Meta) -> Result<ChainConfig, FileError> {
    let malformed = |m: String| FileError::Malformed(m);
    let chain: ChainConfig = serde_json::from_value(meta.chain.clone())
        .map_err(|e| malformed(format!("signal chain configuration: {e}")))?;
    chain
        .validate()
        .map_err(|e| malformed(format!("signal chain configuration: {e}")))?;
    if meta.n_channels != chain.channels || meta.sample_rate_hz != chain.sample_rate_hz {
        return Err(malformed(format!(
            "header says {} channels at {} Hz, the chain configuration {} at {} Hz",
            meta.n_channels, meta.sample_rate_hz, chain.channels, chain.sample_rate_hz
        )));
    }
    Ok(chain)
}

/// Checks the stored sizes and tensor list against those of the kind and spec for `n_in`
/// inputs; returns the model's tensors.
fn check_shapes(meta: &Meta, n_in: usize) -> Result<Vec<TensorInfo>, FileError> {
    if meta.n_inputs != n_in {
        return Err(FileError::WrongShape {
            tensor: "input".into(),
            expected: vec![n_in],
            found: vec![meta.n_inputs],
        });
    }
    if meta.n_outputs != N_FINGERS {
        return Err(FileError::WrongShape {
            tensor: "output".into(),
            expected: vec![N_FINGERS],
            found: vec![meta.n_outputs],
        });
    }
    let expected = AnyModel::expected_tensors(meta.kind, &meta.spec, n_in, N_FINGERS)?;
    check_tensor_list(&expected, &meta.tensors)?;
    if meta.normalizer.name != NORMALIZER_TENSOR || meta.normalizer.shape != [n_in] {
        return Err(FileError::WrongShape {
            tensor: NORMALIZER_TENSOR.into(),
            expected: vec![n_in],
            found: meta.normalizer.shape.clone(),
        });
    }
    Ok(expected)
}

/// The stored tensors must be the expected ones: same names and shapes, in the same order.
fn check_tensor_list(expected: &[TensorInfo], found: &[TensorMeta]) -> Result<(), FileError> {
    for i in 0..expected.len().max(found.len()) {
        match (expected.get(i), found.get(i)) {
            (Some(e), Some(f)) if e.name == f.name && e.shape == f.shape => {}
            (Some(e), f) => {
                return Err(FileError::WrongShape {
                    tensor: e.name.clone(),
                    expected: e.shape.clone(),
                    found: f.map(|f| f.shape.clone()).unwrap_or_default(),
                })
            }
            (None, Some(f)) => {
                return Err(FileError::WrongShape {
                    tensor: f.name.clone(),
                    expected: Vec::new(),
                    found: f.shape.clone(),
                })
            }
            (None, None) => unreachable!("loop bound is the longer list"),
        }
    }
    Ok(())
}

/// The doubles after the metadata: the `expected` tensors' parameters, then `n_in` normalizer
/// scales; all finite, the scales not negative.
fn read_weights(data: &[u8], expected: &[TensorInfo], n_in: usize) -> Result<Vec<f64>, FileError> {
    let n_params: usize = expected.iter().map(|t| t.len()).sum();
    let want_bytes = 8 * (n_params as u64 + n_in as u64);
    if data.len() as u64 != want_bytes {
        return Err(FileError::Malformed(format!(
            "weight data is {} bytes, the tensors need {want_bytes}",
            data.len()
        )));
    }
    let values: Vec<f64> = data
        .chunks_exact(8)
        .map(|c| f64::from_le_bytes(c.try_into().expect("8 bytes")))
        .collect();
    let (params, scales) = values.split_at(n_params);
    check_finite(params, expected)?;
    if let Some(index) = scales.iter().position(|s| !s.is_finite() || *s < 0.0) {
        return Err(FileError::NonFiniteWeight {
            tensor: NORMALIZER_TENSOR.into(),
            index,
        });
    }
    Ok(values)
}

/// With an `expected` configuration, refuses a model whose chain differs from it, naming the
/// fields that differ (`stored` is the configuration as the file wrote it).
fn check_chain(
    stored: &serde_json::Value,
    chain: &ChainConfig,
    expected: Option<&ChainConfig>,
) -> Result<(), FileError> {
    if let Some(exp) = expected {
        if exp != chain {
            let want =
                serde_json::to_value(exp).map_err(|e| FileError::Malformed(e.to_string()))?;
            return Err(FileError::ChainMismatch {
                fields: differing_fields(stored, &want),
            });
        }
    }
    Ok(())
}

/// Adds the optional sections read from a file, each checked; a bad one is a malformed file.
fn with_records(
    mut model: TrainedModel,
    verification: Option<VerificationRecord>,
    rest: Option<Vec<f64>>,
    stage: Option<RestStage>,
    provenance: Option<Provenance>,
) -> Result<TrainedModel, FileError> {
    let malformed =
        |what: &str, e: super::error::ModelError| FileError::Malformed(format!("{what}: {e}"));
    if let Some(v) = verification {
        model = model
            .with_verification(v)
            .map_err(|e| malformed("verification", e))?;
    }
    if let Some(r) = rest {
        model = model
            .with_rest_rms_uv(r)
            .map_err(|e| malformed("rest_rms_uv", e))?;
    }
    if let Some(st) = stage {
        let checked = RestStage::try_new(*st.up(), *st.down(), st.sharpness())
            .map_err(|e| malformed("rest_stage", e))?;
        model = model.with_rest_stage(Some(checked));
    }
    if let Some(p) = provenance {
        model = model
            .with_provenance(p)
            .map_err(|e| malformed("provenance", e))?;
    }
    Ok(model)
}

impl TrainedModel {
    /// The file contents (see the module docs). Errors only if the model holds a non-finite
    /// value (which its constructors prevent) or the metadata cannot be serialised.
    pub fn to_bytes(&self) -> Result<Vec<u8>, FileError> {
        let params = self.model.params();
        let tensors = self.model.tensors();
        check_finite(params, &tensors)?;
        let chain =
            serde_json::to_value(&self.chain).map_err(|e| FileError::Malformed(e.to_string()))?;
        let meta = Meta {
            format: FORMAT_NAME.into(),
            kind: self.model.kind(),
            spec: self.spec,
            n_inputs: self.model.n_inputs(),
            n_outputs: self.model.n_outputs(),
            sample_rate_hz: self.chain.sample_rate_hz,
            n_channels: self.chain.channels,
            feature_names: (0..self.chain.channels)
                .flat_map(|c| FEATURE_NAMES.iter().map(move |f| format!("ch{c}.{f}")))
                .collect(),
            chain,
            tensors: tensors
                .iter()
                .map(|t| TensorMeta {
                    name: t.name.clone(),
                    shape: t.shape.clone(),
                })
                .collect(),
            normalizer: TensorMeta {
                name: NORMALIZER_TENSOR.into(),
                shape: vec![self.normalizer.len()],
            },
            summary: self.summary.clone(),
            verification: self.verification.clone(),
            rest_rms_uv: self.rest_rms_uv.clone(),
            rest_stage: self.rest_stage,
            envelope: self.envelope.as_ref().map(|e| e.max().to_vec()),
            envelope_alone: self.envelope.as_ref().and_then(|e| e.alone()),
            envelope_patterns: self.envelope.as_ref().and_then(|e| e.cone()).map(|c| {
                PatternRecord {
                    patterns: c.patterns().map(<[f64]>::to_vec).collect(),
                    worst: c.worst(),
                }
            }),
            taught: (!self.taught.is_both()).then_some(self.taught),
            provenance: self.provenance.clone(),
            required: [
                self.rest_stage.is_some().then_some("rest_stage"),
                self.envelope.is_some().then_some("envelope"),
                self.envelope
                    .as_ref()
                    .and_then(|e| e.alone())
                    .map(|_| "envelope_alone"),
                self.envelope
                    .as_ref()
                    .and_then(|e| e.cone())
                    .map(|_| "envelope_patterns"),
                (!self.taught.is_both()).then_some("taught"),
            ]
            .into_iter()
            .flatten()
            .map(str::to_owned)
            .collect(),
        };
        let meta_json =
            serde_json::to_vec_pretty(&meta).map_err(|e| FileError::Malformed(e.to_string()))?;
        let mut body =
            Vec::with_capacity(8 + meta_json.len() + 8 * (params.len() + self.normalizer.len()));
        body.extend_from_slice(&(meta_json.len() as u64).to_le_bytes());
        body.extend_from_slice(&meta_json);
        for p in params.iter().chain(self.normalizer.scales()) {
            body.extend_from_slice(&p.to_le_bytes());
        }
        let mut out = Vec::with_capacity(HEADER_LEN + body.len());
        out.extend_from_slice(&MAGIC);
        out.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
        out.extend_from_slice(&crc32fast::hash(&body).to_le_bytes());
        out.extend_from_slice(&(body.len() as u64).to_le_bytes());
        out.extend_from_slice(&body);
        Ok(out)
    }

    /// Parses and checks file contents (see the module docs). With `expected_chain`, a model
    /// trained on a different signal chain configuration is refused, naming the fields that differ.
    pub fn from_bytes(
        bytes: &[u8],
        expected_chain: Option<&ChainConfig>,
    ) -> Result<Self, FileError> {
        let (version, body) = checked_body(bytes)?;
        let (meta, data) = read_meta(version, body)?;
        let chain = meta_chain(&meta)?;
        let n_in = FEATURES_PER_CHANNEL * chain.channels;
        let expected = check_shapes(&meta, n_in)?;
        let values = read_weights(data, &expected, n_in)?;
        let (params, scales) = values.split_at(values.len() - n_in);
        check_chain(&meta.chain, &chain, expected_chain)?;
        if meta.summary.kind != meta.kind {
            return Err(FileError::Malformed(format!(
                "training summary is for {}, the model is {}",
                meta.summary.kind, meta.kind
            )));
        }
        let model = AnyModel::from_params(meta.kind, &meta.spec, n_in, N_FINGERS, params.to_vec())?;
        let normalizer = Normalizer::from_scales(scales.to_vec())?;
        let trained = TrainedModel::new(model, meta.spec, normalizer, chain, meta.summary)?;
        let trained = with_records(
            trained,
            meta.verification,
            meta.rest_rms_uv,
            meta.rest_stage,
            meta.provenance,
        )?
        .with_taught(meta.taught.unwrap_or_default());
        match meta.envelope {
            Some(max) => {
                let cone = meta
                    .envelope_patterns
                    .map(|r| {
                        super::PatternCone::try_new(
                            n_in / FEATURES_PER_CHANNEL,
                            r.patterns,
                            r.worst,
                        )
                    })
                    .transpose()
                    .map_err(|e| FileError::Malformed(format!("envelope: {e}")))?;
                let envelope = super::Envelope::try_new(max)
                    .and_then(|e| e.with_alone(meta.envelope_alone))
                    .and_then(|e| e.with_cone(cone))
                    .map_err(|e| FileError::Malformed(format!("envelope: {e}")))?;
                trained
                    .with_envelope(Some(envelope))
                    .map_err(|e| FileError::Malformed(format!("envelope: {e}")))
            }
            None => Ok(trained),
        }
    }

    /// Writes the model atomically ([`crate::fsio::write_atomic`]: a temporary file in the same
    /// directory, fsync, rename over `path`, fsync of the directory). A crash leaves either the
    /// old file or the new one.
    pub fn save(&self, path: impl AsRef<Path>) -> Result<(), FileError> {
        let path = path.as_ref();
        let bytes = self.to_bytes()?;
        Ok(write_atomic(path, &bytes)?)
    }

    /// Reads and checks a model file; see [`TrainedModel::from_bytes`].
    pub fn load(
        path: impl AsRef<Path>,
        expected_chain: Option<&ChainConfig>,
    ) -> Result<Self, FileError> {
        let path = path.as_ref();
        let bytes = fs::read(path).map_err(io_err("read", path))?;
        Self::from_bytes(&bytes, expected_chain)
    }
}
