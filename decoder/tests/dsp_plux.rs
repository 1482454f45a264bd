//! A real check that the amplitude features track force: PLUX EMG with simultaneous force
//! (one channel, 1 kHz, one contraction). Window RMS must correlate with the window's mean
//! force at Pearson r >= 0.85.

mod dsp_common;

use decoder::dsp::{Chain, ChainConfig};

fn pearson(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len() as f64;
    let (ma, mb) = (a.iter().sum::<f64>() / n, b.iter().sum::<f64>() / n);
    let cov: f64 = a.iter().zip(b).map(|(x, y)| (x - ma) * (y - mb)).sum();
    let va: f64 = a.iter().map(|x| (x - ma).powi(2)).sum();
    let vb: f64 = b.iter().map(|y| (y - mb).powi(2)).sum();
    cov / (va * vb).sqrt()
}

#[test]
fn window_rms_tracks_force() {
    let path = dsp_common::data_path("plux-emg-force/emg_force_1khz.csv");
    let text = std::fs::read_to_string(&path).expect("read PLUX csv");
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("time_s,emg,force"), "unexpected header");
    let (mut emg, mut force) = (Vec::new(), Vec::new());
    for (i, line) in lines.enumerate() {
        let cols: Vec<f64> = line
            .split(',')
            .map(|v| {
                v.trim()
                    .parse()
                    .unwrap_or_else(|_| panic!("line {}: {line:?}", i + 2))
            })
            .collect();
        assert_eq!(cols.len(), 3, "line {}", i + 2);
        emg.push(cols[1]);
        force.push(cols[2]);
    }
    assert!(
        emg.len() >= 4000,
        "5 s at 1 kHz expected, got {}",
        emg.len()
    );

    let settings = ChainConfig {
        channels: 1,
        ..ChainConfig::default()
    }
    .validate()
    .expect("1-channel default chain");
    let w = settings.window_len();
    let mut chain = Chain::new(&settings);
    let (mut rms, mut mean_force) = (Vec::new(), Vec::new());
    for (n, &x) in emg.iter().enumerate() {
        if chain.push(&[x]) {
            rms.push(chain.features()[0]);
            let win = &force[n + 1 - w..=n];
            mean_force.push(win.iter().sum::<f64>() / w as f64);
        }
    }
    let r = pearson(&rms, &mean_force);
    println!(
        "PLUX: {} windows, Pearson r(window RMS, mean force) = {r:.4}",
        rms.len()
    );
    assert!(r >= 0.85, "r = {r}");
}
