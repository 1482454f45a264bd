//! Each node's acceptance filter ([`Listens`]) is complete: a world whose nodes only ever
//! receive what their filter passes (as handsim's SocketCAN sockets do, filtered in the kernel)
//! puts the same frames on the bus, bit for bit, as one whose nodes see everything. Checked
//! with the closed-loop patient tracking through a finger under setpoints and an E-stop, and
//! with the cued patient following CALIBRATION_CUE.

mod common;

use common::Harness;
use hand_dbc::e2e::E2eProtector;
use hand_dbc::messages::{CalibrationCue, CueKind, CuePhase, FingerMode, HandEstop};
use hand_model::bus::{MemBusError, MemEndpoint};
use hand_model::dbc::CanFrame;
use hand_model::faults::{Fault, FaultPlan};
use hand_model::nodes::SetpointSource;
use hand_model::patient::CuedConfig;
use hand_model::scenario::Scenario;
use hand_model::world::{Listens, PatientMode, World, WorldConfig};

/// A bus endpoint that delivers only what the node's filter passes.
struct Filtered {
    inner: MemEndpoint,
    listens: Listens,
}

impl embedded_can::nb::Can for Filtered {
    type Frame = CanFrame;
    type Error = MemBusError;

    fn transmit(&mut self, frame: &CanFrame) -> nb::Result<Option<CanFrame>, MemBusError> {
        self.inner.transmit(frame)
    }

    fn receive(&mut self) -> nb::Result<CanFrame, MemBusError> {
        loop {
            let f = self.inner.receive()?;
            if !f.is_extended() && self.listens.accepts(f.raw_id()) {
                return Ok(f);
            }
        }
    }
}

/// Runs `patient` for `until_us` with setpoint sources keeping every finger ACTIVE at a
/// force following the patient's intent, an E-stop from 2.0 to 2.5 s, and `tool` called every
/// ms with the harness's own endpoint; the bus's frames and the patient's largest index-finger
/// intent.
fn run(
    patient: PatientMode,
    filtered: bool,
    until_us: u64,
    mut tool: impl FnMut(u64, &mut MemEndpoint),
) -> (Vec<CanFrame>, f64) {
    let mut h = Harness::new();
    let bus = h.bus.clone();
    let mut plan = FaultPlan::new();
    plan.add(Fault::EStop, 2_000_000, 2_500_000).expect("valid");
    let cfg = WorldConfig {
        faults: plan,
        ..WorldConfig::default()
    };
    let mut world = World::try_new_listening(cfg, patient, |listens| {
        Ok::<_, std::convert::Infallible>(Filtered {
            inner: bus.endpoint(),
            // Unfiltered: everything passes (every id the bus can carry).
            listens: if filtered {
                listens
            } else {
                Listens::To(ALL_IDS)
            },
        })
    })
    .expect("valid world");
    let mut sources: Vec<(SetpointSource, MemEndpoint)> = (0..5)
        .map(|f| {
            (
                SetpointSource::try_new(f, 0).expect("valid"),
                h.bus.endpoint(),
            )
        })
        .collect();
    let mut ep = h.bus.endpoint();
    let mut most = 0.0f64;
    h.run(until_us, |t| {
        tool(t, &mut ep);
        world.step(t);
        let intent = world.intent().0;
        most = most.max(intent[1]);
        for (f, (s, e)) in sources.iter_mut().enumerate() {
            s.set(FingerMode::Active, 10.0 * intent[f], 0.5 * intent[f])
                .expect("in range");
            s.poll(t, e);
        }
    });
    let frames: Vec<CanFrame> = h.log.iter().map(|r| r.frame).collect();
    (frames, most)
}

/// Every standard id (the unfiltered run's "filter").
static ALL_IDS: &[u32] = &{
    let mut ids = [0u32; 0x800];
    let mut i = 0;
    while i < 0x800 {
        ids[i] = i as u32;
        i += 1;
    }
    ids
};

#[test]
fn the_closed_loop_world_behaves_the_same_behind_its_filters() {
    let patient = || Scenario::Sine.build(3).expect("valid").patient;
    let (plain, _) = run(patient(), false, 4_000_000, |_, _| {});
    let (filtered, _) = run(patient(), true, 4_000_000, |_, _| {});
    assert!(plain.len() > 12_000, "{} frames", plain.len());
    assert!(
        plain.iter().any(|f| f.raw_id() == HandEstop::ID),
        "the E-stop is on the bus"
    );
    assert_eq!(plain, filtered, "the filters changed what the world sent");
}

#[test]
fn the_cued_patient_behaves_the_same_behind_its_filter() {
    let patient = || PatientMode::cued(CuedConfig::default()).expect("valid");
    let cues = || {
        let mut protector = E2eProtector::new(CalibrationCue::E2E);
        move |t: u64, ep: &mut MemEndpoint| {
            if !t.is_multiple_of(100_000) {
                return;
            }
            let (phase, kind) = match t {
                0..1_000_000 => (CuePhase::Prepare, CueKind::Flexion),
                1_000_000..3_000_000 => (CuePhase::Hold, CueKind::Flexion),
                _ => (CuePhase::Relax, CueKind::Flexion),
            };
            let cue = CalibrationCue::new(phase, 0, 1, kind, 0, 0, 1.0, 100).expect("in range");
            let frame = protector.protect_message(&cue).expect("profile");
            ep.send(&frame).expect("sent");
        }
    };
    let (plain, most) = run(patient(), false, 4_000_000, cues());
    let (filtered, most_filtered) = run(patient(), true, 4_000_000, cues());
    assert_eq!(plain, filtered, "the filters changed what the world sent");
    // The patient did follow the cue behind the filter: full index flexion during the hold.
    assert!(
        most > 0.9 && most_filtered == most,
        "{most} {most_filtered}"
    );
}

/// A simulated drive's filter passes every frame a CANopen node may need, wherever handd puts
/// SYNC and whatever the node id, and none of the EMG samples.
#[test]
fn a_drives_filter_passes_everything_but_the_emg_samples() {
    use hand_dbc::messages::{EmgSamplesG0, EmgSamplesG1, EmgSamplesG2};
    let emg = [EmgSamplesG0::ID, EmgSamplesG1::ID, EmgSamplesG2::ID];
    for &id in ALL_IDS {
        assert_eq!(
            Listens::DRIVE.accepts(id),
            !emg.contains(&id),
            "a drive's filter and id {id:#05x}"
        );
    }
}
