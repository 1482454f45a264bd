//! One front end and one feature path (issue 11): for a session recorded on the bus, what
//! training sees (the session loaded from its candump log -> feature windows -> the model) and
//! what the daemon computes (the same frames into `Engine::on_frame`, a tick whenever a
//! training window ends) are equal bit for bit: the 96 features and the 5 model outputs of
//! every window.
//!
//! Two recordings, both framed by the amplifier node's firmware core (`amp-node` over
//! simulated ADS1299): (a) a real one, one 3DC armband recording (Power Grip, repetition 0,
//! from `../shared/data/3dc-armband-p4`) served to the node, which quantizes it to the bus's
//! LSB; (b) a simulated calibration (hand-model's quick protocol) recorded on the in-memory
//! bus, whose amplifier is that node core.

use std::path::{Path, PathBuf};

use amp_node::DcRemoval;
use decoder::dsp::npy::read_npy;
use decoder::dsp::{ChainConfig, FEATURES_PER_CHANNEL};
use decoder::model::{AnyModel, ModelKind, ModelSpec, Normalizer, TrainedModel, TrainingSummary};
use decoder::session::{Session, SessionMeta, Trial, TrialKind, WindowOptions};
use driver::engine::{Engine, EngineSettings};
use hand_dbc::candump::{read_log, LogWriter};
use hand_dbc::emg::{EmgFrame, EMG_CHANNELS, EMG_LSB_UV};
use hand_dbc::hand::{ADC_MAX, N_FINGERS};
use hand_model::emg::AmplifierConfig;
use hand_model::nodes::{AmpBoard, AmplifierNodeConfig};
use hand_model::record::run_on_mem_bus;
use hand_model::world::WorldConfig;
use hand_model::Scenario;

/// `../shared/data/3dc-armband-p4` from the repository's root.
const THREE_DC: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../shared/data/3dc-armband-p4"
);
/// Gesture id of Power Grip in the 3DC index.
const POWER_GRIP: u64 = 7;
/// First receive time of the 3DC log, µs.
const T0_US: u64 = 1_000_000;

/// A fresh, empty directory under the system's temp dir.
fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("one-path-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

/// A deterministic model (random weights, fixed seed) for `chain`.
fn model(chain: &ChainConfig) -> TrainedModel {
    let n_in = FEATURES_PER_CHANNEL * chain.channels;
    let spec = ModelSpec::default();
    let net = AnyModel::random(ModelKind::ResDd, &spec, n_in, N_FINGERS, 7).expect("model");
    let norm = Normalizer::from_scales(vec![20.0; n_in]).expect("scales");
    let summary = TrainingSummary::untrained(ModelKind::ResDd);
    TrainedModel::new(net, spec, norm, chain.clone(), summary).expect("model")
}

/// Samples `start..end` of the 3DC train recording of Power Grip, repetition 0, as raw counts
/// (row-major, 10 channels).
fn three_dc_power_grip() -> (Vec<f64>, usize) {
    let dir = Path::new(THREE_DC);
    assert!(
        dir.join("P4_train_emg.npy").is_file(),
        "{THREE_DC}/P4_train_emg.npy is missing: this test reads the real recordings from \
         ../shared/data (see its README.md)"
    );
    let index = std::fs::read_to_string(dir.join("P4_train_index.csv")).expect("index csv");
    let mut lines = index.lines();
    let header: Vec<&str> = lines.next().expect("header").split(',').collect();
    let col = |name: &str| header.iter().position(|c| *c == name).expect("column");
    let (c_rep, c_gesture) = (col("rep"), col("gesture_id"));
    let (c_start, c_end) = (col("start_sample"), col("end_sample_exclusive"));
    let row: Vec<u64> = lines
        .map(|l| {
            l.split(',')
                .map(|f| f.trim().parse().unwrap_or(u64::MAX))
                .collect()
        })
        .map(|f: Vec<u64>| vec![f[c_rep], f[c_gesture], f[c_start], f[c_end]])
        .find(|f| f[0] == 0 && f[1] == POWER_GRIP)
        .expect("Power Grip, repetition 0, in the index");
    let arr = read_npy(dir.join("P4_train_emg.npy")).expect("3DC samples");
    let channels = arr.shape[1];
    let (a, b) = (row[2] as usize * channels, row[3] as usize * channels);
    (arr.data[a..b].to_vec(), channels)
}

/// (a) as a session directory: the 3DC samples, one count taken as 1 µV, channel `c` of the
/// bus carrying 3DC channel `c % 10`, one sample per ms, served to the amplifier node's
/// firmware core over simulated ADS1299 (`AmpBoard`, as the simulator's amplifier), its
/// frames (EMG and EMG_STATUS) written into `frames.log`, one rest trial over all. The node
/// gives back every sample quantized to the bus's 2.5 µV LSB (clipped to 12 bits), checked
/// here on the frames.
fn write_three_dc_session(dir: &Path) {
    let (counts, channels) = three_dc_power_grip();
    let n = counts.len() / channels;
    // DC-coupled, so the bus can be checked against the recording to the LSB (the simulated
    // session (b) runs the reference board, DC removal on).
    let mut board = AmpBoard::try_with(DcRemoval::Off).expect("the simulated amplifier board");
    let mut log = LogWriter::new(Vec::new());
    for i in 0..n {
        let uv: [f64; EMG_CHANNELS] = std::array::from_fn(|c| counts[i * channels + c % channels]);
        board.convert(&uv, 0, 0);
        let t = T0_US + i as u64 * 1000;
        for (g, f) in board.take_frames().enumerate() {
            if let Ok(Some(frame)) = EmgFrame::decode(f.raw_id(), f.data()) {
                for (k, raw) in frame.raw().iter().enumerate() {
                    let c = 4 * usize::from(frame.group()) + k;
                    let count = counts[i * channels + c % channels];
                    let want = (count / EMG_LSB_UV).round().clamp(-2048.0, 2047.0) as i16;
                    assert!(*raw == want, "sample {i}: {raw} on the bus, {want} wanted");
                }
            }
            log.write_frame(t + 100 * g as u64, "can0", &f)
                .expect("log");
        }
    }
    assert!(
        board.counters().queued == n as u64,
        "{:?}",
        board.counters()
    );
    std::fs::write(dir.join("frames.log"), log.into_inner()).expect("write log");
    let rest = Trial {
        id: 1,
        finger: None,
        kind: TrialKind::Rest,
        repetition: 1,
        start_us: 0,
        end_us: T0_US + n as u64 * 1000 + 1000,
    };
    let meta = SessionMeta::candump(
        ChainConfig::default(),
        "frames.log",
        f64::from(ADC_MAX),
        vec![rest],
    );
    meta.write(dir).expect("session.toml");
}

/// (b) as a session directory: hand-model's quick calibration on the in-memory bus, every
/// frame into `frames.log`, with the session.toml the simulator writes for it.
fn write_simulated_session(dir: &Path) {
    let run = Scenario::CalibrationQuick.build(3).expect("scenario");
    let signal = AmplifierConfig {
        seed: 3,
        ..AmplifierConfig::default()
    };
    run.session_meta("frames.log", &signal)
        .write(dir)
        .expect("write session.toml");
    let cfg = WorldConfig {
        amplifier: AmplifierNodeConfig {
            signal,
            ..AmplifierNodeConfig::default()
        },
        ..WorldConfig::default()
    };
    let mut log = LogWriter::new(Vec::new());
    run_on_mem_bus(cfg, run.patient, run.duration_us, |t, f| {
        log.write_frame(t, "can0", f)
    })
    .expect("world")
    .expect("log");
    std::fs::write(dir.join("frames.log"), log.into_inner()).expect("write log");
}

/// Training's path and the daemon's engine over the session in `dir`; returns the number of
/// windows compared (every training window, or the test fails).
fn compare(dir: &Path) -> usize {
    let session = Session::open(dir).expect("session loads");
    let windows = session.windows(&WindowOptions::default()).expect("windows");
    let trained = model(&session.meta.chain);
    let mut predictor = trained.predictor();
    let settings = session.meta.chain.validate().expect("chain");
    assert_eq!(windows.n_features, 96, "12 channels x 8 features");

    let mut engine = Engine::new(&settings, trained.predictor(), EngineSettings::default(), 0);
    engine.validated(0);
    let log = read_log(dir.join("frames.log")).expect("log");
    let mut frames = log.iter();
    let mut compared = 0;
    for (i, label) in windows.labels.iter().enumerate() {
        let end = label.end_sample as u64;
        // Frames in until the window's last sample is in, then the tick at that frame's time.
        let mut now = 0;
        while engine.samples_in() < end {
            let e = frames.next().expect("the log holds every training window");
            engine.on_frame(&e.frame, e.time_us);
            now = e.time_us;
        }
        assert_eq!(
            engine.samples_in(),
            end,
            "window {i}: samples arrive one at a time"
        );
        engine.tick(now, now);
        assert_eq!(
            engine.samples_used(),
            end,
            "window {i}: the model ran on it"
        );
        let want = windows.row(i);
        let got = engine.model_features();
        assert_eq!(got.len(), want.len());
        for (k, (a, b)) in got.iter().zip(want).enumerate() {
            assert_eq!(
                a.to_bits(),
                b.to_bits(),
                "window {i} feature {k}: {a} vs {b}"
            );
        }
        let y = predictor.run(want);
        for (f, (a, b)) in engine.labels().iter().zip(y).enumerate() {
            assert_eq!(
                a.to_bits(),
                b.to_bits(),
                "window {i} output {f}: {a} vs {b}"
            );
        }
        compared += 1;
    }
    println!("{}: {compared} windows equal bit for bit", dir.display());
    compared
}

#[test]
fn a_real_recording_reads_the_same_in_training_and_in_the_daemon() {
    let dir = temp_dir("3dc");
    write_three_dc_session(&dir);
    let session = Session::open(&dir).expect("session");
    let settings = session.meta.chain.validate().expect("chain");
    let expected = settings.n_windows(session.recording.len());
    assert!(expected > 50, "only {expected} windows in the recording");
    assert_eq!(compare(&dir), expected);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_simulated_calibration_reads_the_same_in_training_and_in_the_daemon() {
    let dir = temp_dir("sim");
    write_simulated_session(&dir);
    let session = Session::open(&dir).expect("session");
    let expected = session
        .windows(&WindowOptions::default())
        .expect("windows")
        .len();
    assert!(expected > 50, "only {expected} training windows");
    assert_eq!(compare(&dir), expected);
    let _ = std::fs::remove_dir_all(&dir);
}
