//! A rig for the daemon's tests: the simulated world and the real daemon loop on one in-memory
//! bus, on a virtual clock, plus a probe that records every frame on the bus.

#![allow(
    dead_code,
    reason = "each test binary uses a different part of the rig"
)]

use decoder::dsp::ChainConfig;
use decoder::model::{
    AnyModel, ModelKind, ModelSpec, Normalizer, Predictor, TrainedModel, TrainingSummary,
};
use driver::daemon::Runner;
use driver::engine::{Engine, EngineSettings};
use driver::mem_transport::MemTransport;
use driver::transport::Transport;
use hand_dbc::messages::{FingerMode, FingerSetpoint};
use hand_dbc::CanFrame;
use hand_model::faults::FaultPlan;
use hand_model::patient::Script;
use hand_model::world::{PatientMode, World, WorldConfig};
use hand_model::{Clock, MemBus, MemEndpoint, VirtualClock};

/// A model with random weights and unit scaling: enough to exercise the loop and its safety
/// rules (the labels it gives are meaningless).
pub fn random_predictor(seed: u64) -> Predictor {
    random_model(seed).predictor()
}

/// The model behind [`random_predictor`].
pub fn random_model(seed: u64) -> TrainedModel {
    let chain = ChainConfig::default();
    let n_in = 8 * chain.channels;
    let spec = ModelSpec::default();
    let model = AnyModel::random(ModelKind::ResDd, &spec, n_in, 5, seed).unwrap();
    let summary = TrainingSummary::untrained(ModelKind::ResDd);
    // Features are in µV; scale them down so labels stay in a sensible range.
    let norm = Normalizer::from_scales(vec![100.0; n_in]).unwrap();
    TrainedModel::new(model, spec, norm, chain, summary).unwrap()
}

/// A model trained on a simulated calibration (the demo's recording and training), once per
/// test binary.
pub fn calibrated_predictor() -> Predictor {
    use std::sync::OnceLock;
    static MODEL: OnceLock<Predictor> = OnceLock::new();
    MODEL
        .get_or_init(|| {
            let seed = driver::demo::DemoOptions::default().seed;
            driver::demo::calibrated_model(seed)
                .expect("the demo's calibration, trained")
                .predictor()
        })
        .clone()
}

/// World + daemon + probe; the daemon reaches the bus through `T` (the in-memory bus itself,
/// or a wrapper that misbehaves on cue).
pub struct Rig<T: Transport = MemTransport<VirtualClock>> {
    pub clock: VirtualClock,
    pub bus: MemBus,
    pub world: World<MemEndpoint>,
    pub runner: Runner<T, VirtualClock>,
    pub probe: MemEndpoint,
    /// Every frame the probe saw, with its time.
    pub seen: Vec<(u64, CanFrame)>,
}

impl Rig {
    /// A resting patient for `duration_us`, the given faults, a random model.
    pub fn new(faults: FaultPlan, script: Script) -> Self {
        Self::with_predictor(faults, PatientMode::Script(script), random_predictor(7))
    }

    /// Any patient and model.
    pub fn with_predictor(faults: FaultPlan, patient: PatientMode, predictor: Predictor) -> Self {
        Rig::with_transport(faults, patient, predictor, |t| t)
    }
}

impl<T: Transport> Rig<T> {
    /// Any patient and model, the daemon's transport wrapped by `wrap`.
    pub fn with_transport(
        faults: FaultPlan,
        patient: PatientMode,
        predictor: Predictor,
        wrap: impl FnOnce(MemTransport<VirtualClock>) -> T,
    ) -> Self {
        Self::with_bus(faults, patient, predictor, wrap, |b| b)
    }

    /// As [`Rig::with_transport`], the bus shaped by `bus` first (e.g. its queue capacity).
    pub fn with_bus(
        faults: FaultPlan,
        patient: PatientMode,
        predictor: Predictor,
        wrap: impl FnOnce(MemTransport<VirtualClock>) -> T,
        bus: impl FnOnce(MemBus) -> MemBus,
    ) -> Self {
        Self::with_settings(
            faults,
            patient,
            predictor,
            wrap,
            bus,
            EngineSettings::default(),
        )
    }

    /// As [`Rig::with_bus`], with the engine's settings (a finger's CiA 402 drive, say).
    pub fn with_settings(
        faults: FaultPlan,
        patient: PatientMode,
        predictor: Predictor,
        wrap: impl FnOnce(MemTransport<VirtualClock>) -> T,
        bus: impl FnOnce(MemBus) -> MemBus,
        settings: EngineSettings,
    ) -> Self {
        let clock = VirtualClock::new();
        let bus = bus(MemBus::with_clock(clock.clone()));
        let b = bus.clone();
        let world = World::try_new(
            WorldConfig {
                faults,
                ..WorldConfig::default()
            },
            patient,
            || Ok::<_, String>(b.endpoint()),
        )
        .unwrap();
        let chain = ChainConfig::default().validate().unwrap();
        let mut engine = Engine::new(&chain, predictor, settings, 0);
        engine.validated(0);
        let transport = wrap(MemTransport::new(bus.endpoint(), clock.clone()));
        let runner = Runner::new(engine, transport, clock.clone(), 50_000);
        let probe = bus.endpoint();
        Self {
            clock,
            bus,
            world,
            runner,
            probe,
            seen: Vec::new(),
        }
    }

    /// Advance to `t_end_us` in 1 ms steps: the world every step, the daemon at its deadlines.
    pub fn run_until(&mut self, t_end_us: u64) {
        self.advance(t_end_us, true);
    }

    /// As [`Rig::run_until`], but the daemon reads the bus only at its deadlines (the loop
    /// before it read between ticks, [`driver::daemon::READ_EVERY_US`]).
    pub fn run_ticks_only_until(&mut self, t_end_us: u64) {
        self.advance(t_end_us, false);
    }

    fn advance(&mut self, t_end_us: u64, between_ticks: bool) {
        let mut now = self.clock.now_us();
        while now < t_end_us {
            now += 1000;
            self.clock.set_us(now);
            self.world.step(now);
            // As `Runner::run_realtime`: a tick at its deadline, the bus served between ticks.
            if now >= self.runner.next_deadline_us() {
                self.runner.step();
            } else if between_ticks && now >= self.runner.next_wake_us() {
                self.runner.service_bus();
            }
            while let Some(r) = self.probe.receive_timestamped() {
                self.seen.push((r.time_us.unwrap_or(now), r.frame));
            }
        }
    }

    /// Advance to `t_end_us` with the daemon stopped (SIGSTOP, a stalled board): the world runs
    /// and its frames queue up for the daemon, which runs no tick.
    pub fn stall_until(&mut self, t_end_us: u64) {
        let mut now = self.clock.now_us();
        while now < t_end_us {
            now += 1000;
            self.clock.set_us(now);
            self.world.step(now);
            while let Some(r) = self.probe.receive_timestamped() {
                self.seen.push((r.time_us.unwrap_or(now), r.frame));
            }
        }
    }

    /// Setpoints seen, as (time, finger, mode, force, velocity).
    pub fn setpoints(&self) -> Vec<(u64, usize, FingerMode, f64, f64)> {
        self.seen
            .iter()
            .filter_map(|(t, f)| {
                let id = f.raw_id();
                FingerSetpoint::instance_of(id)?;
                let m = FingerSetpoint::decode(id, f.data()).ok()?;
                Some((*t, m.instance(), m.mode(), m.force(), m.velocity()))
            })
            .collect()
    }

    /// The first time at or after `from_us` from which every setpoint of `finger` (or of all
    /// fingers) is a stop (SAFE_STOP with zero force and velocity; handd never sends DISABLED),
    /// until `to_us`.
    pub fn stopped_from(&self, from_us: u64, to_us: u64, finger: Option<usize>) -> Option<u64> {
        let sps: Vec<_> = self
            .setpoints()
            .into_iter()
            .filter(|s| s.0 >= from_us && s.0 <= to_us && finger.is_none_or(|f| s.1 == f))
            .collect();
        let is_stop = |s: &(u64, usize, FingerMode, f64, f64)| {
            s.2 == FingerMode::SafeStop && s.3 == 0.0 && s.4 == 0.0
        };
        let last_active = sps.iter().rposition(|s| !is_stop(s));
        match last_active {
            None => sps.first().map(|s| s.0),
            Some(i) => sps.get(i + 1).map(|s| s.0),
        }
    }
}

impl<T: Transport> Rig<T> {
    /// The virtual time now.
    pub fn clock_now(&self) -> u64 {
        self.clock.now_us()
    }
}
