//! CPU time per training epoch of ResDD (H=96, L=2) on a synthetic calibration session of the
//! default size, the handstack side of the PyTorch comparison (`decoder/ref/train_torch.py`
//! builds the same data bit for bit and trains the same model the same way).
//!
//! Data: 11 trials (flexion and extension per finger, rest) x 100 windows x 96 features from a
//! random non-negative mixing of 10 sources (SplitMix64 seed 7, as `benches/model.rs`); the
//! trial-tail split (20% of each trial held out, 3 overlapping windows dropped); Adam
//! (lr 1e-3), batch 32, masked MSE, a validation pass per epoch; early stopping off, so every
//! run trains exactly `--epochs` epochs. One thread, f64; thread CPU time.
//!
//! Run: `cargo run --release -p decoder --example train_bench -- [--json] [--effort]
//! [--epochs N] [--repeats R]`. `--json` prints one line
//! `{"what":"train_resdd_epoch","impl":"handstack","ms_cpu_per_epoch":X,"epochs":N}` (with
//! `--effort`, `"what":"train_resdd_epoch_effort"`: the default effort-ray penalty on).

use cpu_time::ThreadTime;
use decoder::dsp::ChainConfig;
use decoder::model::{
    train, Dataset, EffortPenalty, ModelKind, ModelSpec, TrainConfig, ValidationSplit, N_FINGERS,
};

/// SplitMix64 in [0, 1).
struct Gen(u64);
impl Gen {
    fn unit(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// 11 trials x `windows` windows of 96 features (the same session as `benches/model.rs`).
fn calibration(windows: usize) -> Dataset {
    let mut g = Gen(7);
    let chain = ChainConfig::default();
    let nf = 8 * chain.channels;
    let mix: Vec<Vec<f64>> = (0..10)
        .map(|_| (0..nf).map(|_| g.unit().powi(2)).collect())
        .collect();
    let mut d = Dataset::new(chain).expect("default chain");
    for trial in 0..11 {
        let (finger, dir) = (trial / 2, if trial % 2 == 0 { 1.0 } else { -1.0 });
        for _ in 0..windows {
            let mut x: Vec<f64> = (0..nf).map(|_| 0.05 * g.unit()).collect();
            let (mut t, mut m) = ([0.0; N_FINGERS], [true; N_FINGERS]);
            if trial < 10 {
                let a = 0.8 + 0.2 * g.unit();
                let src = &mix[2 * finger + usize::from(dir < 0.0)];
                for (xi, s) in x.iter_mut().zip(src) {
                    *xi += a * s;
                }
                m = [false; N_FINGERS];
                m[finger] = true;
                t[finger] = dir;
            }
            let x: Vec<f64> = x.iter().map(|v| v * 50.0).collect();
            d.push(&x, t, m, trial).expect("window");
        }
    }
    d
}

struct Args {
    json: bool,
    effort: bool,
    epochs: usize,
    repeats: usize,
}

fn parse_args() -> Result<Args, String> {
    let mut a = Args {
        json: false,
        effort: false,
        epochs: 83,
        repeats: 3,
    };
    let mut it = std::env::args().skip(1);
    while let Some(arg) = it.next() {
        let mut number = |name: &str| -> Result<usize, String> {
            let v = it.next().ok_or(format!("{name} needs a number"))?;
            v.parse().map_err(|_| format!("{name}: not a count: {v:?}"))
        };
        match arg.as_str() {
            "--json" => a.json = true,
            "--effort" => a.effort = true,
            "--epochs" => a.epochs = number("--epochs")?.max(1),
            "--repeats" => a.repeats = number("--repeats")?.max(1),
            other => return Err(format!("unknown argument {other:?}")),
        }
    }
    Ok(a)
}

fn main() {
    let args = parse_args().unwrap_or_else(|e| {
        eprintln!("train_bench: {e}");
        std::process::exit(2);
    });
    let data = calibration(100);
    let cfg = TrainConfig {
        max_epochs: args.epochs,
        patience: args.epochs,
        split: ValidationSplit::TrialTail { fraction: 0.2 },
        effort: args.effort.then(EffortPenalty::default),
        ..TrainConfig::plain()
    };
    let spec = ModelSpec::default();
    let mut per_epoch = Vec::new();
    let mut summary = None;
    for _ in 0..=args.repeats {
        let start = ThreadTime::now();
        let m = train(ModelKind::ResDd, &spec, &data, &cfg, &mut |_| {}).expect("trains");
        let ms = start.elapsed().as_secs_f64() * 1e3;
        per_epoch.push(ms / m.summary().epochs_run as f64);
        summary = Some(m.summary().clone());
    }
    per_epoch.remove(0); // the first run warms caches and the allocator
    per_epoch.sort_by(f64::total_cmp);
    let median = per_epoch[per_epoch.len() / 2];
    let s = summary.expect("at least one run");
    let what = if args.effort {
        "train_resdd_epoch_effort"
    } else {
        "train_resdd_epoch"
    };
    if args.json {
        println!(
            "{{\"what\":\"{what}\",\"impl\":\"handstack\",\"ms_cpu_per_epoch\":{median:.4},\"epochs\":{}}}",
            s.epochs_run
        );
    } else {
        println!(
            "handstack ResDD H=96 L=2, {} train + {} val windows x 96 features, batch 32, Adam, {} epochs{}",
            s.n_train_windows,
            s.n_val_windows,
            s.epochs_run,
            if args.effort { ", effort penalty on" } else { "" }
        );
        println!(
            "CPU ms per epoch: median {median:.3} of {} runs (all: {per_epoch:.3?}); final train loss {:.5}, best val {:?}",
            per_epoch.len(),
            s.final_train_loss,
            s.best_val_loss
        );
    }
}
