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
    // Fingers 2..4 are in no trial: said once, not a refusal.
    assert_eq!(r.notes.len(), 1, "{r}");
    assert!(
        r.notes[0].contains("middle, ring, pinky: trained toward 0 only"),
        "{r}"
    );
    assert!(r.to_string().contains("all quality gates passed"));
    // The pattern figures of both fingers: repetitions alike, flexion unlike extension.
    assert_eq!(r.patterns.len(), 2, "{r}");
    for p in &r.patterns {
        assert_eq!(p.repetitions.len(), 4, "{p}");
        assert!(p.repetitions.iter().all(|x| x.2 > 0.99), "{p}");
        assert!(p.flexion_extension.expect("both kinds") < 0.5, "{p}");
        assert_eq!(
            p.swap_score, None,
            "two movements: no reference for the swap gate"
        );
    }
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
    assert!(r.notes.iter().any(|n| n.contains("no rest trial")), "{r}");
    // Without rest, the profiles are compared without subtracting a rest level.
    assert_eq!(r.patterns.len(), 2, "{r}");
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

/// The clean protocol with a third round (rest, fingers 0 and 1 flexion and extension).
fn three_rounds() -> Vec<SynthTrial> {
    let mut v = clean_protocol();
    let third: Vec<SynthTrial> = v[..5]
        .iter()
        .map(|t| SynthTrial {
            repetition: 3,
            ..t.clone()
        })
        .collect();
    v.extend(third);
    v
}

fn issues_of(r: &decoder::session::GateReport, kind: GateKind) -> Vec<u32> {
    r.issues
        .iter()
        .filter(|i| i.kind == kind)
        .map(|i| i.trial_id)
        .collect()
}

#[test]
fn a_trial_with_too_few_windows_is_caught() {
    let (samples, mut meta) = synth(&clean_protocol(), 17);
    // Trial 4 (finger 1 flexion) lasts 0.3 s: 3 windows of 200 ms at the 50 ms step.
    let t = meta.trials.iter_mut().find(|t| t.id == 4).unwrap();
    t.end_us = t.start_us + 300_000;
    let rec = decoder::session::Recording::from_samples(CHANNELS, samples, RATE).unwrap();
    let s = Session::from_parts("synthetic".into(), meta, rec).unwrap();
    let r = check_gates(&s, &GateConfig::default()).unwrap();
    let few: Vec<_> = r
        .issues
        .iter()
        .filter(|i| matches!(i.kind, GateKind::FewWindows { .. }))
        .collect();
    assert_eq!(few.len(), 1, "{r}");
    assert_eq!(
        (few[0].trial_id, few[0].kind),
        (4, GateKind::FewWindows { windows: 3 })
    );
    assert!(
        few[0].message.contains("at least 5") && few[0].message.contains("400 ms of hold"),
        "{r}"
    );
    // Left out of the pattern gates, which say so.
    assert!(
        r.notes
            .iter()
            .any(|n| n.contains("single usable repetition of index flexion")),
        "{r}"
    );
    assert_eq!(decoder::session::MIN_WINDOWS_PER_TRIAL, 5);
}

#[test]
fn a_repetition_with_another_pattern_is_caught() {
    let mut trials = three_rounds();
    // Trial 7 (finger 0 flexion, repetition 2): the patient extended instead.
    assert_eq!(
        (trials[6].finger, trials[6].kind, trials[6].repetition),
        (Some(0), TrialKind::Flexion, 2)
    );
    trials[6].amps = trials[2].amps;
    let s = session_of(&trials, 18, |_, _| {});
    let r = check_gates(&s, &GateConfig::default()).unwrap();
    assert_eq!(issues_of(&r, GateKind::InconsistentPattern), vec![7], "{r}");
    let m = &r.issues.iter().find(|i| i.trial_id == 7).unwrap().message;
    assert!(
        m.contains("trial(s) 2, 12") && m.contains("another movement"),
        "{m}"
    );
    // Nothing else: same effort, contrast and channels.
    assert!(
        r.issues
            .iter()
            .all(|i| i.kind == GateKind::InconsistentPattern),
        "{r}"
    );
}

#[test]
fn a_finger_whose_flexion_is_its_extension_is_refused() {
    let mut trials = clean_protocol();
    // The patient extends finger 0 at every flexion cue.
    for rep in [0, 5] {
        trials[rep + 1].amps = trials[rep + 2].amps;
    }
    let s = session_of(&trials, 19, |_, _| {});
    let r = check_gates(&s, &GateConfig::default()).unwrap();
    let same = issues_of(&r, GateKind::FlexionLikeExtension { finger: Some(0) });
    assert_eq!(same, vec![2], "reported on the first flexion: {r}");
    let m = &r.issues.iter().find(|i| i.trial_id == 2).unwrap().message;
    assert!(
        m.contains("thumb: flexion (trial(s) 2, 7) and extension (trial(s) 3, 8)"),
        "{m}"
    );
    assert_eq!(r.issues.len(), 1, "{r}");
}

/// An anatomical layout: channels 0 and 1 over the flexors, 2 and 3 over the extensors; finger
/// 0 on channels 0 and 2, finger 1 on 1 and 3, the whole hand on both of its side.
fn anatomical(swap_finger_1: bool) -> Vec<SynthTrial> {
    let a = ACTIVE_AMP;
    let c = 0.3 * ACTIVE_AMP;
    let mut v = Vec::new();
    for rep in 1..=2 {
        v.push(SynthTrial {
            finger: None,
            kind: TrialKind::Rest,
            repetition: rep,
            amps: [REST_AMP; 4],
        });
        let moves = [
            (
                Some(0),
                [a, c, REST_AMP, REST_AMP],
                [REST_AMP, REST_AMP, a, c],
            ),
            (
                Some(1),
                [c, a, REST_AMP, REST_AMP],
                [REST_AMP, REST_AMP, c, a],
            ),
            (None, [a, a, REST_AMP, REST_AMP], [REST_AMP, REST_AMP, a, a]),
        ];
        for (finger, flex, ext) in moves {
            let (flex, ext) = if swap_finger_1 && finger == Some(1) {
                (ext, flex)
            } else {
                (flex, ext)
            };
            for (kind, amps) in [(TrialKind::Flexion, flex), (TrialKind::Extension, ext)] {
                v.push(SynthTrial {
                    finger,
                    kind,
                    repetition: rep,
                    amps,
                });
            }
        }
    }
    v
}

#[test]
fn a_finger_swapped_against_the_other_movements_is_refused() {
    let s = session_of(&anatomical(false), 20, |_, _| {});
    let r = check_gates(&s, &GateConfig::default()).unwrap();
    assert!(r.passed(), "{r}");
    assert_eq!(r.patterns.len(), 3, "{r}");
    assert!(
        r.patterns.iter().all(|p| p.swap_score.expect("ran") > 1.0),
        "{r}"
    );
    // Finger 1 flexes at the extension cue and extends at the flexion cue: consistent and
    // distinct, only swapped.
    let s = session_of(&anatomical(true), 20, |_, _| {});
    let r = check_gates(&s, &GateConfig::default()).unwrap();
    let swapped = issues_of(&r, GateKind::SwappedDirections { finger: Some(1) });
    assert_eq!(swapped, vec![4], "on its first flexion: {r}");
    assert!(
        !r.issues
            .iter()
            .any(|i| i.kind == GateKind::SwappedDirections { finger: Some(0) }),
        "the correct finger 0 is not blamed: {r}"
    );
    assert!(
        r.to_string().contains("index: its flexion looks like"),
        "{r}"
    );
}

#[test]
fn a_finger_moved_in_one_direction_only_is_refused_and_not_ignorable() {
    // No extension of finger 0 at all.
    let trials: Vec<SynthTrial> = clean_protocol()
        .into_iter()
        .filter(|t| !(t.finger == Some(0) && t.kind == TrialKind::Extension))
        .collect();
    let s = session_of(&trials, 21, |_, _| {});
    let r = check_gates(&s, &GateConfig::default()).unwrap();
    let one: Vec<_> = r.binding().collect();
    assert_eq!(one.len(), 1, "{r}");
    assert_eq!(
        (one[0].trial_id, one[0].kind),
        (
            2,
            GateKind::OneDirection {
                finger: 0,
                missing: TrialKind::Extension
            }
        )
    );
    assert!(!one[0].kind.can_be_ignored());
    assert!(
        one[0]
            .message
            .contains("thumb: the session has flexion trials")
            && one[0].message.contains("no extension trial")
            && one[0].message.contains("--ignore-gates does not override"),
        "{r}"
    );
    // Every other gate's issue can be ignored.
    assert!(GateKind::InconsistentPattern.can_be_ignored());
    // Whole-hand trials count for every finger: with a whole-hand flexion and extension the
    // thumb has its extension anchor (and the other fingers both).
    let mut trials = trials;
    for (kind, amps) in [
        (
            TrialKind::Flexion,
            [ACTIVE_AMP, REST_AMP, ACTIVE_AMP, REST_AMP],
        ),
        (
            TrialKind::Extension,
            [REST_AMP, ACTIVE_AMP, REST_AMP, ACTIVE_AMP],
        ),
    ] {
        trials.push(SynthTrial {
            finger: None,
            kind,
            repetition: 1,
            amps,
        });
    }
    let s = session_of(&trials, 21, |_, _| {});
    let r = check_gates(&s, &GateConfig::default()).unwrap();
    assert_eq!(r.binding().count(), 0, "{r}");
    // A whole-hand extension alone gives the fingers never flexed one direction only.
    trials.truncate(trials.len() - 2);
    trials.push(SynthTrial {
        finger: None,
        kind: TrialKind::Extension,
        repetition: 1,
        amps: [REST_AMP, ACTIVE_AMP, REST_AMP, ACTIVE_AMP],
    });
    let s = session_of(&trials, 21, |_, _| {});
    let r = check_gates(&s, &GateConfig::default()).unwrap();
    let fingers: Vec<usize> = r
        .binding()
        .map(|i| match i.kind {
            GateKind::OneDirection { finger, missing } => {
                assert_eq!(missing, TrialKind::Flexion);
                finger
            }
            other => panic!("{other:?}"),
        })
        .collect();
    assert_eq!(fingers, vec![2, 3, 4], "{r}");
}

#[test]
fn pearson_needs_a_shape() {
    use decoder::session::pearson;
    assert_eq!(pearson(&[1.0, 2.0], &[2.0, 1.0]), None, "two channels");
    assert_eq!(pearson(&[3.0; 4], &[1.0, 2.0, 3.0, 4.0]), None, "flat");
    let r = pearson(&[1.0, 2.0, 3.0, 4.0], &[10.0, 20.0, 30.0, 40.0]).unwrap();
    assert!((r - 1.0).abs() < 1e-12);
    let r = pearson(&[1.0, 2.0, 3.0, 4.0], &[4.0, 3.0, 2.0, 1.0]).unwrap();
    assert!((r + 1.0).abs() < 1e-12);
}
