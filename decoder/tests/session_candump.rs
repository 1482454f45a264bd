//! A recorded session: a candump log of EMG_SAMPLES frames plus session.toml, read through
//! hand-dbc's CRC check and sample reassembly.

mod session_support;

use std::path::PathBuf;

use decoder::dsp::ChainConfig;
use decoder::session::{
    RecordingFormat, RecordingSpec, Session, SessionMeta, Trial, TrialKind, WindowOptions,
};
use hand_dbc::candump::LogWriter;
use hand_dbc::e2e::E2eProtector;
use hand_dbc::emg::EMG_LSB_UV;
use hand_dbc::messages::{EmgSamplesG0, EmgSamplesG1, EmgSamplesG2};
use session_support::temp_dir;

const T0_US: u64 = 1_700_000_000_000_000;

/// Channel `c` of sample `i`: a deterministic pattern of whole LSBs, louder in the second half.
fn value_uv(i: usize, c: usize) -> f64 {
    let amp = if i < 1500 { 4.0 } else { 60.0 };
    let lsb = ((i * 7 + c * 13) % 17) as f64 - 8.0;
    (amp * lsb / 8.0).round() * EMG_LSB_UV
}

/// Writes `n` samples as frames; `corrupt` names a sample whose G1 frame gets a bad CRC and
/// `drop_from..drop_to` a silent stretch (no frames at all).
fn write_log(path: &PathBuf, n: usize, corrupt: Option<usize>, silent: std::ops::Range<usize>) {
    let mut w = LogWriter::new(Vec::new());
    let mut p0 = E2eProtector::new(EmgSamplesG0::E2E);
    let mut p1 = E2eProtector::new(EmgSamplesG1::E2E);
    let mut p2 = E2eProtector::new(EmgSamplesG2::E2E);
    for i in 0..n {
        let v = |c: usize| value_uv(i, c);
        let f0 = p0
            .protect_message(&EmgSamplesG0::new(v(0), v(1), v(2), v(3)).unwrap())
            .unwrap();
        let mut f1 = p1
            .protect_message(&EmgSamplesG1::new(v(4), v(5), v(6), v(7)).unwrap())
            .unwrap();
        let f2 = p2
            .protect_message(&EmgSamplesG2::new(v(8), v(9), v(10), v(11)).unwrap())
            .unwrap();
        if silent.contains(&i) {
            continue;
        }
        if corrupt == Some(i) {
            f1.data_mut()[0] ^= 0x5a;
        }
        let t = T0_US + i as u64 * 1000;
        w.write_frame(t + 100, "can0", &f0).unwrap();
        w.write_frame(t + 200, "can0", &f1).unwrap();
        w.write_frame(t + 300, "can0", &f2).unwrap();
    }
    std::fs::write(path, w.into_inner()).unwrap();
}

fn meta(channels: usize) -> SessionMeta {
    let trial = |id, kind, start_ms: u64, end_ms: u64| Trial {
        id,
        finger: if kind == TrialKind::Rest {
            None
        } else {
            Some(2)
        },
        kind,
        repetition: 1,
        start_us: T0_US + start_ms * 1000,
        end_us: T0_US + end_ms * 1000,
    };
    SessionMeta {
        chain: ChainConfig {
            channels,
            ..ChainConfig::default()
        },
        onset_skip_ms: 0.0,
        recording: RecordingSpec {
            format: RecordingFormat::Candump,
            file: PathBuf::from("frames.log"),
            full_scale: Some(2047.0),
        },
        segments: Vec::new(),
        trials: vec![
            trial(1, TrialKind::Rest, 0, 1500),
            trial(2, TrialKind::Flexion, 1500, 3000),
        ],
        reference: None,
        recorded_utc: None,
    }
}

#[test]
fn a_candump_session_loads_sample_exact() {
    let dir = temp_dir("candump");
    write_log(&dir.join("frames.log"), 3000, None, 0..0);
    meta(12).write(&dir).unwrap();
    let s = Session::open(&dir).unwrap();
    assert_eq!(s.recording.len(), 3000);
    assert_eq!(s.recording.lost_samples, 0);
    for i in [0, 1, 1499, 1500, 2999] {
        for c in 0..12 {
            assert_eq!(
                s.recording.samples[i * 12 + c],
                value_uv(i, c),
                "sample {i} channel {c}"
            );
        }
    }
    let w = s.windows(&WindowOptions::default()).unwrap();
    // Each trial lasts 1500 samples: (1500 - 200) / 50 + 1 = 27 windows, give or take the
    // one whose edges the 300 µs receive offset moves.
    let flex = w.labels.iter().filter(|l| l.targets[2] == 1.0).count();
    let rest = w.labels.iter().filter(|l| l.targets == [0.0; 5]).count();
    assert!(
        (26..=27).contains(&flex) && (26..=27).contains(&rest),
        "{flex} {rest}"
    );
    // A session that uses fewer channels than the bus carries reads the first ones.
    meta(8).write(&dir).unwrap();
    let s8 = Session::open(&dir).unwrap();
    assert_eq!(s8.recording.samples[8 * 10 + 7], value_uv(10, 7));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn bad_crc_frames_are_bridged_and_gaps_break_windows() {
    let dir = temp_dir("candump-faults");
    write_log(&dir.join("frames.log"), 3000, Some(100), 2000..2100);
    meta(12).write(&dir).unwrap();
    let s = Session::open(&dir).unwrap();
    assert_eq!(s.recording.bad_frames, 1);
    // The bad frame's channels hold the previous sample's values.
    assert_eq!(s.recording.samples[100 * 12 + 4], value_uv(99, 4));
    assert_eq!(s.recording.samples[100 * 12], value_uv(100, 0));
    // 100 ms of silence is beyond bridging: a break, and no window spans it.
    assert_eq!(s.recording.breaks.len(), 1);
    let b = s.recording.breaks[0];
    let w = s.windows(&WindowOptions::default()).unwrap();
    assert!(w
        .labels
        .iter()
        .all(|l| !(l.end_sample - 200 < b && b < l.end_sample)));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_log_without_emg_or_with_a_bad_line_is_refused() {
    let dir = temp_dir("candump-bad");
    meta(12).write(&dir).unwrap();
    std::fs::write(dir.join("frames.log"), "(1.000000) can0 123#00\n").unwrap();
    let e = Session::open(&dir).unwrap_err().to_string();
    assert!(e.contains("no EMG_SAMPLES frames"), "{e}");
    std::fs::write(dir.join("frames.log"), "(1.000000) can0 123#00\ngarbage\n").unwrap();
    let e = Session::open(&dir).unwrap_err().to_string();
    assert!(e.contains("line 2"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn saturation_is_judged_in_bus_lsb() {
    // Full-scale samples (raw ±2047 = ±5117.5 µV) in the flexion trial's channel 5.
    let dir = temp_dir("candump-sat");
    let mut out = LogWriter::new(Vec::new());
    let mut p = [
        E2eProtector::new(EmgSamplesG0::E2E),
        E2eProtector::new(EmgSamplesG1::E2E),
        E2eProtector::new(EmgSamplesG2::E2E),
    ];
    for i in 0..3000usize {
        let v = |c: usize| {
            if i >= 1500 && c == 5 && i % 4 == 0 {
                2047.0 * EMG_LSB_UV
            } else {
                value_uv(i, c)
            }
        };
        let t = T0_US + i as u64 * 1000;
        let frames = [
            p[0].protect_message(&EmgSamplesG0::new(v(0), v(1), v(2), v(3)).unwrap())
                .unwrap(),
            p[1].protect_message(&EmgSamplesG1::new(v(4), v(5), v(6), v(7)).unwrap())
                .unwrap(),
            p[2].protect_message(&EmgSamplesG2::new(v(8), v(9), v(10), v(11)).unwrap())
                .unwrap(),
        ];
        for (g, f) in frames.iter().enumerate() {
            out.write_frame(t + 100 * g as u64, "can0", f).unwrap();
        }
    }
    std::fs::write(dir.join("frames.log"), out.into_inner()).unwrap();
    meta(12).write(&dir).unwrap();
    let s = Session::open(&dir).unwrap();
    let r = decoder::session::check_gates(&s, &decoder::session::GateConfig::default()).unwrap();
    let sat: Vec<_> = r
        .issues
        .iter()
        .filter(|i| matches!(i.kind, decoder::session::GateKind::Saturated { .. }))
        .collect();
    assert_eq!(sat.len(), 1, "{r}");
    assert_eq!(
        sat[0].kind,
        decoder::session::GateKind::Saturated { channel: 5 }
    );
    assert_eq!(sat[0].trial_id, 2);
    std::fs::remove_dir_all(&dir).unwrap();
}
