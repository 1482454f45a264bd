//! What the engine's unit tests share: a random ResDD on the default chain.

use decoder::dsp::ChainConfig;
use decoder::model::{
    AnyModel, ModelKind, ModelSpec, Normalizer, Predictor, TrainedModel, TrainingSummary,
};

use super::{Engine, EngineSettings};

/// A ResDD with random weights (`seed`) and unit-ish scaling on the default chain: enough to
/// exercise the engine (its labels mean nothing).
pub(super) fn random_predictor(seed: u64) -> Predictor {
    let chain = ChainConfig::default();
    let n_in = 8 * chain.channels;
    let spec = ModelSpec::default();
    let model = AnyModel::random(ModelKind::ResDd, &spec, n_in, 5, seed).expect("model");
    let norm = Normalizer::from_scales(vec![100.0; n_in]).expect("normalizer");
    let summary = TrainingSummary::untrained(ModelKind::ResDd);
    TrainedModel::new(model, spec, norm, chain, summary)
        .expect("trained model")
        .predictor()
}

/// An engine in READY on the default chain with [`random_predictor`]`(seed)`.
pub(super) fn validated_engine(seed: u64) -> Engine {
    let chain = ChainConfig::default().validate().expect("chain");
    let mut e = Engine::new(&chain, random_predictor(seed), EngineSettings::default(), 0);
    e.validated(0);
    e
}
