//! Per-sample cost of the node core on the host: `AmpNode::on_frames` (12 conversions, three
//! EMG frames encoded and protected, the status every 100th period) and `AmpNode::drain` into
//! a controller that takes every frame; and the same per conversion at 2 kSPS with the
//! decimating FIR. `cargo bench -p amp-node --bench node`.

#![allow(
    missing_docs,
    reason = "criterion_group! generates an undocumented pub fn"
)]

use std::hint::black_box;

use ads1299::{Code, Frame, Gain, LeadOff, Status};
use amp_node::{AmpNode, NodeRate, NodeSettings};
use criterion::{criterion_group, criterion_main, Criterion};
use hand_dbc::CanFrame;

struct Sink(u64);

impl embedded_can::nb::Can for Sink {
    type Frame = CanFrame;
    type Error = embedded_can::ErrorKind;

    fn transmit(&mut self, frame: &CanFrame) -> nb::Result<Option<CanFrame>, Self::Error> {
        self.0 += u64::from(frame.data()[0]);
        Ok(None)
    }

    fn receive(&mut self) -> nb::Result<CanFrame, Self::Error> {
        Err(nb::Error::WouldBlock)
    }
}

fn frames(i: i32) -> (Frame, Frame) {
    let code = |c: i32| {
        Code::new((i * 7919 + c * 104_729) % 400_000 - 200_000).unwrap_or(Code::POSITIVE_FULL_SCALE)
    };
    let a = Frame {
        status: Status::new(0, 0, 0),
        codes: std::array::from_fn(|c| code(c as i32)),
    };
    let b = Frame {
        status: Status::new(0, 0, 0),
        codes: std::array::from_fn(|c| code(c as i32 + 8)),
    };
    (a, b)
}

fn bench(c: &mut Criterion) {
    let inputs: Vec<(Frame, Frame)> = (0..1000).map(frames).collect();
    for (rate, name) in [
        (NodeRate::Sps1000, "amp_node sample (on_frames + drain)"),
        // Per conversion at 2 kSPS: every second one runs the 63-tap FIR on 12 channels and
        // encodes the sample; a bus sample costs two of these.
        (
            NodeRate::Sps2000Decimated,
            "amp_node conversion at 2 kSPS (on_frames + drain)",
        ),
    ] {
        let settings =
            NodeSettings::try_with_rate(rate, Gain::X8, LeadOff::Dc6nA).expect("settings");
        let mut node: AmpNode = AmpNode::new(&settings);
        let mut sink = Sink(0);
        let mut k = 0;
        c.bench_function(name, |b| {
            b.iter(|| {
                let (a, bb) = &inputs[k % inputs.len()];
                k += 1;
                black_box(node.on_frames(black_box(a), black_box(bb)));
                node.drain(&mut sink);
            })
        });
        black_box(sink.0);
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
