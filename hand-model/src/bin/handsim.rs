//! `handsim`: runs the simulated amplifier, motor controllers, patient and faults on a
//! SocketCAN interface in real time (beside a real daemon), or on the in-memory bus as fast
//! as possible (`--mem`, for tests and for a quick look at the traffic).

use std::collections::BTreeMap;
use std::process::ExitCode;
use std::time::Duration;

use clap::Parser;
use hand_dbc::candump::LogWriter;
use hand_model::clock::{Clock, SystemClock};
use hand_model::emg::AmplifierConfig;
use hand_model::faults::{Fault, FaultPlan};
use hand_model::finger::FingerConfig;
use hand_model::nodes::{AmplifierNodeConfig, Bus};
use hand_model::patient::CuedConfig;
use hand_model::record::run_on_mem_bus;
use hand_model::scenario::{Scenario, ScenarioRun};
use hand_model::socketcan_bus::SocketCanBus;
use hand_model::world::{NodeSelection, World, WorldConfig};
use hand_model::SimError;

/// After the options in `handsim --help`.
const AFTER_HELP: &str = "\
Scenario cued (the simulated patient of `handctl calibrate`): the patient reads CALIBRATION_CUE
frames (0x380, E2E-valid only) from the bus and acts on them like a person: after a reaction
delay of 250-450 ms (seeded by --seed) it contracts the cued finger, or the whole hand, in the
cued direction at the cued effort while the phase is HOLD (reaching it within 200 ms more), and
lets go (over 500 ms) on RELAX, PREPARE, IDLE, DONE or ABORTED. Without a valid cue for 1 s it
rests; with none at all it rests for the whole run (30 min unless --duration). E.g. beside
handd:  handsim --iface vcan0 --scenario cued --weak-trial 3
(--inverted-finger 1: the index finger's cues followed the wrong way round).";

#[derive(Parser, Debug)]
#[command(
    name = "handsim",
    version,
    about = "The simulated hand on a CAN bus",
    after_help = AFTER_HELP
)]
struct Args {
    /// SocketCAN interface to run on in real time (e.g. vcan0).
    #[arg(long, conflicts_with = "mem")]
    iface: Option<String>,
    /// Run on the in-memory bus on a virtual clock, as fast as possible, and print a summary.
    #[arg(long)]
    mem: bool,
    /// Scenario (see --list-scenarios).
    #[arg(long, default_value = "rest")]
    scenario: String,
    /// Run for this many seconds instead of the scenario's length.
    #[arg(long)]
    duration: Option<f64>,
    /// Seed of the amplifier's noise, the patient's motor noise and the cued patient's
    /// reaction delays.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Mains frequency, 50 or 60 Hz.
    #[arg(long, default_value_t = 50)]
    mains: u32,
    /// A fault, `NAME[:ARGS][@FROM..UNTIL]` with times in seconds (default: the whole run),
    /// e.g. `drop-emg:10@2..5`, `estop@3..3.5`, `motor-silent:2`. Repeatable.
    #[arg(long = "fault")]
    faults: Vec<String>,
    /// Do not run the amplifier (e.g. a real one is on the bus).
    #[arg(long)]
    no_amplifier: bool,
    /// Run the motor controllers of these fingers only, e.g. `013` (default: 01234; `none`).
    #[arg(long, default_value = "01234")]
    fingers: String,
    /// Move these fingers by a simulated CANopen CiA 402 drive instead of a native controller,
    /// e.g. `1` (the index): finger F's drive is node 5+F (thumb 5 .. pinky 9), with the scaling
    /// of the example in handd.toml (rated torque 25 mNm, gear 64, moment arm 0.04 m, limits
    /// 1000 per mille and 8000 rpm). handd needs the matching `[fingers.NAME.drive]` tables.
    #[arg(long, value_name = "FINGERS")]
    cia402: Option<String>,
    /// What moves the fingers: `cia402` puts every finger on a simulated CiA 402 drive (as
    /// `--cia402 01234`); `native` their native controllers.
    #[arg(long, value_enum, conflicts_with = "cia402")]
    drives: Option<Drives>,
    /// Write the scenario's calibration trials (session.toml `[[trial]]` form) to this file.
    #[arg(long)]
    trials_out: Option<std::path::PathBuf>,
    /// With --mem: write a calibration session directory (frames.log in candump format and
    /// session.toml with the trials), ready for decoder::session.
    #[arg(long, requires = "mem")]
    session_out: Option<std::path::PathBuf>,
    /// With --scenario cued: hold the first attempt (cue Attempt 0) of trial N (the cue's
    /// Trial index, 0..254) at 50% effort whatever the cue asks, once, so that a calibration's
    /// quality check can catch it and repeat the trial (later attempts are full).
    #[arg(long, value_name = "N")]
    weak_trial: Option<u8>,
    /// With --scenario cued: follow finger F's (0 thumb .. 4 pinky) own cues the wrong way
    /// round, every time: extend it at its flexion cue, flex it at its extension cue
    /// (whole-hand cues as cued), so that a calibration's pattern gates can refuse the finger.
    #[arg(long, value_name = "F")]
    inverted_finger: Option<u8>,
    /// List the scenarios and faults, then exit.
    #[arg(long)]
    list_scenarios: bool,
}

fn parse_fault(spec: &str, duration_us: u64) -> Result<(Fault, u64, u64), SimError> {
    let (name, window) = match spec.split_once('@') {
        Some((n, w)) => (n, Some(w)),
        None => (spec, None),
    };
    let fault: Fault = name.parse()?;
    let secs = |s: &str| -> Result<u64, SimError> {
        let v: f64 = s
            .trim()
            .parse()
            .map_err(|_| SimError::BadScript(format!("fault {spec:?}: bad time {s:?}")))?;
        if !(v.is_finite() && v >= 0.0) {
            return Err(SimError::BadScript(format!(
                "fault {spec:?}: bad time {s:?}"
            )));
        }
        Ok((v * 1e6).round() as u64)
    };
    let (from, until) = match window {
        None => (0, duration_us.max(1)),
        Some(w) => {
            let (a, b) = w.split_once("..").ok_or_else(|| {
                SimError::BadScript(format!(
                    "fault {spec:?}: window must be FROM..UNTIL seconds"
                ))
            })?;
            (secs(a)?, secs(b)?)
        }
    };
    Ok((fault, from, until))
}

/// `--drives`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
enum Drives {
    /// hand.dbc's native finger controllers.
    Native,
    /// A simulated CiA 402 drive per finger.
    Cia402,
}

/// The simulated CiA 402 drives `--cia402 FINGERS` asks for.
fn sim_drives(
    fingers: Option<&str>,
) -> Result<[Option<hand_model::nodes::DriveFingerConfig>; 5], SimError> {
    let mut out = [None; 5];
    let Some(s) = fingers else {
        return Ok(out);
    };
    let mask = parse_fingers(s).map_err(|_| {
        SimError::BadScript(format!(
            "--cia402 {s:?}: use finger digits 0 (thumb) to 4 (pinky), e.g. 1 or 012"
        ))
    })?;
    for (f, slot) in out.iter_mut().enumerate() {
        if mask & (1 << f) != 0 {
            *slot = Some(hand_model::nodes::DriveFingerConfig::simulated(f)?);
        }
    }
    Ok(out)
}

fn parse_fingers(s: &str) -> Result<u8, SimError> {
    if s == "none" {
        return Ok(0);
    }
    let mut mask = 0u8;
    for c in s.chars() {
        let f = c.to_digit(10).filter(|d| *d < 5).ok_or_else(|| {
            SimError::BadScript(format!("--fingers {s:?}: use digits 0..4 or none"))
        })?;
        mask |= 1 << f;
    }
    Ok(mask)
}

/// The scenario, with the cued patient's options from the command line.
fn build(scenario: Scenario, args: &Args) -> Result<ScenarioRun, SimError> {
    let cued_options = [
        ("--weak-trial", args.weak_trial.is_some()),
        ("--inverted-finger", args.inverted_finger.is_some()),
    ];
    let given: Vec<&str> = cued_options.iter().filter(|o| o.1).map(|o| o.0).collect();
    match scenario {
        _ if given.is_empty() => scenario.build(args.seed),
        Scenario::Cued => ScenarioRun::cued(CuedConfig {
            seed: args.seed,
            weak_trial: args.weak_trial,
            inverted_finger: args.inverted_finger,
            ..CuedConfig::default()
        }),
        _ => Err(SimError::BadScript(format!(
            "{} applies to --scenario cued only, not {}",
            given.join(" and "),
            scenario.name()
        ))),
    }
}

fn run() -> Result<(), String> {
    let args = Args::parse();
    if args.list_scenarios {
        for s in Scenario::ALL {
            println!("{:<18} {}", s.name(), s.description());
        }
        println!(
            "\nfaults (--fault NAME[:ARGS][@FROM..UNTIL]): {}",
            Fault::SYNTAX
        );
        return Ok(());
    }
    let scenario: Scenario = args.scenario.parse().map_err(|e: SimError| e.to_string())?;
    let run = build(scenario, &args).map_err(|e| e.to_string())?;
    let duration_us = match args.duration {
        Some(d) if d.is_finite() && d > 0.0 => (d * 1e6).round() as u64,
        Some(d) => {
            return Err(format!(
                "--duration {d}: must be a positive number of seconds"
            ))
        }
        None => run.duration_us,
    };
    if let Some(path) = &args.trials_out {
        std::fs::write(path, run.trials_toml())
            .map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    }
    let mut plan = FaultPlan::new();
    for spec in &args.faults {
        let (f, from, until) = parse_fault(spec, duration_us).map_err(|e| e.to_string())?;
        plan.add(f, from, until).map_err(|e| e.to_string())?;
    }
    let mains = match args.mains {
        50 => hand_model::emg::Mains::Hz50,
        60 => hand_model::emg::Mains::Hz60,
        m => return Err(format!("--mains {m}: must be 50 or 60")),
    };
    let amp_signal = AmplifierConfig {
        seed: args.seed,
        mains,
        ..AmplifierConfig::default()
    };
    let session_meta = args
        .session_out
        .as_ref()
        .map(|_| run.session_meta("frames.log", &amp_signal));
    let amp = AmplifierNodeConfig {
        signal: amp_signal,
        ..AmplifierNodeConfig::default()
    };
    let cfg = WorldConfig {
        amplifier: amp,
        finger: FingerConfig::default(),
        faults: plan,
        nodes: NodeSelection {
            amplifier: !args.no_amplifier,
            fingers: parse_fingers(&args.fingers).map_err(|e| e.to_string())?,
        },
        start_us: 0,
        drives: sim_drives(match args.drives {
            Some(Drives::Cia402) => Some("01234"),
            Some(Drives::Native) => None,
            None => args.cia402.as_deref(),
        })
        .map_err(|e| e.to_string())?,
    };
    match (&args.iface, args.mem) {
        (Some(iface), false) => {
            let iface = iface.clone();
            let world = World::try_new_listening(cfg, run.patient, |l| {
                SocketCanBus::open_listening(&iface, l)
            })
            .map_err(|e| e.to_string())?;
            eprintln!(
                "handsim: scenario {} on {iface} for {:.1} s (real time)",
                scenario.name(),
                duration_us as f64 * 1e-6
            );
            run_realtime(world, duration_us);
            Ok(())
        }
        (None, true) => {
            let mut log = match &args.session_out {
                Some(dir) => {
                    std::fs::create_dir_all(dir)
                        .map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
                    let path = dir.join("frames.log");
                    let file = std::fs::File::create(&path)
                        .map_err(|e| format!("cannot create {}: {e}", path.display()))?;
                    Some((LogWriter::new(std::io::BufWriter::new(file)), path))
                }
                None => None,
            };
            let mut per_id: BTreeMap<u32, u64> = BTreeMap::new();
            run_on_mem_bus(cfg, run.patient, duration_us, |t, frame| {
                *per_id.entry(frame.raw_id()).or_default() += 1;
                if let Some((w, path)) = &mut log {
                    w.write_frame(t, "can0", frame)
                        .map_err(|e| format!("cannot write {}: {e}", path.display()))?;
                }
                Ok::<_, String>(())
            })
            .map_err(|e| e.to_string())??;
            if let (Some((mut w, path)), Some(dir), Some(meta)) =
                (log, &args.session_out, &session_meta)
            {
                w.flush()
                    .map_err(|e| format!("cannot write {}: {e}", path.display()))?;
                meta.write(dir).map_err(|e| e.to_string())?;
            }
            let secs = duration_us as f64 * 1e-6;
            println!(
                "scenario {} for {secs:.3} s on the in-memory bus",
                scenario.name()
            );
            println!("{:>6} {:>10} {:>10}", "id", "frames", "per s");
            for (id, n) in &per_id {
                println!("{id:#06x} {n:>10} {:>10.1}", *n as f64 / secs.max(1e-9));
            }
            println!(
                "total {} frames; {} trials",
                per_id.values().sum::<u64>(),
                run.trials.len()
            );
            Ok(())
        }
        _ => Err("choose one transport: --iface IFACE (SocketCAN, real time) or --mem".into()),
    }
}

fn run_realtime<B: Bus>(mut world: World<B>, duration_us: u64) {
    let clock = SystemClock::new();
    loop {
        let now = clock.now_us();
        if now > duration_us {
            break;
        }
        world.step(now);
        // 1 ms steps: the amplifier's frame period. Late wake-ups are caught up by the nodes.
        std::thread::sleep(Duration::from_micros(1000 - now % 1000));
    }
    eprintln!("handsim: done; {} frames sent", world.frames_sent());
    for f in world.fingers() {
        let m = f.motion_stats();
        eprintln!(
            "handsim: finger {}: {} stop impacts (fastest {:.2} rad/s, overtravel {:.1} mrad); \
commands over the limits on {} ticks (force, largest {:.1} N) and {} ticks (speed, largest \
{:.2} rad/s)",
            f.finger(),
            m.impacts,
            m.max_impact_speed_rad_s,
            m.max_overtravel_rad * 1e3,
            m.over_force_ticks,
            m.max_force_requested_n,
            m.over_speed_ticks,
            m.max_speed_requested_rad_s
        );
    }
    if let Some(amp) = world.amplifier() {
        let st = amp.stats();
        eprintln!(
            "handsim: amplifier transmits refused: {} (queue full), {} (errors); {} samples \
skipped by stalls",
            st.tx_would_block,
            st.tx_errors,
            amp.samples_dropped()
        );
    }
}

fn main() -> ExitCode {
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("handsim: {e}");
            ExitCode::FAILURE
        }
    }
}
