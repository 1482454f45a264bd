//! EMG frame decode + reassembly throughput (DESIGN.md section 8 goal: >= 2 million frames/s
//! on one core; the bus carries 3,000/s).
//!
//! `cargo bench -p hand-dbc --bench emg_decode`; `front_end` is the whole front end the daemon
//! and the offline path share (E2E check, decode, reassembly, rails, µV).

#![allow(
    missing_docs,
    reason = "criterion_group! generates an undocumented pub fn"
)]

use std::hint::black_box;
use std::time::Duration;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use hand_dbc::e2e::E2eProtector;
use hand_dbc::emg::{EmgAssembler, EmgConfig, EmgFrame};
use hand_dbc::emg_front::{EmgFront, EmgFrontConfig, EmgFrontSettings, FrontSample};
use hand_dbc::messages::{self, EmgSamplesG0, EmgSamplesG1, EmgSamplesG2};
use hand_dbc::CanFrame;

const SAMPLES: usize = 1000;

/// One second of bus traffic: 1000 samples x 3 protected frames, with varying channel values.
fn frames() -> Vec<(CanFrame, u64)> {
    let mut p = [
        E2eProtector::new(EmgSamplesG0::E2E),
        E2eProtector::new(EmgSamplesG1::E2E),
        E2eProtector::new(EmgSamplesG2::E2E),
    ];
    let mut out = Vec::with_capacity(SAMPLES * 3);
    for k in 0..SAMPLES {
        let v = |c: usize| ((k * 37 + c * 101) % 4096) as i16 - 2048;
        let mut f0 = EmgSamplesG0::decode(&[0; 8]).expect("zeros valid");
        f0.set_emg0_raw(v(0)).expect("12 bit");
        f0.set_emg3_raw(v(3)).expect("12 bit");
        let mut f1 = EmgSamplesG1::decode(&[0; 8]).expect("zeros valid");
        f1.set_emg5_raw(v(5)).expect("12 bit");
        let mut f2 = EmgSamplesG2::decode(&[0; 8]).expect("zeros valid");
        f2.set_emg11_raw(v(11)).expect("12 bit");
        let t = k as u64 * 1000;
        out.push((p[0].protect_message(&f0).expect("profile"), t));
        out.push((p[1].protect_message(&f1).expect("profile"), t + 100));
        out.push((p[2].protect_message(&f2).expect("profile"), t + 200));
    }
    out
}

fn bench(c: &mut Criterion) {
    let input = frames();
    let mut group = c.benchmark_group("emg");
    group
        .throughput(Throughput::Elements(input.len() as u64))
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(3))
        .sample_size(30);

    group.bench_function("decode_dispatch+reassemble", |b| {
        let mut asm = EmgAssembler::try_new(EmgConfig::default()).expect("valid");
        let mut acc = 0i64;
        b.iter(|| {
            for (frame, t) in &input {
                let msg = messages::decode_frame(frame).expect("valid frame");
                if let Some(f) = EmgFrame::from_message(&msg) {
                    asm.push(&f, *t, &mut |s| acc += i64::from(s.raw[0]));
                }
            }
            black_box(acc)
        });
    });

    group.bench_function("decode_direct+reassemble", |b| {
        let mut asm = EmgAssembler::try_new(EmgConfig::default()).expect("valid");
        let mut acc = 0i64;
        b.iter(|| {
            for (frame, t) in &input {
                if let Ok(Some(f)) = EmgFrame::decode(frame.raw_id(), frame.data()) {
                    asm.push(&f, *t, &mut |s| acc += i64::from(s.raw[11]));
                }
            }
            black_box(acc)
        });
    });
    group.bench_function("decode_only", |b| {
        let mut acc = 0i64;
        b.iter(|| {
            for (frame, _) in &input {
                if let Ok(Some(f)) = EmgFrame::decode(frame.raw_id(), frame.data()) {
                    acc += i64::from(f.raw()[1]);
                }
            }
            black_box(acc)
        });
    });
    group.bench_function("front_end", |b| {
        let settings = EmgFrontSettings::try_new(EmgFrontConfig::default()).expect("defaults");
        let mut front = EmgFront::new(&settings);
        let mut acc = 0.0f64;
        b.iter(|| {
            for (frame, t) in &input {
                front.on_frame(frame, *t, &mut |s: &FrontSample| acc += s.uv()[11]);
            }
            black_box(acc)
        });
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
