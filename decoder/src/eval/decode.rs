//! Decoding a whole recording with a trained model: per window its time and the five outputs,
//! and the session's reference signal resampled to the windows (the mean over each window's
//! samples, see [`crate::session::Reference`]). The windows come from
//! [`crate::session::Session::stream_windows`], the same feature path as training and
//! evaluation.

use std::fmt::Write as _;

use super::error::EvalError;
use crate::dsp::ChainConfig;
use crate::model::{TrainedModel, N_FINGERS};
use crate::session::{Reference, StreamWindows, FINGER_NAMES};

/// A decoded recording.
#[derive(Debug, Clone, PartialEq)]
pub struct Decoded {
    /// Time of each window's newest sample, s.
    pub time_s: Vec<f64>,
    /// The model's five outputs per window.
    pub outputs: Vec<[f64; N_FINGERS]>,
    /// The reference's name and its mean over each window, if the session has one.
    pub reference: Option<(String, Vec<f64>)>,
    /// Windows beyond the calibration's envelope, moved back into it (issue 25).
    pub beyond: usize,
    /// Implausible windows (one channel standing alone, or a shape off the calibration's
    /// channel patterns): output rest.
    pub implausible: usize,
}

impl Decoded {
    /// One finger's output per window.
    pub fn finger(&self, finger: usize) -> Vec<f64> {
        self.outputs.iter().map(|o| o[finger]).collect()
    }

    /// `time_s,thumb,index,middle,ring,pinky` (and the reference's name) then one row per
    /// window; numbers in Rust's shortest round-trip form, so a reader gets the exact values.
    pub fn to_csv(&self) -> String {
        let mut out = String::from("time_s");
        for name in FINGER_NAMES {
            out.push(',');
            out.push_str(name);
        }
        if let Some((name, _)) = &self.reference {
            out.push(',');
            out.push_str(name);
        }
        out.push('\n');
        for (i, (t, o)) in self.time_s.iter().zip(&self.outputs).enumerate() {
            // Writing into a String cannot fail.
            let _ = write!(out, "{t}");
            for v in o {
                let _ = write!(out, ",{v}");
            }
            if let Some((_, r)) = &self.reference {
                let _ = write!(out, ",{}", r[i]);
            }
            out.push('\n');
        }
        out
    }
}

/// The `[chain]` fields in which `a` and `b` differ, as `field: a vs b`.
fn chain_differences(a: &ChainConfig, b: &ChainConfig) -> Vec<String> {
    let table = |c: &ChainConfig| {
        toml::Value::try_from(c)
            .ok()
            .and_then(|v| v.as_table().cloned())
    };
    let (Some(ta), Some(tb)) = (table(a), table(b)) else {
        return vec![format!("{a:?} vs {b:?}")];
    };
    ta.iter()
        .filter(|(k, v)| tb.get(*k) != Some(*v))
        .map(|(k, v)| {
            let other = tb.get(k).map_or("-".to_string(), |o| o.to_string());
            format!("{k}: {v} vs {other}")
        })
        .collect()
}

/// Runs `model` on every window of a recording whose chain is `chain`; `reference` is the
/// session's reference signal, if any.
pub fn decode(
    model: &TrainedModel,
    chain: &ChainConfig,
    windows: &StreamWindows,
    reference: Option<&Reference>,
) -> Result<Decoded, EvalError> {
    if model.chain() != chain {
        return Err(EvalError::Shape(format!(
            "the model was trained on another signal chain than the recording's (model vs recording: {}); its features would not mean the same",
            chain_differences(model.chain(), chain).join(", ")
        )));
    }
    let n = model.normalizer().len();
    let mut p = model.predictor();
    let (mut beyond, mut implausible) = (0, 0);
    let outputs: Vec<[f64; N_FINGERS]> = windows
        .features
        .chunks_exact(n)
        .map(|row| {
            let y = p.run(row);
            beyond += usize::from(p.last_scale() < 1.0 && !p.last_implausible());
            implausible += usize::from(p.last_implausible());
            y
        })
        .collect();
    Ok(Decoded {
        beyond,
        implausible,
        time_s: windows.time_us.iter().map(|&t| t as f64 / 1e6).collect(),
        outputs,
        reference: reference.map(|r| {
            (
                r.name.clone(),
                r.window_means(&windows.end_sample, windows.window_len),
            )
        }),
    })
}
