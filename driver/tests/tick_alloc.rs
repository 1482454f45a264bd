//! Proof that the daemon's tick never touches the heap: a counting global allocator
//! (`stats_alloc`, which holds the unsafe code) around 10 s of real traffic from the simulated
//! amplifier and finger controllers going through `Engine::on_frame`, 200 ticks and their
//! latency bookkeeping, and the latch set published to the writer's channel every tick (its
//! writer thread not started: it allocates, off the loop), and every input and output put on a
//! tape's queue (`handd --tape`; its writer not started either, so the queue fills and the
//! rest is counted lost, the other path). Then the same traffic with the index finger on a
//! live simulated CiA 402 drive (`with_a_cia402_drive`). Runs without the test harness so no
//! other thread allocates while the region is measured.

mod common;

use driver::engine::{Engine, EngineSettings};
use hand_dbc::CanFrame;
use hand_model::patient::Script;
use hand_model::record::run_on_mem_bus;
use hand_model::world::{PatientMode, WorldConfig};
use stats_alloc::{Region, StatsAlloc, INSTRUMENTED_SYSTEM};
use std::alloc::System;

#[global_allocator]
static GLOBAL: &StatsAlloc<System> = &INSTRUMENTED_SYSTEM;

fn main() {
    // Traffic: a patient flexing and extending the hand, recorded once, outside the region.
    let mut script = Script::new();
    script
        .rest(1_000_000)
        .ramp_to(hand_model::patient::Intent::all(1.0), 3_000_000)
        .ramp_to(hand_model::patient::Intent::all(-1.0), 3_000_000)
        .rest(3_000_000);
    let mut frames: Vec<(u64, CanFrame)> = Vec::new();
    run_on_mem_bus(
        WorldConfig::default(),
        PatientMode::Script(script),
        10_000_000,
        |t, f| {
            frames.push((t, *f));
            Ok::<_, ()>(())
        },
    )
    .expect("world")
    .expect("recording");

    let chain = decoder::dsp::ChainConfig::default()
        .validate()
        .expect("chain");
    let mut engine = Engine::new(
        &chain,
        common::random_predictor(3),
        EngineSettings::default(),
        0,
    );
    let (recorder, _queue) = driver::tape::unwritten(driver::tape::recorder::QUEUE_ENTRIES);
    engine.record_to(recorder);
    engine.validated(0);
    let (mut latches, _store, _writer) =
        driver::persist::latch_channel(std::env::temp_dir().join("tick-alloc-latches"), None);
    let mut stop = driver::safety::FaultSet::default();
    stop.insert(driver::safety::Fault::StopRequested);
    let stopped = driver::persist::Latches::of(stop, driver::engine::Hold::Free);
    let mut sent = 0usize;
    let mut next = 0usize;
    let mut deadline = 50_000u64;
    let region = Region::new(GLOBAL);
    while deadline <= 10_000_000 {
        while next < frames.len() && frames[next].0 <= deadline {
            engine.on_frame(&frames[next].1, frames[next].0);
            next += 1;
        }
        sent += engine.tick(deadline, deadline).len();
        engine.written(deadline + 20, 20);
        // A change every tick, as the loop publishes it (the first fills the wake-up slot,
        // the rest find it full).
        latches.publish(engine.latches());
        latches.publish(stopped);
        deadline += 50_000;
    }
    let stats = region.change();
    let ticks = engine.counters().ticks;
    let lost = engine.tape().map_or(0, |t| t.lost());
    println!("tape: {lost} entries lost once its queue was full");
    assert!(lost > 0, "the full queue's path was taken");
    println!(
        "{ticks} ticks, {next} frames in, {sent} frames out, state {}: {} allocations, {} reallocations",
        engine.state(),
        stats.allocations,
        stats.reallocations
    );
    assert_eq!(ticks, 200);
    assert!(next > 25_000, "frames fed: {next}");
    assert_eq!(
        engine.state(),
        driver::safety::DaemonState::Running,
        "{}",
        engine.faults()
    );
    assert!(
        sent >= 200 * 6,
        "setpoints and diagnostics every tick: {sent}"
    );
    assert_eq!(stats.allocations, 0, "heap allocations in the tick");
    assert_eq!(stats.reallocations, 0, "heap reallocations in the tick");
    with_a_cia402_drive(&frames, hand_canopen::Mode::CyclicSyncTorque);
    with_a_cia402_drive(&frames, hand_canopen::Mode::CyclicSyncVelocity);
    with_every_plausibility_test(&frames);
    println!("tick_alloc: 4 passed, 0 failed");
}

/// The same traffic through a model with a calibration envelope and channel patterns, made so
/// that every path of the plausibility check runs in the tick: the envelope's maximum is low
/// (windows are moved back into it), and the patterns are two single channels, which no
/// window of the whole hand fits (the full pattern fit runs; the window is implausible).
fn with_every_plausibility_test(frames: &[(u64, CanFrame)]) {
    use decoder::model::{Envelope, PatternCone};
    let chain = decoder::dsp::ChainConfig::default();
    let n = chain.channels;
    let single = |c: usize| (0..n).map(|i| f64::from(u8::from(i == c))).collect();
    let envelope = Envelope::try_new(vec![20.0; 8 * n])
        .and_then(|e| e.with_alone(Some(2.0)))
        .and_then(|e| {
            e.with_cone(Some(
                PatternCone::try_new(n, vec![single(0), single(6)], 0.0).expect("cone"),
            ))
        })
        .expect("envelope");
    let predictor = common::random_model(3)
        .with_envelope(Some(envelope))
        .expect("envelope")
        .predictor();
    let settings = chain.validate().expect("chain");
    let mut engine = Engine::new(&settings, predictor, EngineSettings::default(), 0);
    engine.validated(0);
    let (mut next, mut deadline) = (0usize, 50_000u64);
    let region = Region::new(GLOBAL);
    while deadline <= 10_000_000 {
        while next < frames.len() && frames[next].0 <= deadline {
            engine.on_frame(&frames[next].1, frames[next].0);
            next += 1;
        }
        engine.tick(deadline, deadline);
        engine.written(deadline + 20, 20);
        deadline += 50_000;
    }
    let stats = region.change();
    let c = engine.counters();
    println!(
        "every plausibility test: {} ticks, {} windows beyond the calibration, {} implausible: \
         {} allocations, {} reallocations",
        c.ticks, c.beyond_calibration, c.implausible, stats.allocations, stats.reallocations
    );
    assert!(c.implausible > 0, "the pattern fit ran");
    assert_eq!(stats.allocations, 0, "heap allocations in the tick");
    assert_eq!(stats.reallocations, 0, "heap reallocations in the tick");
}

/// The same traffic with the index finger on a live simulated CiA 402 drive (node 6, in `mode`:
/// CST, or CSV with the torque limit in RPDO1): its RPDO1, SYNC and heartbeat every tick, its TPDO1, heartbeat and SDO answers into
/// `Engine::on_frame`. Only the engine's calls are counted (the simulated drive allocates
/// between them, outside the product), from the first tick after the drive follows its
/// target: its start-up (a boxed plan per drive, at construction and at `arm`) is not the tick.
fn with_a_cia402_drive(frames: &[(u64, CanFrame)], mode: hand_canopen::Mode) {
    use driver::drive_config::{Drive, Drives};
    use hand_canopen::sim::SimDrive;
    use hand_canopen::{CobId, NodeId};
    let node = NodeId::try_new(6).expect("in range");
    let scaling = hand_canopen::scaling::ScalingSettings {
        rated_torque_mnm: 25.0,
        gear_ratio: 64.0,
        moment_arm_m: 0.04,
        max_torque_permille: 1000,
        max_speed_rpm: 8000,
    }
    .validate()
    .expect("scaling");
    let mut fingers = [Drive::Native; 5];
    fingers[1] = Drive::Cia402 {
        node,
        mode,
        scaling,
    };
    let settings = EngineSettings {
        drives: Drives {
            fingers,
            master: Some((
                NodeId::try_new(127).expect("in range"),
                CobId::try_new(0x07F).expect("11 bits"),
            )),
        },
        ..EngineSettings::default()
    };
    let chain = decoder::dsp::ChainConfig::default()
        .validate()
        .expect("chain");
    let mut engine = Engine::new(&chain, common::random_predictor(3), settings, 0);
    engine.validated(0);
    let mut drive = SimDrive::new(node);
    let mut to_engine: Vec<(u64, CanFrame)> = Vec::new();
    let mut boot = Vec::new();
    drive.power_on(0, &mut boot);
    let dbc = |f: hand_canopen::CanFrame| {
        CanFrame::new_standard(f.cob_id(), f.payload()).expect("11-bit frame")
    };
    to_engine.extend(boot.into_iter().map(|f| (1, dbc(f))));
    let mut counted = (0u64, 0u64);
    let mut counting = false;
    let mut calls = 0u64;
    let mut next = 0usize;
    let mut deadline = 50_000u64;
    let mut now = 0u64;
    while now < 10_000_000 {
        now += 1_000;
        // The drive's frames of the last step reach the engine first (stamped half a step
        // after they were sent), then the recorded traffic up to now.
        let mut from_drive = Vec::new();
        let mut to_drive: Vec<CanFrame> = Vec::new();
        let feed = |engine: &mut Engine, f: &CanFrame, at: u64, out: &mut Vec<CanFrame>| {
            // The engine's calls only: copying its frames out is the test's own allocation.
            let before = GLOBAL.stats();
            engine.on_frame(f, at);
            let immediate = engine.take_immediate();
            let after = GLOBAL.stats();
            out.extend_from_slice(immediate);
            (after.allocations - before.allocations) as u64
                + (after.reallocations - before.reallocations) as u64
        };
        for (t, f) in to_engine.drain(..) {
            let n = feed(&mut engine, &f, t, &mut to_drive);
            if counting {
                counted.0 += n;
                calls += 1;
            }
        }
        while next < frames.len() && frames[next].0 <= now {
            let (t, f) = frames[next];
            // The native index controller's status is ignored for a CiA 402 finger.
            let n = feed(&mut engine, &f, t, &mut to_drive);
            if counting {
                counted.0 += n;
                calls += 1;
            }
            next += 1;
        }
        if now >= deadline {
            let before = GLOBAL.stats();
            let out = engine.tick(deadline, deadline);
            let ticked = GLOBAL.stats();
            to_drive.extend_from_slice(out);
            let before_written = GLOBAL.stats();
            engine.written(deadline + 20, 20);
            let after = GLOBAL.stats();
            if counting {
                counted.1 += (ticked.allocations - before.allocations) as u64
                    + (ticked.reallocations - before.reallocations) as u64
                    + (after.allocations - before_written.allocations) as u64
                    + (after.reallocations - before_written.reallocations) as u64;
                calls += 1;
            }
            counting = counting
                || matches!(
                    engine.drive_status(1),
                    Some(hand_canopen::DriveStatus::Running { enabled: true, .. })
                );
            deadline += 50_000;
        }
        for f in &to_drive {
            if let Some(c) = hand_canopen::CanFrame::new(f.raw_id() as u16, f.data()) {
                drive.on_frame(&c, now, &mut from_drive);
            }
        }
        drive.poll(now, &mut from_drive);
        to_engine.extend(from_drive.into_iter().map(|f| (now + 500, dbc(f))));
    }
    println!(
        "with a CiA 402 drive in {mode:?}: state {}, drive {:?}; {calls} engine calls counted: {} \
         allocations or reallocations in on_frame, {} in the tick",
        engine.state(),
        engine
            .drive_status(1)
            .map(|s| matches!(s, hand_canopen::DriveStatus::Running { enabled: true, .. })),
        counted.0,
        counted.1
    );
    assert!(
        counting,
        "the drive never followed its target: {:?}",
        engine.drive_status(1)
    );
    assert!(calls > 20_000, "engine calls counted: {calls}");
    assert!(
        drive.stats().rpdos_applied > 100,
        "RPDO1 applied by the drive: {}",
        drive.stats().rpdos_applied
    );
    assert_eq!(drive.stats().rpdo_length_errors, 0, "{mode:?}");
    assert_eq!(
        counted,
        (0, 0),
        "heap allocations with a CiA 402 drive in {mode:?}"
    );
}
