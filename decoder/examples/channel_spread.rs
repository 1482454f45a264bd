//! The figure behind the plausibility check's *alone* test (`Envelope::implausible`, issue 25):
//! on each 3DC participant, per window of the train and test recordings, the top channel's
//! level (RMS over the calibration's largest, the envelope fitted on the train recording) over
//! the next channel's, and how often one channel at ten times its level stands alone.
//!
//!     cargo run -p decoder --example channel_spread [FLOOR]
//!
//! FLOOR (default `PLAUSIBLE_FLOOR`): windows whose top channel is below it are left out.
use decoder::dsp::{FEATURES_PER_CHANNEL, FEATURE_NAMES};
use decoder::model::{Envelope, PLAUSIBLE_FLOOR, PLAUSIBLE_SPREAD};
use decoder::session::{load_3dc, Split, WindowOptions};
use std::path::PathBuf;

/// Channel levels of `row`, largest first.
fn levels(row: &[f64], env: &Envelope, rms: usize) -> Vec<f64> {
    let mut e: Vec<f64> = (0..row.len() / FEATURES_PER_CHANNEL)
        .map(|c| {
            let j = c * FEATURES_PER_CHANNEL + rms;
            row[j] / env.max()[j]
        })
        .collect();
    e.sort_by(|a, b| b.total_cmp(a));
    e
}

fn main() {
    let rms = FEATURE_NAMES.iter().position(|n| *n == "RMS").expect("RMS");
    let floor: f64 = std::env::args()
        .nth(1)
        .map(|s| s.parse().expect("FLOOR must be a number"))
        .unwrap_or(PLAUSIBLE_FLOOR);
    for p in [4u32, 6, 7] {
        let d = PathBuf::from(format!("../shared/data/3dc-armband-p{p}"));
        assert!(
            d.exists(),
            "{} is missing (run from the repo root)",
            d.display()
        );
        let opts = WindowOptions::default();
        let train = load_3dc(&d, Split::Train).unwrap().windows(&opts).unwrap();
        let test = load_3dc(&d, Split::Test).unwrap().windows(&opts).unwrap();
        let env = Envelope::fit(
            train.n_features,
            train.features.chunks_exact(train.n_features),
        )
        .unwrap();
        for (name, w) in [("train", &train), ("test", &test)] {
            let (mut n, mut worst, mut over) = (0usize, 0.0f64, 0usize);
            for row in w.features.chunks_exact(w.n_features) {
                let e = levels(row, &env, rms);
                if e[0] > floor {
                    n += 1;
                    worst = worst.max(e[0] / e[1]);
                    over += usize::from(e[0] > PLAUSIBLE_SPREAD * e[1]);
                }
            }
            println!(
                "P{p} {name}: {n} windows with the top channel above {floor}: top / next at most \
                 {worst:.2}; {over} above the spread {PLAUSIBLE_SPREAD}"
            );
        }
        let (mut alone, mut all) = (0usize, 0usize);
        for c in 0..test.n_features / FEATURES_PER_CHANNEL {
            for row in test.features.chunks_exact(test.n_features) {
                let mut r = row.to_vec();
                r[c * FEATURES_PER_CHANNEL + rms] *= 10.0;
                let e = levels(&r, &env, rms);
                all += 1;
                alone += usize::from(e[0] > floor && e[0] > PLAUSIBLE_SPREAD * e[1]);
            }
        }
        println!(
            "P{p} test, each channel in turn at 10x: {alone} of {all} windows ({:.1}%) stand alone",
            100.0 * alone as f64 / all as f64
        );
    }
}
