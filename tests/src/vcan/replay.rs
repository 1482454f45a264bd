//! Replay of a recorded closed loop: the log's input frames (EMG, finger status, E-stop,
//! amplifier status) go through a fresh engine, built from handd's config and model, tick by
//! tick, and each tick's setpoint frames are compared with the ones handd put on the bus, bit
//! for bit.
//!
//! What a tick computes depends on its deadline and on the frames received by then (handd
//! holds later ones back for the next tick). The deadlines lie on an exact 50 ms grid, whose
//! phase the log gives to within a fraction of a millisecond (each tick's setpoints leave a
//! little after its deadline); that phase serves as the tick's time. Which frames a tick had
//! needs more precision, since every EMG sample moves the window: the tick's HAND_DIAG, one
//! tick later, carries the time from its newest complete sample to its setpoints written, which
//! points at that sample's frame to within microseconds. The replay feeds the frames up to the
//! frame it points at; if that tick's setpoints do not come out bit for bit, it tries the
//! neighbouring cut points of the last [`CUT_SEARCH_US`] on clones of the engine, nearest
//! first (a frame may be timestamped microseconds from another under emulation). A tick that
//! matches at no cut point is a difference.

use driver::engine::Engine;
use hand_dbc::candump::LogEntry;
use hand_dbc::messages::{FingerMode, FingerSetpoint, HandDiag};
use hand_dbc::CanFrame;

/// What a replay found.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ReplayReport {
    /// Ticks of the running closed loop whose setpoints match bit for bit.
    pub same: usize,
    /// Ticks that match at no cut point, as µs after the first tick.
    pub different: Vec<u64>,
    /// Matching ticks whose cut point was not the one HAND_DIAG points at.
    pub searched: usize,
    /// The running closed loop: first and last ACTIVE setpoint, µs.
    pub running: (u64, u64),
}

/// How far back before a tick's setpoints the replay looks for its cut point, µs.
pub const CUT_SEARCH_US: u64 = 20_000;

const SETPOINT_IDS: std::ops::RangeInclusive<u32> = 0x200..=0x204;
const HAND_DIAG_ID: u32 = 0x301;
const HAND_HEARTBEAT_ID: u32 = 0x300;

fn from_handd(id: u32) -> bool {
    SETPOINT_IDS.contains(&id) || id == HAND_DIAG_ID || id == HAND_HEARTBEAT_ID
}

/// One of handd's ticks in the log.
struct Tick {
    /// Log index of its first setpoint frame, and that frame's time.
    first: usize,
    time_us: u64,
    /// Time of the last frame it sent (its setpoints written, to within microseconds).
    written_us: u64,
    /// TickLatency of its HAND_DIAG (about the tick before).
    latency_us: Option<u64>,
}

/// Replays `log` (a candump log of the bus, handd's frames included) through an engine made
/// from handd's `config` and its model. Panics with a message if the model does not load or
/// the log holds no running closed loop.
pub fn replay(config: &driver::Config, log: &[LogEntry]) -> ReplayReport {
    let loaded = driver::startup::load_model(&config.model, config.mains_hz).expect("model");
    let period = config.tick_ms * 1000;
    let ticks = ticks_of(log);
    assert!(ticks.len() > 400, "only {} ticks recorded", ticks.len());
    let t_first = ticks[0].time_us;
    // The deadline grid: tick j is due at phase + k_j * period, at or before its setpoints.
    let k_of = |t: u64| ((t - t_first) as f64 / period as f64).round() as u64;
    let phase = ticks
        .iter()
        .map(|t| t.time_us - k_of(t.time_us) * period)
        .min()
        .expect("ticks");
    let active: Vec<u64> = log
        .iter()
        .filter(|e| {
            SETPOINT_IDS.contains(&e.frame.raw_id())
                && FingerSetpoint::decode(e.frame.raw_id(), e.frame.data())
                    .is_ok_and(|s| s.mode() == FingerMode::Active)
        })
        .map(|e| e.time_us)
        .collect();
    let running = (
        *active
            .first()
            .expect("no ACTIVE setpoint in the closed loop"),
        *active.last().expect("no ACTIVE setpoint"),
    );
    // Log indices of the input frames (everything handd did not send), in order.
    let inputs: Vec<usize> = (0..log.len())
        .filter(|&i| !from_handd(log[i].frame.raw_id()))
        .collect();
    let mut engine = Engine::new(
        &loaded.chain,
        loaded.model.predictor(),
        driver::startup::engine_settings(config, loaded.model_id),
        phase,
    );
    engine.validated(phase);
    let mut report = ReplayReport {
        same: 0,
        different: Vec::new(),
        searched: 0,
        running,
    };
    let mut fed = 0usize;
    for (j, tick) in ticks.iter().enumerate() {
        let t = tick.time_us;
        let deadline = phase + k_of(t) * period;
        let recorded: Vec<&CanFrame> = log[tick.first..]
            .iter()
            .filter(|e| SETPOINT_IDS.contains(&e.frame.raw_id()))
            .take(5)
            .map(|e| &e.frame)
            .collect();
        // Inputs logged before the setpoints; those older than the search window were had.
        let avail = inputs.partition_point(|&k| k < tick.first);
        let sure = inputs
            .partition_point(|&k| k < tick.first && log[k].time_us + CUT_SEARCH_US <= t)
            .max(fed);
        // Where HAND_DIAG points: the newest complete sample's frame.
        let pointed = ticks
            .get(j + 1)
            .and_then(|next| next.latency_us)
            .map(|lat| tick.written_us.saturating_sub(lat));
        // Cut points (inputs fed), the pointed one first, then by distance to it (or latest
        // first without a pointer).
        let mut cuts: Vec<usize> = (sure..=avail).collect();
        let time_of_cut = |n: usize| {
            if n == 0 {
                0
            } else {
                log[inputs[n - 1]].time_us
            }
        };
        match pointed {
            Some(p) => cuts.sort_by_key(|&n| {
                // The cut just after the pointed frame: its time is at or after the pointer.
                let tc = time_of_cut(n);
                let below = time_of_cut(n.saturating_sub(1).max(sure));
                if tc >= p && below < p {
                    0
                } else {
                    tc.abs_diff(p) + 1
                }
            }),
            None => cuts.reverse(),
        }
        let mut base = engine.clone();
        feed(&mut base, &inputs[fed..sure], log);
        let mut chosen: Option<(usize, Engine)> = None;
        let mut first_try: Option<(usize, Engine)> = None;
        for (tries, &n) in cuts.iter().enumerate() {
            let mut e = base.clone();
            feed(&mut e, &inputs[sure..n], log);
            let out = tick_setpoints(&mut e, deadline, t);
            let matches = out.len() == recorded.len()
                && out
                    .iter()
                    .zip(&recorded)
                    .all(|(a, b)| a.raw_id() == b.raw_id() && a.data() == b.data());
            if matches {
                if tries > 0 {
                    report.searched += 1;
                }
                chosen = Some((n, e));
                break;
            }
            if first_try.is_none() {
                first_try = Some((n, e));
            }
        }
        // The closed loop proper: from handd's first ACTIVE setpoint to its last. Before it,
        // handd's start (its clock before the first tick) is not in the log; after it,
        // handsim has ended and the silence timeout falls between tick and send.
        let scored = t >= running.0 && t <= running.1;
        let (n, e) = match chosen {
            Some(c) => {
                report.same += usize::from(scored);
                c
            }
            None => {
                if scored {
                    report.different.push(t - t_first);
                }
                first_try.expect("at least one cut point")
            }
        };
        fed = n;
        engine = e;
    }
    report
}

/// handd's ticks in `log`: each begins with FINGER_SETPOINT_0; its other frames follow before
/// the next one.
fn ticks_of(log: &[LogEntry]) -> Vec<Tick> {
    let starts: Vec<usize> = (0..log.len())
        .filter(|&i| log[i].frame.raw_id() == 0x200)
        .collect();
    starts
        .iter()
        .enumerate()
        .map(|(j, &first)| {
            let end = starts.get(j + 1).copied().unwrap_or(log.len());
            let own = || {
                log[first..end]
                    .iter()
                    .filter(|e| from_handd(e.frame.raw_id()))
            };
            let written_us = own().map(|e| e.time_us).max().unwrap_or(log[first].time_us);
            let latency_us = own()
                .find(|e| e.frame.raw_id() == HAND_DIAG_ID)
                .and_then(|e| HandDiag::decode(e.frame.data()).ok())
                .map(|d| d.tick_latency() as u64)
                .filter(|&l| l < u64::from(u16::MAX));
            Tick {
                first,
                time_us: log[first].time_us,
                written_us,
                latency_us,
            }
        })
        .collect()
}

fn feed(e: &mut Engine, inputs: &[usize], log: &[LogEntry]) {
    for &k in inputs {
        e.on_frame(&log[k].frame, log[k].time_us);
    }
}

/// One tick of `e` due at `deadline`, written at `t`: its setpoint frames.
fn tick_setpoints(e: &mut Engine, deadline: u64, t: u64) -> Vec<CanFrame> {
    let out = e
        .tick(deadline, t)
        .iter()
        .filter(|f| SETPOINT_IDS.contains(&f.raw_id()))
        .copied()
        .collect();
    e.written(t, 0);
    out
}
