//! The motor controller brakes by itself within 150 ms (+ one 50 ms tick) when valid
//! setpoints stop: silence, bad CRC, stuck counter.

mod common;

use common::Harness;
use hand_dbc::messages::{FingerMode, FingerSetpoint, FingerState, FingerStatus};
use hand_model::finger::FingerConfig;
use hand_model::nodes::{FingerNode, SetpointCorruption, SetpointSource};

const FINGER: usize = 2;
const STOP_AT_US: u64 = 1_000_000;

/// Runs 1 s of good setpoints, then `corruption` for 0.5 s. Returns (time of the last valid
/// setpoint on the bus, time of the first BRAKED status, the harness).
fn run(corruption: SetpointCorruption) -> (u64, u64, Harness) {
    let mut h = Harness::new();
    let mut mc_ep = h.bus.endpoint();
    let mut sp_ep = h.bus.endpoint();
    let mut mc = FingerNode::try_new(FINGER, FingerConfig::default(), 0).expect("valid");
    let mut sp = SetpointSource::try_new(FINGER, 0).expect("valid");
    sp.set(FingerMode::Active, 5.0, 0.5).expect("in range");
    h.run(1_500_000, |t| {
        if t == STOP_AT_US {
            sp.set_corruption(corruption);
        }
        sp.poll(t, &mut sp_ep);
        mc.poll(t, &mut mc_ep);
    });
    let last_valid = h
        .with_id(FingerSetpoint::IDS[FINGER])
        .iter()
        .map(|(t, _)| *t)
        .filter(|t| *t < STOP_AT_US)
        .max()
        .expect("setpoints were sent");
    let statuses: Vec<(u64, FingerStatus)> = h
        .with_id(FingerStatus::IDS[FINGER])
        .into_iter()
        .map(|(t, f)| {
            (
                t,
                FingerStatus::decode(f.raw_id(), f.data()).expect("valid status"),
            )
        })
        .collect();
    // Before the stop the finger was active, moving and pushing.
    let before = statuses
        .iter()
        .rev()
        .find(|(t, _)| *t < STOP_AT_US)
        .expect("status before the stop");
    assert_eq!(before.1.state(), FingerState::Active);
    assert!(before.1.force() > 4.9, "force {}", before.1.force());
    let braked_at = statuses
        .iter()
        .find(|(t, s)| *t >= STOP_AT_US && s.state() == FingerState::Braked)
        .map(|(t, s)| {
            assert_eq!(s.velocity(), 0.0);
            assert_eq!(s.force(), 0.0);
            assert!(s.faults() & (1 << 3) != 0, "timeout fault bit");
            *t
        })
        .expect("the controller must brake");
    // Once braked it stays braked (no valid setpoint comes back).
    assert!(statuses
        .iter()
        .filter(|(t, _)| *t >= braked_at)
        .all(|(_, s)| s.state() == FingerState::Braked && s.force() == 0.0));
    (last_valid, braked_at, h)
}

fn assert_brake_window(last_valid: u64, braked_at: u64) {
    let dt = braked_at - last_valid;
    assert!(
        (150_000..=200_000).contains(&dt),
        "braked {dt} µs after the last valid setpoint (must be 150 ms + at most one 50 ms tick)"
    );
}

#[test]
fn brakes_when_setpoints_stop() {
    let (last, braked, _) = run(SetpointCorruption::Silent);
    assert_brake_window(last, braked);
}

#[test]
fn brakes_when_setpoints_have_a_bad_crc() {
    let (last, braked, h) = run(SetpointCorruption::BadCrc);
    assert_brake_window(last, braked);
    // The bad frames were on the bus all along, and the controller said so.
    assert!(h
        .with_id(FingerSetpoint::IDS[FINGER])
        .iter()
        .any(|(t, _)| *t > braked));
    let e2e_flagged = h
        .with_id(FingerStatus::IDS[FINGER])
        .iter()
        .filter(|(t, _)| *t > STOP_AT_US)
        .map(|(_, f)| FingerStatus::decode(f.raw_id(), f.data()))
        .any(|s| s.expect("valid").faults() & (1 << 4) != 0);
    assert!(e2e_flagged, "E2E fault bit never reported");
}

#[test]
fn brakes_when_the_counter_is_stuck() {
    let (last, braked, h) = run(SetpointCorruption::StuckCounter);
    // The first frame with the stuck counter still carries a fresh counter value; the
    // repetitions after it are what must not count.
    let first_stuck = h
        .with_id(FingerSetpoint::IDS[FINGER])
        .iter()
        .map(|(t, _)| *t)
        .find(|t| *t >= STOP_AT_US)
        .expect("stuck frames sent");
    assert!(last < first_stuck);
    assert_brake_window(first_stuck, braked);
}

#[test]
fn good_setpoints_never_brake_and_motion_stays_in_range() {
    let mut h = Harness::new();
    let mut mc_ep = h.bus.endpoint();
    let mut sp_ep = h.bus.endpoint();
    let cfg = FingerConfig::default();
    let mut mc = FingerNode::try_new(FINGER, cfg, 0).expect("valid");
    let mut sp = SetpointSource::try_new(FINGER, 0).expect("valid");
    sp.set(FingerMode::Active, 30.0, 10.0).expect("in range");
    h.run(2_000_000, |t| {
        sp.poll(t, &mut sp_ep);
        mc.poll(t, &mut mc_ep);
    });
    let statuses: Vec<FingerStatus> = h
        .with_id(FingerStatus::IDS[FINGER])
        .into_iter()
        .map(|(_, f)| FingerStatus::decode(f.raw_id(), f.data()).expect("valid"))
        .collect();
    assert!(
        statuses.len() >= 99,
        "50 Hz status: {} in 2 s",
        statuses.len()
    );
    for s in &statuses[1..] {
        assert_ne!(s.state(), FingerState::Braked);
        assert!(
            s.position() >= cfg.angle_min_rad - 1e-3 && s.position() <= cfg.angle_max_rad + 1e-3
        );
        assert!(s.velocity().abs() <= cfg.max_velocity_rad_s + 0.01);
        assert!(
            s.force().abs() <= cfg.max_force_n + 0.025,
            "force clamped to the finger's limit"
        );
    }
    let last = statuses.last().expect("statuses");
    assert!(
        (last.position() - cfg.angle_max_rad).abs() < 2e-3,
        "reached full flexion"
    );
    assert!(last.faults() & (1 << 5) != 0, "joint limit reported");
}

#[test]
fn resumes_only_in_a_new_epoch_after_a_timeout_and_obeys_estop_release() {
    use hand_dbc::messages::{EstopReason, EstopRequest, EstopSource, HandEstop};
    use hand_model::dbc::seal;

    let mut h = Harness::new();
    let mut mc_ep = h.bus.endpoint();
    let mut sp_ep = h.bus.endpoint();
    let mut tool_ep = h.bus.endpoint();
    let mut mc = FingerNode::try_new(FINGER, FingerConfig::default(), 0).expect("valid");
    let mut sp = SetpointSource::try_new(FINGER, 0).expect("valid");
    sp.set(FingerMode::Active, 3.0, 0.0).expect("in range");
    let estop = |req: EstopRequest, counter: u8| {
        let mut f = HandEstop::new(req, EstopSource::Tool, EstopReason::Technician)
            .expect("valid")
            .to_frame();
        seal(&mut f, HandEstop::E2E, counter, false);
        f
    };
    use embedded_can::nb::Can;
    h.run(2_000_000, |t| {
        match t {
            500_000 => sp.set_corruption(SetpointCorruption::Silent),
            800_000 => sp.set_corruption(SetpointCorruption::None),
            // Braking by itself retired the epoch: only a new one, opened by a SAFE_STOP,
            // moves the finger again.
            950_000 => sp.new_epoch(),
            1_200_000 => {
                tool_ep
                    .transmit(&estop(EstopRequest::Stop, 0))
                    .expect("sent");
            }
            1_600_000 => {
                tool_ep
                    .transmit(&estop(EstopRequest::Release, 1))
                    .expect("sent");
            }
            _ => {}
        }
        sp.poll(t, &mut sp_ep);
        mc.poll(t, &mut mc_ep);
    });
    let state_at = |t0: u64| {
        h.with_id(FingerStatus::IDS[FINGER])
            .into_iter()
            .rfind(|(t, _)| *t <= t0)
            .map(|(_, f)| {
                FingerStatus::decode(f.raw_id(), f.data())
                    .expect("valid")
                    .state()
            })
            .expect("status")
    };
    assert_eq!(state_at(480_000), FingerState::Active);
    assert_eq!(state_at(780_000), FingerState::Braked, "timed out");
    assert_eq!(
        state_at(940_000),
        FingerState::Braked,
        "valid setpoints of the epoch it braked in do not release the brake"
    );
    let stale_flagged = h
        .with_id(FingerStatus::IDS[FINGER])
        .into_iter()
        .filter(|(t, _)| (800_000..=960_000).contains(t))
        .any(|(_, f)| {
            FingerStatus::decode(f.raw_id(), f.data())
                .expect("valid")
                .faults()
                & (1 << 6)
                != 0
        });
    assert!(
        stale_flagged,
        "ignored stale-epoch setpoints are reported (fault bit 6)"
    );
    assert_eq!(mc.epoch_gate().bound(), Some(1), "bound to the new epoch");
    assert_eq!(
        state_at(1_150_000),
        FingerState::Active,
        "recovered on a SAFE_STOP of a new epoch and ACTIVE after it"
    );
    assert_eq!(state_at(1_500_000), FingerState::Braked, "E-stop latched");
    assert_eq!(state_at(1_900_000), FingerState::Active, "released");
}
