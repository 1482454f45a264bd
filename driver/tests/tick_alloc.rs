//! Proof that the daemon's tick never touches the heap: a counting global allocator
//! (`stats_alloc`, which holds the unsafe code) around 10 s of real traffic from the simulated
//! amplifier and finger controllers going through `Engine::on_frame`, 200 ticks and their
//! latency bookkeeping, and the latch set published to the writer's channel every tick (its
//! writer thread not started: it allocates, off the loop), and every input and output put on a
//! tape's queue (`handd --tape`; its writer not started either, so the queue fills and the
//! rest is counted lost, the other path). Runs without the test harness so no other thread allocates while the
//! region is measured.

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
    println!("tick_alloc: 1 passed, 0 failed");
}
