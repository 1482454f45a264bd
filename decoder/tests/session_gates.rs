//! Quality gates: each fires on its fault with a message naming the trial; a clean session passes.

mod session_support;

use decoder::session::{check_gates, GateConfig, GateKind, Session, SessionMeta, TrialKind};
use session_support::*;

fn session_of(
    trials: &[SynthTrial],
    seed: u64,
    edit: impl FnOnce(&mut Vec<f64>, &SessionMeta),
) -> Session {
    let (mut samples, meta) = synth(trials, seed);
    edit(&mut samples, &meta);
    let rec = decoder::session::Recording::from_samples(CHANNELS, samples, RATE).unwrap();
    Session::from_parts("synthetic".into(), meta, rec).unwrap()
}

fn trial_range(meta: &SessionMeta, id: u32) -> std::ops::Range<usize> {
    let t = meta.trials.iter().find(|t| t.id == id).unwrap();
    (t.start_us / 1000) as usize..(t.end_us / 1000) as usize
}

#[test]
fn a_clean_session_passes() {
    let s = session_of(&clean_protocol(), 10, |_, _| {});
    let r = check_gates(&s, &GateConfig::default()).unwrap();
    assert!(r.passed(), "{r}");
    assert!(r.notes.is_empty());
    assert!(r.to_string().contains("all quality gates passed"));
}

#[test]
fn saturation_is_caught() {
    let s = session_of(&clean_protocol(), 11, |x, m| {
        // Trial 2 (finger 0 flexion): channel 0 clips at the rail in a fifth of its samples.
        for i in trial_range(m, 2).step_by(5) {
            x[i * CHANNELS] = 2047.0;
        }
    });
    let r = check_gates(&s, &GateConfig::default()).unwrap();
    // The clipped spikes also inflate the trial's RMS, so its second repetition may look weak
    // beside it; the saturation itself is reported exactly once.
    let sat: Vec<_> = r
        .issues
        .iter()
        .filter(|i| matches!(i.kind, GateKind::Saturated { .. }))
        .collect();
    assert_eq!(sat.len(), 1, "{r}");
    assert_eq!(sat[0].trial_id, 2);
    assert_eq!(sat[0].kind, GateKind::Saturated { channel: 0 });
    assert!(
        sat[0].message.contains("trial 2") && sat[0].message.contains("saturated"),
        "{r}"
    );
}

#[test]
fn a_flat_channel_is_caught() {
    let s = session_of(&clean_protocol(), 12, |x, m| {
        for i in trial_range(m, 4) {
            x[i * CHANNELS + 3] = 17.0; // lead-off: the channel sits at a constant
        }
    });
    let r = check_gates(&s, &GateConfig::default()).unwrap();
    assert!(
        r.issues
            .iter()
            .any(|i| i.trial_id == 4 && i.kind == GateKind::Flat { channel: 3 }),
        "{r}"
    );
    assert!(r.issues.iter().all(|i| i.trial_id == 4), "{r}");
    assert!(r.to_string().contains("channel 3 is flat"), "{r}");
}

#[test]
fn a_noisy_electrode_is_caught_and_named() {
    let mut trials = clean_protocol();
    // Channel 1 picks up eight times the others' noise at rest: a loose electrode.
    for t in trials.iter_mut().filter(|t| t.kind == TrialKind::Rest) {
        t.amps[1] = 8.0 * REST_AMP;
    }
    let s = session_of(&trials, 15, |_, _| {});
    let r = check_gates(&s, &GateConfig::default()).unwrap();
    let noisy: Vec<_> = r
        .issues
        .iter()
        .filter(|i| matches!(i.kind, GateKind::Noisy { .. }))
        .collect();
    assert_eq!(noisy.len(), 1, "{r}");
    assert_eq!(noisy[0].kind, GateKind::Noisy { channel: 1 });
    assert_eq!(noisy[0].trial_id, 1, "reported on the first rest trial");
    let m = &noisy[0].message;
    assert!(
        m.contains("channel 1 is noisy") && m.contains("re-seat"),
        "{m}"
    );
    // The clean protocol has no noisy channel (a_clean_session_passes checks every gate).
    let clean = session_of(&clean_protocol(), 15, |_, _| {});
    let r = check_gates(&clean, &GateConfig::default()).unwrap();
    assert!(
        !r.issues
            .iter()
            .any(|i| matches!(i.kind, GateKind::Noisy { .. })),
        "{r}"
    );
}

#[test]
fn low_contrast_against_rest_is_caught() {
    let mut trials = clean_protocol();
    // Trial 3 (finger 0 extension, repetition 1) barely contracts.
    trials[2].amps = [REST_AMP * 1.2; CHANNELS];
    let s = session_of(&trials, 13, |_, _| {});
    let r = check_gates(&s, &GateConfig::default()).unwrap();
    let mine: Vec<_> = r
        .issues
        .iter()
        .filter(|i| i.kind == GateKind::LowContrast)
        .collect();
    assert_eq!(mine.len(), 1, "{r}");
    assert_eq!(mine[0].trial_id, 3);
    assert!(mine[0].message.contains("x the RMS of rest"), "{r}");
}

#[test]
fn a_weak_repetition_is_caught() {
    let mut trials = clean_protocol();
    // Trial 7 is finger 0 flexion, repetition 2: at a third of repetition 1's effort.
    assert_eq!((trials[6].finger, trials[6].repetition), (Some(0), 2));
    for a in &mut trials[6].amps {
        if *a > REST_AMP {
            *a /= 3.0;
        }
    }
    let s = session_of(&trials, 14, |_, _| {});
    let r = check_gates(&s, &GateConfig::default()).unwrap();
    let weak: Vec<_> = r
        .issues
        .iter()
        .filter(|i| i.kind == GateKind::WeakRepetition)
        .collect();
    assert_eq!(weak.len(), 1, "{r}");
    assert_eq!(weak[0].trial_id, 7);
    assert!(
        weak[0].message.contains("trial 2"),
        "names the stronger repetition: {r}"
    );
}

#[test]
fn without_rest_the_contrast_gate_says_it_did_not_run() {
    let trials: Vec<SynthTrial> = clean_protocol()
        .into_iter()
        .filter(|t| t.kind != decoder::session::TrialKind::Rest)
        .collect();
    let s = session_of(&trials, 15, |_, _| {});
    let r = check_gates(&s, &GateConfig::default()).unwrap();
    assert!(r.passed(), "{r}");
    assert_eq!(r.notes.len(), 1);
    assert!(r.notes[0].contains("no rest trial"));
}

#[test]
fn a_trial_broken_into_short_pieces_gives_no_window_and_says_why() {
    let (samples, meta) = synth(&clean_protocol(), 16);
    let mut rec = decoder::session::Recording::from_samples(CHANNELS, samples, RATE).unwrap();
    // Trial 4's EMG stream breaks every 150 samples: no 200-sample window is whole.
    let range = trial_range(&meta, 4);
    rec.breaks = (range.start + 150..range.end).step_by(150).collect();
    let pieces = rec.breaks.len();
    let s = Session::from_parts("synthetic".into(), meta, rec).unwrap();
    let r = check_gates(&s, &GateConfig::default()).unwrap();
    let none: Vec<_> = r
        .issues
        .iter()
        .filter(|i| i.kind == GateKind::NoWindows)
        .collect();
    assert_eq!(none.len(), 1, "{r}");
    assert_eq!(none[0].trial_id, 4);
    let m = &none[0].message;
    assert!(
        m.contains(&format!("{} EMG samples", range.len()))
            && m.contains(&format!("{pieces} break(s)"))
            && m.contains("200 ms of unbroken"),
        "{m}"
    );
}
