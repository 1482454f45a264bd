//! Issue 25, item 7, on the in-memory bus: the signal leaves what the calibration saw and no
//! finger moves the wrong way. The real daemon loop runs a model trained on a simulated
//! calibration; the simulated patient then
//! - contracts harder than at calibration (`Fault::OverEffort`, 2x and 3x the recorded full
//!   effort), each finger flexed and extended in turn;
//! - has an electrode knocked (`Fault::ElectrodePop`) while one finger flexes and again at rest;
//! - wears the electrode band turned by half a spacing (`Fault::ElectrodeShift`), each finger
//!   flexed and extended in turn.
//!
//! What the hand does is read from the setpoints on the bus: each finger's conditioned label
//! (force / kF). A finger moves the wrong way when its label passes 0.1 in a direction the
//! patient did not ask of it in the last [`LOOKBACK_US`] (for a resting finger: either way).
//! The bar (the issue's): no finger the wrong way by more than 0.1 for more than one tick.
//! A safe stop (the plausibility supervisor's `implausible_input`, a saturation) is not a
//! wrong way: it is zero force. Each run prints how long handd held the hand safe and how
//! many ticks each finger followed the patient, so "no wrong way" cannot hide a hand that
//! never moved: at 2x and 3x effort today it is held safe (signal_quality) most of the run.
//!
//! The pop passes since the plausibility check's *alone* test (a channel above 2.5x the next):
//! before it, a pop on channel 7 at rest extended the index to -1.0 for 7 ticks. The shift
//! passes since its *off the patterns* test (`decoder::model::PatternCone`): before it, every
//! finger moved while asked to rest for 15 ticks in a row (largest 0.84), fingers 0-3 against
//! the direction asked for 5 ticks, and handd never left RUNNING. Now the turned band's windows
//! are implausible and the hand is held at rest: safe, and it does not follow the patient
//! either (a band that moved wants refitting; the test asserts the safe stop too).

mod common;

use common::{calibrated_predictor, Rig};
use driver::safety::DaemonState;
use hand_model::faults::{Fault, FaultPlan};
use hand_model::patient::{Intent, Script};
use hand_model::world::PatientMode;

/// The label beyond which a finger moves, label units (the 0.1).
const WRONG: f64 = 0.1;
/// The patient's intents this far back count as asked for: the 200 ms window, the muscles'
/// relaxation and a tick (a flexion's label may outlast the intent; it may never flip).
const LOOKBACK_US: u64 = 700_000;
/// Rest before the scenario starts, so the daemon runs on a full window of rest.
const SETTLE_US: u64 = 1_500_000;

/// Per finger: the longest run of consecutive ticks the wrong way, how many ticks in all, the
/// largest wrong-way label, how many of those ticks it moved against a direction the patient
/// asked (the rest: it moved while asked to rest), and how many ticks it followed the patient
/// (beyond 0.1 the way asked).
#[derive(Debug, Default, Clone, Copy)]
struct Wrong {
    longest: usize,
    ticks: usize,
    largest: f64,
    against: usize,
    followed: usize,
}

/// What a run did: per finger how it went the wrong way, the ticks seen, the ticks handd held
/// the hand safe and the windows it found implausible.
struct Outcome {
    wrong: [Wrong; 5],
    ticks: usize,
    safe: usize,
    implausible: u64,
}

/// Runs `script` with `plan`.
fn run(script: &Script, plan: FaultPlan) -> Outcome {
    let mut asked = script.clone();
    let mut rig = Rig::with_predictor(
        plan,
        PatientMode::Script(script.clone()),
        calibrated_predictor(),
    );
    // The daemon's state at every tick: how much of the run the hand was held safe.
    let (mut t, mut safe) = (0, 0);
    while t < script.duration_us() {
        t += 50_000;
        rig.run_until(t);
        safe += usize::from(t > SETTLE_US && rig.runner.engine().state() == DaemonState::Safe);
    }
    let c = rig.runner.engine().counters();
    println!(
        "  handd: SAFE {safe} ticks (faults at the end {:?}); windows beyond the calibration \
         {}, implausible {}",
        rig.runner.engine().faults(),
        c.beyond_calibration,
        c.implausible
    );
    let kf: Vec<f64> = rig.runner.engine().gains().iter().map(|g| g.kf).collect();
    let mut wrong = [Wrong::default(); 5];
    let mut run_len = [0usize; 5];
    let mut ticks = 0;
    for (t, f, _, force, _) in rig.setpoints() {
        if t < SETTLE_US {
            continue;
        }
        ticks += usize::from(f == 0);
        let label = force / kf[f];
        let from = t.saturating_sub(LOOKBACK_US);
        let (mut pos, mut neg) = (false, false);
        for k in 0..=(LOOKBACK_US / 10_000) {
            let i = asked.intent_at(from + k * 10_000).0[f];
            pos |= i > 0.0;
            neg |= i < 0.0;
        }
        let bad = (label > WRONG && !pos) || (label < -WRONG && !neg);
        let w = &mut wrong[f];
        w.against += usize::from(bad && (pos || neg));
        w.followed += usize::from((label > WRONG && pos) || (label < -WRONG && neg));
        if bad {
            run_len[f] += 1;
            w.ticks += 1;
            w.longest = w.longest.max(run_len[f]);
            w.largest = w.largest.max(label.abs());
        } else {
            run_len[f] = 0;
        }
    }
    Outcome {
        wrong,
        ticks,
        safe,
        implausible: c.implausible,
    }
}

/// Each finger flexed, then extended, at full effort (`hold_us` each, rest between).
fn each_finger_both_ways(hold_us: u64) -> Script {
    let mut s = Script::new();
    s.rest(SETTLE_US);
    for f in 0..5 {
        s.hold(Intent::finger(f, 1.0), hold_us)
            .rest(400_000)
            .hold(Intent::finger(f, -1.0), hold_us)
            .rest(400_000);
    }
    s
}

fn check(what: &str, wrong: &[Wrong; 5], ticks: usize, script: &Script) {
    report(what, wrong, ticks);
    let expected = ((script.duration_us() - SETTLE_US) / 50_000) as usize;
    assert!(
        ticks + 2 >= expected,
        "{what}: only {ticks} ticks of the {expected} the script lasts"
    );
    for (f, w) in wrong.iter().enumerate() {
        assert!(
            w.longest <= 1,
            "{what}: finger {f} moved the wrong way by more than {WRONG} for {} ticks in a row \
             (largest {:.3})",
            w.longest,
            w.largest
        );
    }
}

fn report(what: &str, wrong: &[Wrong; 5], ticks: usize) {
    println!(
        "{what}: {ticks} ticks; per finger the wrong way: longest run, ticks (of them against \
         a direction asked), largest |label|; ticks following the patient"
    );
    for (f, w) in wrong.iter().enumerate() {
        println!(
            "  finger {f}: {} {} ({}) {:.3}; {}",
            w.longest, w.ticks, w.against, w.largest, w.followed
        );
    }
}

#[test]
fn a_stronger_grip_than_the_calibrations_moves_no_finger_the_wrong_way() {
    let script = each_finger_both_ways(600_000);
    let o = run(&script, FaultPlan::new());
    report(
        "the calibration's effort (1x), for comparison",
        &o.wrong,
        o.ticks,
    );
    for pct in [200, 300] {
        let mut plan = FaultPlan::new();
        plan.add_from(Fault::OverEffort { pct }, SETTLE_US)
            .expect("over-effort");
        let o = run(&script, plan);
        check(&format!("over-effort {pct}%"), &o.wrong, o.ticks, &script);
    }
}

#[test]
fn a_knocked_electrode_moves_no_finger_the_wrong_way() {
    let mut script = Script::new();
    script
        .rest(SETTLE_US)
        .hold(Intent::finger(1, 0.6), 1_500_000)
        .rest(2_000_000);
    let mut plan = FaultPlan::new();
    // Channel 1 (over the index flexor) while the index flexes; channel 7 (an extensor's) at
    // rest, where a pop is the whole signal.
    plan.add(
        Fault::ElectrodePop { channel: 1 },
        SETTLE_US + 700_000,
        SETTLE_US + 1_300_000,
    )
    .expect("pop")
    .add(
        Fault::ElectrodePop { channel: 7 },
        SETTLE_US + 2_300_000,
        SETTLE_US + 2_900_000,
    )
    .expect("pop");
    let o = run(&script, plan);
    check("electrode pop", &o.wrong, o.ticks, &script);
}

#[test]
fn a_shifted_electrode_band_moves_no_finger_the_wrong_way() {
    let script = each_finger_both_ways(600_000);
    let mut plan = FaultPlan::new();
    plan.add_from(Fault::ElectrodeShift { tenths: 5 }, 0)
        .expect("shift");
    let o = run(&script, plan);
    check(
        "electrode band shifted half a spacing",
        &o.wrong,
        o.ticks,
        &script,
    );
    // Not by chance: handd saw the band's windows as implausible and held the hand safe.
    assert!(
        o.implausible > 0 && o.safe > o.ticks / 2,
        "the turned band was not caught: {} implausible windows, SAFE {} of {} ticks",
        o.implausible,
        o.safe,
        o.ticks
    );
}
