//! Small valid model files and their parts, to build hostile variants with a correct header
//! (so a defect reaches the check behind the checksum).

use decoder::dsp::ChainConfig;
use decoder::model::{
    AnyModel, ModelKind, ModelSpec, Normalizer, TrainedModel, TrainingSummary, HEADER_LEN, MAGIC,
    N_FINGERS,
};

/// A small model's file: 4 channels (32 inputs), narrow layers.
pub fn valid_file(kind: ModelKind) -> Vec<u8> {
    let chain = ChainConfig {
        channels: 4,
        ..ChainConfig::default()
    };
    let n_in = 8 * chain.channels;
    let mut spec = ModelSpec::default();
    spec.resdd.hidden = 6;
    spec.ln.hidden = [6, 6];
    spec.mlp.hidden = [6, 6];
    spec.cnn.filters = [2, 2];
    spec.cnn.dense = 6;
    let model = AnyModel::random(kind, &spec, n_in, N_FINGERS, 7).expect("model");
    let scales = (0..n_in).map(|i| 0.5 + i as f64 * 0.01).collect();
    let normalizer = Normalizer::from_scales(scales).expect("scales");
    let summary = TrainingSummary::untrained(kind);
    let trained = TrainedModel::new(model, spec, normalizer, chain, summary).expect("bundle");
    trained.to_bytes().expect("serialises")
}

/// A file's body: the metadata JSON and the raw weights after it.
pub struct Parts {
    /// The metadata's bytes.
    pub meta: Vec<u8>,
    /// The weights and normalizer scales.
    pub data: Vec<u8>,
}

/// Splits a valid file.
pub fn split(bytes: &[u8]) -> Parts {
    let body = &bytes[HEADER_LEN..];
    let meta_len = u64::from_le_bytes(body[..8].try_into().expect("8 bytes")) as usize;
    Parts {
        meta: body[8..8 + meta_len].to_vec(),
        data: body[8 + meta_len..].to_vec(),
    }
}

/// A file of `meta` and `data` whose header and metadata length claim what is given.
pub fn join_claiming(meta: &[u8], data: &[u8], meta_len: u64, body_len: Option<u64>) -> Vec<u8> {
    let mut body = meta_len.to_le_bytes().to_vec();
    body.extend_from_slice(meta);
    body.extend_from_slice(data);
    let mut out = MAGIC.to_vec();
    out.extend_from_slice(&1u32.to_le_bytes());
    out.extend_from_slice(&crc32fast::hash(&body).to_le_bytes());
    out.extend_from_slice(&body_len.unwrap_or(body.len() as u64).to_le_bytes());
    out.extend_from_slice(&body);
    out
}

/// A file of `meta` and `data` with a correct header.
pub fn join(meta: &[u8], data: &[u8]) -> Vec<u8> {
    join_claiming(meta, data, meta.len() as u64, None)
}
