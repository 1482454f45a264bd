//! Every fault can be switched on, and shows on the bus.

mod common;

use common::Harness;
use hand_dbc::e2e::E2eProfile;
use hand_dbc::messages::{
    EmgSamplesG0, EmgSamplesG2, EmgStatus, EstopRequest, FingerMode, FingerState, FingerStatus,
    HandEstop,
};
use hand_model::bus::MemEndpoint;
use hand_model::faults::{CrcTarget, Fault, FaultPlan};
use hand_model::nodes::SetpointSource;
use hand_model::patient::{Intent, Script};
use hand_model::world::{PatientMode, World, WorldConfig};

const FROM: u64 = 200_000;
const UNTIL: u64 = 400_000;
const END: u64 = 600_000;

/// Runs a world (patient holding a half fist) with `fault` on in [FROM, UNTIL), and
/// setpoint sources keeping every finger active. Returns the harness with the bus log.
fn run_with(fault: Fault) -> Harness {
    let mut plan = FaultPlan::new();
    plan.add(fault, FROM, UNTIL).expect("valid fault");
    let mut h = Harness::new();
    let bus = h.bus.clone();
    let mut script = Script::new();
    script.hold(Intent::all(0.5), END + 1);
    let cfg = WorldConfig {
        faults: plan,
        ..WorldConfig::default()
    };
    let mut world: World<MemEndpoint> = World::try_new(cfg, PatientMode::Script(script), || {
        Ok::<_, std::convert::Infallible>(bus.endpoint())
    })
    .expect("valid world");
    let mut sources: Vec<(SetpointSource, MemEndpoint)> = (0..5)
        .map(|f| {
            let mut s = SetpointSource::try_new(f, 0).expect("valid");
            s.set(FingerMode::Active, 2.0, 0.2).expect("in range");
            (s, h.bus.endpoint())
        })
        .collect();
    h.run(END, |t| {
        for (s, ep) in &mut sources {
            s.poll(t, ep);
        }
        world.step(t);
    });
    h
}

fn in_window(t: u64) -> bool {
    (FROM..UNTIL).contains(&t)
}

fn crc_ok(profile: E2eProfile, data: &[u8]) -> bool {
    data[0] == profile.crc(data)
}

/// G0 counters received inside the fault window, in arrival order.
fn g0_counters(h: &Harness) -> Vec<u8> {
    h.with_id(EmgSamplesG0::ID)
        .into_iter()
        .filter(|(t, _)| in_window(*t))
        .map(|(_, f)| f.data()[1])
        .collect()
}

fn emg_frames_in_window(h: &Harness) -> usize {
    (0x100..=0x102)
        .map(|id| h.with_id(id).iter().filter(|(t, _)| in_window(*t)).count())
        .sum()
}

#[test]
fn without_faults_the_amplifier_sends_three_frames_per_sample() {
    let h = run_with(Fault::CounterJump { by: 1 });
    // A counter jump does not change the number of frames: 200 samples in the window.
    assert_eq!(emg_frames_in_window(&h), 600);
    assert_eq!(
        h.with_id(EmgSamplesG0::ID).len(),
        601,
        "samples at 0, 1, ..., 600 ms"
    );
}

#[test]
fn dropped_emg_frames() {
    let h = run_with(Fault::DropEmgFrames { every: 10 });
    assert_eq!(emg_frames_in_window(&h), 600 - 60);
}

#[test]
fn repeated_emg_frames() {
    let h = run_with(Fault::RepeatEmgFrames { every: 10 });
    assert_eq!(emg_frames_in_window(&h), 600 + 60);
    let repeats = g0_counters(&h).windows(2).filter(|w| w[0] == w[1]).count();
    assert!(repeats >= 15, "G0 repeats seen: {repeats}");
}

#[test]
fn reordered_emg_frames() {
    let h = run_with(Fault::ReorderEmgFrames { every: 10 });
    let backwards = g0_counters(&h)
        .windows(2)
        .filter(|w| w[1] == w[0].wrapping_sub(1))
        .count();
    assert_eq!(backwards, 20, "one reordered pair per 10 samples");
    assert_eq!(emg_frames_in_window(&h), 600, "reordering loses nothing");
}

#[test]
fn counter_jump() {
    let h = run_with(Fault::CounterJump { by: 5 });
    let all: Vec<u8> = h
        .with_id(EmgSamplesG0::ID)
        .iter()
        .map(|(_, f)| f.data()[1])
        .collect();
    let steps: Vec<u8> = all.windows(2).map(|w| w[1].wrapping_sub(w[0])).collect();
    assert_eq!(
        steps.iter().filter(|&&d| d == 6).count(),
        1,
        "exactly one jump of 1 + 5"
    );
    assert!(steps.iter().all(|&d| d == 1 || d == 6));
    // Every frame still has a correct CRC: a jump is not corruption.
    assert!(h
        .with_id(EmgSamplesG0::ID)
        .iter()
        .all(|(_, f)| crc_ok(EmgSamplesG0::E2E, f.data())));
}

#[test]
fn bad_crc_on_emg_status_and_finger_status() {
    let h = run_with(Fault::BadCrc {
        target: CrcTarget::Emg,
        every: 10,
    });
    let bad: usize = [(0x100, EmgSamplesG0::E2E), (0x102, EmgSamplesG2::E2E)]
        .iter()
        .map(|(id, p)| {
            h.with_id(*id)
                .iter()
                .filter(|(_, f)| !crc_ok(*p, f.data()))
                .count()
        })
        .sum();
    assert!(bad >= 35, "bad EMG CRCs in G0+G2: {bad}");
    assert!(h
        .with_id(0x100)
        .iter()
        .filter(|(t, _)| !in_window(*t))
        .all(|(_, f)| crc_ok(EmgSamplesG0::E2E, f.data())));

    let h = run_with(Fault::BadCrc {
        target: CrcTarget::EmgStatus,
        every: 1,
    });
    let st = h.with_id(EmgStatus::ID);
    assert!(st
        .iter()
        .filter(|(t, _)| in_window(*t))
        .all(|(_, f)| !crc_ok(EmgStatus::E2E, f.data())));
    assert!(st
        .iter()
        .filter(|(t, _)| !in_window(*t))
        .all(|(_, f)| crc_ok(EmgStatus::E2E, f.data())));

    let h = run_with(Fault::BadCrc {
        target: CrcTarget::FingerStatus(3),
        every: 2,
    });
    let bad = h
        .with_id(FingerStatus::IDS[3])
        .iter()
        .filter(|(_, f)| !crc_ok(FingerStatus::E2E[3], f.data()))
        .count();
    assert_eq!(bad, 5, "every 2nd of the 10 statuses in 200 ms");
}

#[test]
fn lead_off_channels() {
    let h = run_with(Fault::LeadOff { channels: 0b11 });
    let masks: Vec<(u64, EmgStatus)> = h
        .with_id(EmgStatus::ID)
        .into_iter()
        .map(|(t, f)| (t, EmgStatus::decode(f.data()).expect("valid")))
        .collect();
    assert!(masks
        .iter()
        .filter(|(t, _)| in_window(*t))
        .all(|(_, s)| s.lead_off_mask() == 0b11));
    assert!(masks
        .iter()
        .filter(|(t, _)| !in_window(*t))
        .all(|(_, s)| s.lead_off_mask() == 0));
    // The open electrode shows clipped mains pick-up.
    let rails = h
        .with_id(EmgSamplesG0::ID)
        .iter()
        .filter(|(t, _)| in_window(*t))
        .filter(|(_, f)| {
            EmgSamplesG0::decode(f.data())
                .expect("valid")
                .emg0_raw()
                .abs()
                >= 2047
        })
        .count();
    assert!(rails > 50, "channel 0 at the rails in {rails} samples");
}

#[test]
fn saturated_channels() {
    let h = run_with(Fault::Saturation { channels: 1 << 11 });
    let g2: Vec<i16> = h
        .with_id(EmgSamplesG2::ID)
        .iter()
        .filter(|(t, _)| in_window(*t))
        .map(|(_, f)| EmgSamplesG2::decode(f.data()).expect("valid").emg11_raw())
        .collect();
    assert!(g2.iter().all(|&x| x == 2047));
    let sat_reported = h
        .with_id(EmgStatus::ID)
        .iter()
        .filter(|(t, _)| *t > FROM && *t <= UNTIL)
        .all(|(_, f)| {
            EmgStatus::decode(f.data())
                .expect("valid")
                .saturation_mask()
                & (1 << 11)
                != 0
        });
    assert!(sat_reported);
}

#[test]
fn amplifier_silence() {
    let h = run_with(Fault::AmplifierSilence);
    assert_eq!(emg_frames_in_window(&h), 0);
    assert_eq!(
        h.with_id(EmgStatus::ID)
            .iter()
            .filter(|(t, _)| in_window(*t))
            .count(),
        0
    );
    assert!(
        h.with_id(EmgSamplesG0::ID).iter().any(|(t, _)| *t >= UNTIL),
        "resumes after"
    );
}

#[test]
fn estop_frame_and_the_fingers_brake() {
    let h = run_with(Fault::EStop);
    let stops = h.with_id(HandEstop::ID);
    assert_eq!(stops.len(), 20, "every 10 ms for 200 ms");
    for (t, f) in &stops {
        assert!(in_window(*t));
        assert!(crc_ok(HandEstop::E2E, f.data()));
        assert_eq!(
            HandEstop::decode(f.data()).expect("valid").request(),
            EstopRequest::Stop
        );
    }
    let braked = h
        .with_id(FingerStatus::IDS[0])
        .iter()
        .filter(|(t, _)| *t > FROM + 20_000)
        .all(|(_, f)| {
            FingerStatus::decode(f.raw_id(), f.data())
                .expect("valid")
                .state()
                == FingerState::Braked
        });
    assert!(braked, "an E-stop latches the brake");
}

#[test]
fn motor_controller_stops_reporting() {
    let h = run_with(Fault::MotorSilent { finger: 2 });
    assert_eq!(
        h.with_id(FingerStatus::IDS[2])
            .iter()
            .filter(|(t, _)| in_window(*t))
            .count(),
        0
    );
    assert_eq!(
        h.with_id(FingerStatus::IDS[1])
            .iter()
            .filter(|(t, _)| in_window(*t))
            .count(),
        10
    );
    assert!(h
        .with_id(FingerStatus::IDS[2])
        .iter()
        .any(|(t, _)| *t >= UNTIL));
}

#[test]
fn burst_of_unknown_ids() {
    let h = run_with(Fault::UnknownIdBurst {
        id: 0x7A0,
        count: 100,
    });
    let burst = h.with_id(0x7A0);
    assert_eq!(burst.len(), 100);
    assert!(burst.iter().all(|(t, _)| *t == FROM));
    assert!(
        hand_dbc::messages::decode(0x7A0, burst[0].1.data()).is_err(),
        "not a hand.dbc id"
    );
}

#[test]
fn flood_at_full_bus_load() {
    let h = run_with(Fault::BusFlood);
    let flood = h.with_id(0x001);
    // 1 Mbit/s / 135 bit per frame = 7407 frames/s: 1481 in 200 ms, give or take the 7.4
    // frames of the 1 ms polling step at the window's end.
    let n = flood.len() as i64;
    assert!((n - 1481).abs() <= 8, "{n} flood frames in 200 ms");
    assert!(flood.iter().all(|(t, _)| in_window(*t)));
}
