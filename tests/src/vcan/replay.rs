//! Replay of a recorded closed loop: the log's input frames (EMG, finger status, E-stop,
//! amplifier status) go through a fresh engine, built from handd's config and model, tick by
//! tick, and each tick's setpoint frames are compared with the ones handd put on the bus, bit
//! for bit.
//!
//! What a tick computes depends on its deadline and on the frames received by then (handd
//! holds later ones back for the next tick). The deadlines lie on an exact 50 ms grid, whose
//! phase the log gives to within a fraction of a millisecond (each tick's setpoints leave a
//! little after its deadline); that phase serves as the tick's time. Which frames a tick had
//! needs more precision, since every EMG sample moves the window: the next tick's HAND_DIAG
//! carries the time from the tick's newest complete sample to its setpoints written (which
//! points at that sample's frames to within a millisecond or so under emulation) and that
//! sample's counter modulo 4 (which picks the one sample there). The replay feeds the frames
//! up to that sample's last frame. Should the setpoints not come out bit for bit there, it
//! tries the other cut points of the last [`CUT_SEARCH_US`], latest first, and counts the tick
//! as searched; a tick that matches at no cut point is a difference.
//!
//! Every setpoint carries handd's setpoint epoch, drawn at random when handd starts: the
//! replay's engine begins in the epoch of the first setpoint in the log, and from there
//! changes epoch by the same rules as handd (entry into SAFE, a controller's self-brake
//! report, both read from the log's frames). A bus recovery also starts a new epoch in handd;
//! it is not in the frames, so a log with one does not replay past it.

use driver::engine::Engine;
use hand_dbc::candump::LogEntry;
use hand_dbc::messages::{
    EmgSamplesG0, EmgSamplesG1, EmgSamplesG2, FingerMode, FingerSetpoint, HandDiag,
};
use hand_dbc::CanFrame;

/// What a replay found.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ReplayReport {
    /// Ticks of the running closed loop whose setpoints match bit for bit.
    pub same: usize,
    /// Ticks that match at no cut point, as µs after the first tick.
    pub different: Vec<u64>,
    /// Matching ticks whose cut point was not the one HAND_DIAG names.
    pub searched: usize,
    /// The running closed loop: first and last ACTIVE setpoint, µs.
    pub running: (u64, u64),
}

/// How far back before a tick's setpoints the replay looks for its cut point, µs.
pub const CUT_SEARCH_US: u64 = 20_000;
/// Where HAND_DIAG's latency points, the named sample's frames are looked for this far before
/// and after, µs: the pointer is early by the time between the daemon's last write and its
/// clock reading (up to about a millisecond under emulation), and the window is shorter than
/// four samples, so the counter modulo 4 names one sample in it.
const POINTER_BEFORE_US: u64 = 300;
const POINTER_AFTER_US: u64 = 2_500;

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
    /// TickLatency and NewestSample of its HAND_DIAG (about the tick before).
    latency_us: Option<u64>,
    newest_mod4: Option<u8>,
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
    // Each finger's epoch is its own: each begins at its first recorded setpoint's.
    for (f, id) in FingerSetpoint::IDS.iter().enumerate() {
        let first = log[ticks[0].first..]
            .iter()
            .find(|e| e.frame.raw_id() == *id)
            .unwrap_or_else(|| panic!("no setpoint of finger {f} in the log"));
        let epoch = FingerSetpoint::decode(*id, first.frame.data())
            .expect("handd's first setpoint decodes")
            .epoch();
        engine.begin_epoch(f, epoch);
    }
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
        // The cut HAND_DIAG names (just after the last frame of the tick's newest complete
        // sample), then every other cut point of the window, latest first.
        let named = ticks.get(j + 1).and_then(|next| {
            let p = tick.written_us.saturating_sub(next.latency_us?);
            let c = next.newest_mod4?;
            let first = (sure..avail).find(|&n| {
                let e = &log[inputs[n]];
                e.time_us + POINTER_BEFORE_US >= p && emg_counter(e).is_some_and(|k| k % 4 == c)
            })?;
            let counter = emg_counter(&log[inputs[first]]);
            let last = (first..avail)
                .take_while(|&n| log[inputs[n]].time_us <= p + POINTER_AFTER_US)
                .filter(|&n| emg_counter(&log[inputs[n]]) == counter)
                .last()?;
            Some(last + 1)
        });
        let mut cuts: Vec<usize> = named.into_iter().collect();
        cuts.extend((sure..=avail).rev().filter(|&n| Some(n) != named));
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
            let diag = own()
                .find(|e| e.frame.raw_id() == HAND_DIAG_ID)
                .and_then(|e| HandDiag::decode(e.frame.data()).ok());
            Tick {
                first,
                time_us: log[first].time_us,
                written_us,
                latency_us: diag
                    .as_ref()
                    .map(|d| u64::from(d.tick_latency()))
                    .filter(|&l| l < u64::from(u16::MAX)),
                newest_mod4: diag.map(|d| d.newest_sample()),
            }
        })
        .collect()
}

/// The sample counter of an EMG_SAMPLES frame.
fn emg_counter(e: &LogEntry) -> Option<u8> {
    let d = e.frame.data();
    match e.frame.raw_id() {
        0x100 => EmgSamplesG0::decode(d).ok().map(|m| m.counter()),
        0x101 => EmgSamplesG1::decode(d).ok().map(|m| m.counter()),
        0x102 => EmgSamplesG2::decode(d).ok().map(|m| m.counter()),
        _ => None,
    }
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
