//! The cued patient with an inverted finger (`CuedConfig::inverted_finger`, `handsim
//! --inverted-finger`): at that finger's own cues it moves the other way, every time, and
//! nothing else changes. Two worlds with the same seeds on the virtual clock, one patient
//! inverted and one not, get the same cue sequence (every finger and the whole hand, flexion
//! and extension); their intents and the EMG channel patterns on the bus are compared.

mod common;

use common::{rms_ac, Harness};
use hand_dbc::e2e::E2eProtector;
use hand_dbc::emg::{EmgFrame, CHANNELS_PER_GROUP, EMG_CHANNELS};
use hand_dbc::messages::{CalibrationCue, CueKind, CuePhase};
use hand_model::bus::MemEndpoint;
use hand_model::patient::{CuedConfig, Intent};
use hand_model::world::{PatientMode, World, WorldConfig};

/// The inverted finger: the index.
const INVERTED: usize = 1;
/// Every movement cued: each finger (0..4) and the whole hand (5), flexion then extension.
const MOVEMENTS: [(u8, CueKind); 12] = {
    let mut out = [(0, CueKind::Flexion); 12];
    let mut i = 0;
    while i < 12 {
        let kind = if i % 2 == 0 {
            CueKind::Flexion
        } else {
            CueKind::Extension
        };
        out[i] = ((i / 2) as u8, kind);
        i += 1;
    }
    out
};
/// Each movement's cues: PREPARE, HOLD, RELAX, µs (a slot of 3 s from 0.5 s on).
const PREPARE_US: u64 = 500_000;
const HOLD_US: u64 = 1_500_000;
const RELAX_US: u64 = 1_000_000;
const SLOT_US: u64 = PREPARE_US + HOLD_US + RELAX_US;
const FIRST_US: u64 = 500_000;
/// A hold's plateau: 650 ms after its HOLD cue at the latest (reaction + rise).
const PLATEAU_AFTER_US: u64 = 700_000;

/// The cue of movement `m` at `t_us` (rest before the first and after the last).
fn cue_at(t_us: u64) -> CalibrationCue {
    let idle = || {
        CalibrationCue::new(CuePhase::Idle, 255, 15, CueKind::Rest, 0, 0, 0.0, 0).expect("in range")
    };
    if t_us < FIRST_US {
        return idle();
    }
    let m = ((t_us - FIRST_US) / SLOT_US) as usize;
    let Some(&(finger, kind)) = MOVEMENTS.get(m) else {
        return idle();
    };
    let into = (t_us - FIRST_US) % SLOT_US;
    let phase = if into < PREPARE_US {
        CuePhase::Prepare
    } else if into < PREPARE_US + HOLD_US {
        CuePhase::Hold
    } else {
        CuePhase::Relax
    };
    CalibrationCue::new(phase, m as u8, finger, kind, 0, 0, 1.0, 100).expect("in range")
}

/// The HOLD of movement `m`: [start, end) µs.
fn hold_of(m: usize) -> (u64, u64) {
    let start = FIRST_US + m as u64 * SLOT_US + PREPARE_US;
    (start, start + HOLD_US)
}

/// One world's run: its patient's intent every ms and its EMG frames with receive times.
struct Run {
    intents: Vec<Intent>,
    emg: Vec<(u64, EmgFrame)>,
    inverted_holds: u64,
}

fn run(inverted_finger: Option<u8>) -> Run {
    let mut h = Harness::new();
    let patient = PatientMode::cued(CuedConfig {
        seed: 11,
        inverted_finger,
        ..CuedConfig::default()
    })
    .expect("a valid cued patient");
    let bus = h.bus.clone();
    let mut world = World::try_new(WorldConfig::default(), patient, || {
        Ok::<_, std::convert::Infallible>(bus.endpoint())
    })
    .expect("a world");
    let mut tool: MemEndpoint = h.bus.endpoint();
    let mut protect = E2eProtector::new(CalibrationCue::E2E);
    let mut intents = Vec::new();
    let end = FIRST_US + MOVEMENTS.len() as u64 * SLOT_US;
    h.run(end, |t| {
        if t % 100_000 == 0 {
            let frame = protect.protect_message(&cue_at(t)).expect("profile 1");
            tool.send(&frame).expect("the bus takes the cue");
        }
        world.step(t);
        intents.push(world.intent());
    });
    let PatientMode::Cued(p) = world.patient() else {
        panic!("a cued patient")
    };
    let inverted_holds = p.stats().inverted_holds;
    let emg = h
        .log
        .iter()
        .filter_map(|r| {
            let f = EmgFrame::decode(r.frame.raw_id(), r.frame.data()).ok()??;
            Some((r.time_us.expect("the harness bus has a clock"), f))
        })
        .collect();
    Run {
        intents,
        emg,
        inverted_holds,
    }
}

/// Per-channel AC RMS of the EMG received in [from, to), raw units.
fn profile(emg: &[(u64, EmgFrame)], from: u64, to: u64) -> [f64; EMG_CHANNELS] {
    std::array::from_fn(|ch| {
        let (g, k) = (ch / CHANNELS_PER_GROUP, ch % CHANNELS_PER_GROUP);
        let v: Vec<f64> = emg
            .iter()
            .filter(|(t, f)| (from..to).contains(t) && usize::from(f.group()) == g)
            .map(|(_, f)| f64::from(f.raw()[k]))
            .collect();
        rms_ac(&v)
    })
}

/// Pearson's r of two channel profiles.
fn pearson(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len() as f64;
    let (ma, mb) = (a.iter().sum::<f64>() / n, b.iter().sum::<f64>() / n);
    let (mut ab, mut aa, mut bb) = (0.0, 0.0, 0.0);
    for (x, y) in a.iter().zip(b) {
        ab += (x - ma) * (y - mb);
        aa += (x - ma) * (x - ma);
        bb += (y - mb) * (y - mb);
    }
    ab / (aa * bb).sqrt()
}

#[test]
fn the_inverted_finger_moves_the_other_way_at_its_own_cues_and_nothing_else_changes() {
    let plain = run(None);
    let inv = run(Some(INVERTED as u8));
    assert_eq!(plain.inverted_holds, 0);
    assert_eq!(
        inv.inverted_holds, 2,
        "one inverted hold per cue of the index finger (its flexion and its extension)"
    );
    // Intent, every ms: the negation on the inverted finger from its own HOLD cues until the
    // next movement's PREPARE (its relax takes at most 950 ms of the 1 s RELAX); the same
    // everywhere else, bit for bit (same seed: same reaction delays and effort shortfalls).
    let index_slots: Vec<(u64, u64)> = MOVEMENTS
        .iter()
        .enumerate()
        .filter(|(_, (f, _))| usize::from(*f) == INVERTED)
        .map(|(m, _)| (hold_of(m).0, hold_of(m).1 + RELAX_US))
        .collect();
    let (mut negated, mut moved) = (0usize, 0usize);
    for (ms, (a, b)) in plain.intents.iter().zip(&inv.intents).enumerate() {
        let t = ms as u64 * 1000;
        let in_index_slot = index_slots.iter().any(|&(s, e)| (s..e).contains(&t));
        for f in 0..a.0.len() {
            if f == INVERTED && in_index_slot {
                assert_eq!(
                    b.0[f], -a.0[f],
                    "at {t} µs the inverted finger's intent {} is not the negation of {}",
                    b.0[f], a.0[f]
                );
                negated += usize::from(a.0[f] != 0.0);
            } else {
                assert_eq!(
                    b.0[f], a.0[f],
                    "at {t} µs finger {f}'s intent differs ({} against {}) outside the \
                     inverted finger's own cues",
                    b.0[f], a.0[f]
                );
                moved += usize::from(a.0[f] != 0.0);
            }
        }
    }
    assert!(
        negated > 2 * 1000 && moved > 10 * 1000,
        "too little movement compared: {negated} ms inverted, {moved} finger-ms the same"
    );
    // The EMG channel pattern on the bus: at the index's flexion cue the inverted patient
    // shows the plain patient's index extension pattern, and the reverse; every other
    // movement's pattern is the plain one's.
    let plateau = |r: &Run, m: usize| {
        let (s, e) = hold_of(m);
        profile(&r.emg, s + PLATEAU_AFTER_US, e)
    };
    for (m, &(finger, kind)) in MOVEMENTS.iter().enumerate() {
        let mine = plateau(&inv, m);
        let same = pearson(&mine, &plateau(&plain, m));
        if usize::from(finger) == INVERTED {
            // The index's other cue is the neighbouring movement (flexion, then extension).
            let other = if kind == CueKind::Flexion {
                m + 1
            } else {
                m - 1
            };
            let swapped = pearson(&mine, &plateau(&plain, other));
            println!(
                "index {kind:?} cue: r against the plain patient's same cue {same:.3}, against \
                 its opposite cue {swapped:.3}"
            );
            assert!(
                swapped > 0.95 && same < 0.5,
                "the inverted index's {kind:?} pattern is not the plain one's opposite \
                 (r {swapped:.3} with the opposite cue, {same:.3} with the same)"
            );
        } else {
            assert!(
                same > 0.95,
                "movement {m} (finger {finger}, {kind:?}) changed its pattern (r {same:.3})"
            );
        }
    }
}
