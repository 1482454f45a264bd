//! Replay of a recorded closed loop: the log's input frames (EMG, finger status, E-stop,
//! amplifier status) go through a fresh engine, built from handd's config and model, tick by
//! tick, and each tick's setpoint frames are compared with the ones handd put on the bus, bit
//! for bit.
//!
//! The log does not say when handd's tick ran: it drains its socket and reads its clock at the
//! start of a tick and writes its setpoints a computation later (a millisecond or more under
//! emulation), so frames logged in between went to the next tick, and the tick's time (which
//! its timeouts and recovery delays compare against) is a little before its frames' time.
//! Only one kind of frame changes what a tick computes: the one that completes a feature
//! vector (every 50 samples). So at each tick the replay considers the drain points of the
//! last [`DRAIN_SEARCH_US`] that differ in the feature vectors they hold (at most a few), at
//! the tick times [`TICK_TIME_OFFSETS_US`] before the setpoints, keeps those whose tick gives
//! the recorded frames bit for bit, and carries them on as hypotheses: two of them may give the
//! same setpoints now (a clamped or slew-limited force, or a safe stop) and differ later, since
//! the velocity integrates every tick. A tick where no hypothesis matches is a difference.

use driver::engine::Engine;
use hand_dbc::candump::LogEntry;
use hand_dbc::messages::{FingerMode, FingerSetpoint};
use hand_dbc::CanFrame;

/// What a replay found.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ReplayReport {
    /// Ticks of the running closed loop whose setpoints match bit for bit.
    pub same: usize,
    /// Ticks that match at no drain point, as µs after the first tick.
    pub different: Vec<u64>,
    /// Ticks whose match needed a drain point before the last input frame logged ahead of the
    /// setpoints (on the first surviving hypothesis).
    pub early_drains: usize,
    /// Most hypotheses carried at once.
    pub widest: usize,
    /// The running closed loop: first and last ACTIVE setpoint, µs.
    pub running: (u64, u64),
}

/// How far back before a tick's setpoints the replay looks for handd's drain point, µs.
pub const DRAIN_SEARCH_US: u64 = 20_000;
/// Candidate tick times, µs before the tick's first setpoint frame, most likely first.
pub const TICK_TIME_OFFSETS_US: [u64; 5] = [0, 500, 1_000, 2_000, 5_000];
/// Most hypotheses carried from one tick to the next.
const MAX_HYPOTHESES: usize = 8;

const SETPOINT_IDS: std::ops::RangeInclusive<u32> = 0x200..=0x204;

/// One way handd's ticks may have drained the log so far.
struct Hypothesis {
    engine: Engine,
    /// Input frames fed (a prefix of the inputs).
    fed: usize,
    /// Whether the last tick drained before the last input logged ahead of its setpoints.
    early: bool,
}

/// Replays `log` (a candump log of the bus, handd's frames included) through an engine made
/// from handd's `config` and its model. Panics with a message if the model does not load or
/// the log holds no running closed loop.
pub fn replay(config: &driver::Config, log: &[LogEntry]) -> ReplayReport {
    let loaded = driver::startup::load_model(&config.model, config.mains_hz).expect("model");
    let from_handd = |id: u32| SETPOINT_IDS.contains(&id) || id == 0x300 || id == 0x301;
    // handd's ticks: each begins with FINGER_SETPOINT_0, followed by the other four.
    let ticks: Vec<usize> = (0..log.len())
        .filter(|&i| log[i].frame.raw_id() == 0x200)
        .collect();
    assert!(ticks.len() > 400, "only {} ticks recorded", ticks.len());
    let t_first = log[ticks[0]].time_us;
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
    let mut engine = Engine::new(
        &loaded.chain,
        loaded.model.predictor(),
        driver::startup::engine_settings(config, loaded.model_id),
        t_first,
    );
    engine.validated(t_first);
    let mut beam = vec![Hypothesis {
        engine,
        fed: 0,
        early: false,
    }];
    // Log indices of the input frames (everything handd did not send), in order.
    let inputs: Vec<usize> = (0..log.len())
        .filter(|&i| !from_handd(log[i].frame.raw_id()))
        .collect();
    let mut report = ReplayReport {
        same: 0,
        different: Vec::new(),
        early_drains: 0,
        widest: 1,
        running,
    };
    for &i in &ticks {
        let t = log[i].time_us;
        let recorded: Vec<&CanFrame> = log[i..]
            .iter()
            .filter(|e| SETPOINT_IDS.contains(&e.frame.raw_id()))
            .take(5)
            .map(|e| &e.frame)
            .collect();
        // Inputs logged before the setpoints, and those old enough to have been drained.
        let avail = inputs.partition_point(|&k| k < i);
        let sure = inputs.partition_point(|&k| k < i && log[k].time_us + DRAIN_SEARCH_US <= t);
        let mut next: Vec<Hypothesis> = Vec::new();
        let mut fallback = None;
        for h in std::mem::take(&mut beam) {
            for (fed, drained) in drain_points(h, sure, avail, &inputs, log) {
                for dt in TICK_TIME_OFFSETS_US {
                    let mut e = drained.clone();
                    let out = tick(&mut e, t.saturating_sub(dt));
                    let matches = out.len() == recorded.len()
                        && out
                            .iter()
                            .zip(&recorded)
                            .all(|(a, b)| a.raw_id() == b.raw_id() && a.data() == b.data());
                    let key = (fed, e.state(), e.faults());
                    if matches {
                        if next.len() < MAX_HYPOTHESES
                            && next
                                .iter()
                                .all(|n| (n.fed, n.engine.state(), n.engine.faults()) != key)
                        {
                            next.push(Hypothesis {
                                engine: e,
                                fed,
                                early: fed < avail,
                            });
                        }
                    } else if fallback.is_none() && fed == avail && dt == 0 {
                        fallback = Some(Hypothesis {
                            engine: e,
                            fed,
                            early: false,
                        });
                    }
                }
            }
        }
        // The closed loop proper: from handd's first ACTIVE setpoint to its last. Before it,
        // the engine's start (handd's clock before its first tick) is not in the log; after
        // it, handsim has ended and the silence timeout falls between tick and send.
        let scored = t >= running.0 && t <= running.1;
        if next.is_empty() {
            if scored {
                report.different.push(t - t_first);
            }
            next.extend(fallback);
        } else if scored {
            report.same += 1;
            report.early_drains += usize::from(next[0].early);
        }
        report.widest = report.widest.max(next.len());
        assert!(!next.is_empty(), "the replay lost every hypothesis");
        beam = next;
    }
    report
}

/// The engine states of `h` drained at each point of `inputs[sure..avail]` that holds a
/// different set of feature vectors, latest first, with the number of inputs fed.
fn drain_points(
    mut h: Hypothesis,
    sure: usize,
    avail: usize,
    inputs: &[usize],
    log: &[LogEntry],
) -> Vec<(usize, Engine)> {
    let feed = |e: &mut Engine, from: usize, to: usize| {
        for &k in &inputs[from..to] {
            e.on_frame(&log[k].frame, log[k].time_us);
        }
    };
    let start = h.fed.max(sure);
    feed(&mut h.engine, h.fed, start);
    let mut cur = h.engine;
    let mut points = Vec::new();
    // Inside a group (the same vectors emitted) only the latest drain point is kept: the
    // frames between change nothing a tick computes from.
    let mut group_start = (start, cur.clone());
    let mut key = cur.vectors_emitted();
    let avail = avail.max(start);
    for n in start..avail {
        feed(&mut cur, n, n + 1);
        if cur.vectors_emitted() != key {
            let (from, mut e) = group_start;
            feed(&mut e, from, n);
            points.push((n, e));
            group_start = (n + 1, cur.clone());
            key = cur.vectors_emitted();
        }
    }
    points.push((avail, cur));
    points.reverse();
    points
}

/// One tick of `e` at `t`: its setpoint frames.
fn tick(e: &mut Engine, t: u64) -> Vec<CanFrame> {
    let out = e
        .tick(t, t)
        .iter()
        .filter(|f| SETPOINT_IDS.contains(&f.raw_id()))
        .copied()
        .collect();
    e.written(t, 0);
    out
}
