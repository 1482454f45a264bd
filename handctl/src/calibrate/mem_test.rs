//! The whole calibration in memory (issue 14's last check): the cued patient of `hand-model`
//! on the in-memory bus, the sequencer on a virtual clock, recording, the per-trial checks with
//! one weak attempt caught and repeated, Ctrl-C and `--resume`, the session, training.

use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use decoder::session::{check_gates, GateConfig, GateKind, Session, TrialKind};
use hand_dbc::CanFrame;
use hand_model::patient::CuedConfig;
use hand_model::world::{PatientMode, World, WorldConfig};
use hand_model::{Clock, MemBus, MemEndpoint, VirtualClock};

use super::error::CalibrateError;
use super::output::{Mode, Output};
use super::protocol::Protocol;
use super::workflow::{record_session, Pace, Plan, Recorded, Transport};

/// The tool's own endpoint on the in-memory bus.
struct MemTransport(MemEndpoint);

impl Transport for MemTransport {
    fn send(&mut self, frame: &CanFrame) -> Result<(), CalibrateError> {
        self.0
            .send(frame)
            .map_err(|e| CalibrateError::Bus(e.to_string()))
    }

    fn receive(&mut self) -> Result<Option<(CanFrame, u64)>, CalibrateError> {
        Ok(self
            .0
            .receive_timestamped()
            .map(|r| (r.frame, r.time_us.unwrap_or(0))))
    }
}

/// The virtual clock: waiting steps the simulated world (amplifier, fingers, the cued patient)
/// in 1 ms steps; at `stop_at` it raises the stop flag, as Ctrl-C would.
struct SimClock {
    clock: VirtualClock,
    world: World<MemEndpoint>,
    stop_at: Option<(u64, Arc<AtomicBool>)>,
}

impl Pace for SimClock {
    fn now_us(&mut self) -> u64 {
        self.clock.now_us()
    }

    fn wait_until(&mut self, t_us: u64) {
        let mut now = self.clock.now_us();
        while now < t_us {
            now = ((now / 1000 + 1) * 1000).min(t_us);
            self.clock.set_us(now);
            self.world.step(now);
        }
        if let Some((at, flag)) = &self.stop_at {
            if now >= *at {
                flag.store(true, Ordering::Relaxed);
            }
        }
    }
}

/// A world with the cued patient `cued` starting at `start_us`, and the tool's transport.
fn rig(start_us: u64, cued: CuedConfig) -> (MemTransport, SimClock) {
    let clock = VirtualClock::new();
    clock.set_us(start_us);
    let bus = MemBus::with_clock(clock.clone()).with_capacity(1 << 14);
    let tool = MemTransport(bus.endpoint());
    let patient = PatientMode::cued(cued).expect("a valid cued patient");
    let cfg = WorldConfig {
        start_us,
        ..WorldConfig::default()
    };
    let world = World::try_new(cfg, patient, || {
        Ok::<_, std::convert::Infallible>(bus.endpoint())
    })
    .expect("a world");
    let sim = SimClock {
        clock,
        world,
        stop_at: None,
    };
    (tool, sim)
}

/// Two rounds of rest, index flexion and extension, whole-hand flexion and extension.
const SHORT: &str = "repetitions = 2\nprepare_s = 0.5\nhold_s = 1.5\nrest_s = 2.0\nrelax_s = 1.0\n\
                     fingers = [\"index\", \"all\"]\nmax_attempts = 3\n";
/// The protocol's trial 6 (0-based; the cue's Trial): round 2's index flexion.
const WEAK: u8 = 6;

fn run(
    dir: &Path,
    start_us: u64,
    stop_at: Option<u64>,
    resume: bool,
) -> Result<Recorded, CalibrateError> {
    let cued = CuedConfig {
        seed: start_us + 1,
        weak_trial: Some(WEAK),
        ..CuedConfig::default()
    };
    let (mut bus, mut sim) = rig(start_us, cued);
    let stop = Arc::new(AtomicBool::new(false));
    sim.stop_at = stop_at.map(|t| (t, Arc::clone(&stop)));
    let plan = Plan {
        protocol: (!resume).then(|| Protocol::parse(SHORT, "short").expect("valid")),
        dir: dir.to_path_buf(),
        iface: "mem0".into(),
        chain: super::chain(50),
        resume,
        max_resume_age_min: super::resume_check::DEFAULT_MAX_RESUME_AGE_MIN,
        force_rest_mismatch: false,
    };
    let mut out = Output::new(Mode::Quiet, 10);
    record_session(&mut bus, &mut sim, &plan, &mut out, &stop)
}

#[test]
fn the_cued_patient_is_calibrated_in_memory_the_weak_trial_repeated_and_a_ctrl_c_resumed() {
    let dir = std::env::temp_dir().join(format!("handctl-calibrate-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    // Ctrl-C 10 s in: trials 1..3 done (3.5 + 3 + 3 s), the 4th running.
    let first = run(&dir, 1_000_000, Some(11_000_000), false);
    let Err(CalibrateError::Interrupted { kept, next, .. }) = first else {
        panic!("expected the interruption, got {first:?}")
    };
    assert_eq!((kept, next), (3, 4));
    let partial = Session::open(&dir).expect("a consistent partial session");
    assert_eq!(partial.meta.trials.len(), 3);
    // Three hours later it is no longer the same fitting: refused, its age named, the log
    // untouched.
    let log = std::fs::metadata(dir.join("frames.log"))
        .expect("log")
        .len();
    let late = run(&dir, 3 * 3_600_000_000 + 2_000_000, None, true);
    let Err(CalibrateError::Resume(why)) = late else {
        panic!("expected the age refusal, got {late:?}")
    };
    assert!(why.contains("started 3 h 00 min ago"), "{why}");
    assert_eq!(
        std::fs::metadata(dir.join("frames.log"))
            .expect("log")
            .len(),
        log
    );
    // Resumed later on the same log (the amplifier restarted: a gap in the recording), after
    // the live rest is compared with the session's rest trial.
    let done = run(&dir, 30_000_000, None, true).expect("the rest of the protocol");
    assert_eq!(done.kept, 10);
    // The weak attempt was caught once, by the repetition gate, and repeated.
    assert_eq!(done.repeats.len(), 1, "{:?}", done.repeats);
    let weak = &done.repeats[0];
    assert_eq!((weak.trial.id, weak.attempt), (u32::from(WEAK) + 1, 0));
    assert!(weak.reasons[0].contains("only"), "{:?}", weak.reasons);
    println!("caught: {}", weak.reasons[0]);
    println!(
        "reactions measured, ms: {:?}",
        done.reactions_us
            .iter()
            .map(|r| r / 1000)
            .collect::<Vec<_>>()
    );
    let session = Session::open(&dir).expect("the session");
    let ids: Vec<u32> = session.meta.trials.iter().map(|t| t.id).collect();
    assert_eq!(ids, (1..=10).collect::<Vec<_>>());
    // The session holds the repeated attempt, after the weak one, not the weak one.
    let kept = session.meta.trials[usize::from(WEAK)];
    assert_eq!((kept.finger, kept.kind), (Some(1), TrialKind::Flexion));
    assert!(
        kept.start_us > weak.trial.end_us,
        "{kept:?} vs the weak {:?}",
        weak.trial
    );
    // Every reaction was measured inside the patient's 250..450 ms (+ the 200 ms RMS window).
    assert!(
        done.reactions_us
            .iter()
            .all(|&r| (200_000..=800_000).contains(&r)),
        "{:?}",
        done.reactions_us
    );
    let report = check_gates(&session, &GateConfig::default()).expect("gates run");
    println!("the calibrated session's gates:\n{report}");
    assert!(report.passed(), "{report}");
    assert_eq!(
        report.patterns.len(),
        2,
        "index and the whole hand: {report}"
    );
    // Independently: the weak attempt in its place fails the calibration's repetition gate.
    let mut meta = session.meta.clone();
    meta.trials[usize::from(WEAK)] = weak.trial;
    let swapped = Session::from_parts(dir.clone(), meta, session.recording.clone()).expect("parts");
    let bad = check_gates(&swapped, &super::check::gate_config()).expect("gates run");
    assert!(
        bad.issues
            .iter()
            .any(|i| i.trial_id == u32::from(WEAK) + 1 && i.kind == GateKind::WeakRepetition),
        "{bad}"
    );
    train_and_summarize(&dir);
    let _ = std::fs::remove_dir_all(&dir);
}

/// The vcan drill's protocol for an inverted finger (tests/tests/vcan/deploy_safety.rs): one
/// round of rest, index, middle and whole-hand flexion and extension.
const INVERTED: &str = "repetitions = 1\nprepare_s = 1.0\nhold_s = 2.0\nrest_s = 3.0\n\
                        relax_s = 1.5\nfingers = [\"index\", \"middle\", \"all\"]\n";

#[test]
fn a_patient_who_inverts_the_index_is_refused_by_the_gates_naming_it_and_no_model_is_written() {
    for seed in [1, 2, 3] {
        let dir = std::env::temp_dir().join(format!(
            "handctl-calibrate-inverted-{seed}-{}",
            std::process::id()
        ));
        let _ = std::fs::remove_dir_all(&dir);
        let cued = CuedConfig {
            seed,
            inverted_finger: Some(1),
            ..CuedConfig::default()
        };
        let (mut bus, mut sim) = rig(1_000_000, cued);
        let plan = Plan {
            protocol: Some(Protocol::parse(INVERTED, "inverted").expect("valid")),
            dir: dir.clone(),
            iface: "mem0".into(),
            chain: super::chain(50),
            resume: false,
            max_resume_age_min: super::resume_check::DEFAULT_MAX_RESUME_AGE_MIN,
            force_rest_mismatch: false,
        };
        let mut out = Output::new(Mode::Quiet, 10);
        let stop = Arc::new(AtomicBool::new(false));
        let done = record_session(&mut bus, &mut sim, &plan, &mut out, &stop)
            .expect("every trial is recorded (one repetition: nothing to compare it with)");
        assert_eq!(done.kept, 7, "rest and six movements");
        let session = Session::open(&dir).expect("the session");
        let report = check_gates(&session, &GateConfig::default()).expect("gates run");
        let scores: Vec<String> = report
            .patterns
            .iter()
            .map(|p| format!("{:?} {:+.2}", p.finger, p.swap_score.unwrap_or(f64::NAN)))
            .collect();
        println!("seed {seed}: swap scores {}", scores.join(", "));
        let swapped: Vec<&GateKind> = report
            .issues
            .iter()
            .map(|i| &i.kind)
            .filter(|k| matches!(k, GateKind::SwappedDirections { .. }))
            .collect();
        assert_eq!(
            swapped,
            [&GateKind::SwappedDirections { finger: Some(1) }],
            "seed {seed}: the index alone is refused as swapped:\n{report}"
        );
        let refused = super::training::train_session(
            &dir,
            &opts(),
            decoder::model::verify::DEFAULT_TOLERANCE,
            None,
        );
        let Err(e) = refused else {
            panic!("seed {seed}: a model was trained on the inverted index")
        };
        assert_eq!(e.exit_code(), 3, "seed {seed}: {e}");
        assert!(
            !dir.join(super::training::MODEL_FILE).exists(),
            "seed {seed}: a model file was written"
        );
        let _ = std::fs::remove_dir_all(&dir);
    }
}

/// calibrate's training options by default (200 epochs at most).
fn opts() -> crate::args::TrainingOpts {
    crate::args::TrainingOpts {
        two_point: false,
        plain: false,
        no_rest_stage: false,
        paper_masks: false,
        seed: 0,
        epochs: 200,
        ignore_gates: false,
        allow_one_direction: false,
        validation: None,
    }
}

fn train_and_summarize(dir: &Path) {
    let trained = super::training::train_session(
        dir,
        &opts(),
        decoder::model::verify::DEFAULT_TOLERANCE,
        Some("P-001"),
    )
    .expect("a verified model");
    assert!(trained.path.exists());
    let loaded =
        decoder::model::TrainedModel::load(&trained.path, Some(&trained.session.meta.chain))
            .expect("the model file loads");
    let origin = loaded
        .provenance()
        .expect("calibrate records the provenance");
    // The calibration date is the session's (the day it began, kept through the resume).
    let began = trained.session.meta.recorded_utc.as_deref();
    assert!(began.is_some(), "calibrate records when the session began");
    assert_eq!(Some(origin.calibrated_utc.as_str()), began);
    let dir_name = dir
        .file_name()
        .expect("a named directory")
        .to_string_lossy();
    assert_eq!(
        (
            origin.patient.as_deref(),
            origin.session.as_str(),
            origin.ignore_gates
        ),
        (Some("P-001"), dir_name.as_ref(), false)
    );
    let fingers = super::summary::summarize(&trained);
    let index = fingers[1];
    assert!(index.windows > 0 && index.monotonic, "{index:?}");
    assert!(index.contrast > 5.0, "{index:?}");
    assert!(index.reach > 0.5, "{index:?}");
    assert_eq!(fingers[0].windows, 0, "the thumb was not in the protocol");
    let text = super::summary::render(&trained, &fingers);
    println!("{text}");
    assert!(
        text.contains("handctl deploy") && text.contains("handctl arm"),
        "{text}"
    );
}
