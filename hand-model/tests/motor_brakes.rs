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
    let statuses = statuses(&h);
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

/// The finger's statuses on the bus, decoded, with their times.
fn statuses(h: &Harness) -> Vec<(u64, FingerStatus)> {
    h.with_id(FingerStatus::IDS[FINGER])
        .into_iter()
        .map(|(t, f)| {
            let s = FingerStatus::decode(f.raw_id(), f.data()).expect("valid status");
            (t, s)
        })
        .collect()
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
        // Within the joint range, widened by the stops' small overtravel.
        let over = cfg.max_overtravel_rad() + 1e-3;
        assert!(
            s.position() >= cfg.angle_min_rad - over && s.position() <= cfg.angle_max_rad + over
        );
        assert!(s.velocity().abs() <= cfg.max_velocity_rad_s + 0.01);
        assert!(
            s.force().abs() <= cfg.max_force_n + 0.025,
            "force clamped to the finger's limit"
        );
    }
    let last = statuses.last().expect("statuses");
    // Pressed into the flexion stop by the full 20 N: 120 rad/s² / 25,000 /s² = 4.8 mrad.
    let press = cfg.max_accel_rad_s2 / cfg.stop_stiffness_per_s2;
    assert!(
        (last.position() - cfg.angle_max_rad - press).abs() < 2e-3,
        "reached full flexion: {}",
        last.position()
    );
    assert!(last.faults() & (1 << 5) != 0, "joint limit reported");
    // 30 N and 10 rad/s exceed the motor's 20 N and 6 rad/s: saturated and counted on every
    // control tick after the opening SAFE_STOP.
    let st = mc.motion_stats();
    assert!(
        st.over_force_ticks > 1900 && st.over_speed_ticks > 1900,
        "{st:?}"
    );
    assert_eq!(
        (st.max_force_requested_n, st.max_speed_requested_rad_s),
        (30.0, 10.0)
    );
    assert_eq!(st.impacts, 1, "one run into the flexion stop");
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
    assert_eq!(
        mc.epoch_gate().retired(),
        Some(1),
        "bound to the new epoch, which the E-stop then retired"
    );
    assert_eq!(
        state_at(1_150_000),
        FingerState::Active,
        "recovered on a SAFE_STOP of a new epoch and ACTIVE after it"
    );
    assert_eq!(state_at(1_500_000), FingerState::Braked, "E-stop latched");
    // The setpoints go on in the retired epoch: ignored, they feed no watchdog, so the
    // released controller is braked by itself again, never ACTIVE.
    assert_eq!(
        state_at(1_900_000),
        FingerState::Braked,
        "released: the old command is not resumed"
    );
}

/// An E-stop retires the epoch like braking by itself: a STOP and a RELEASE 10 ms later (inside
/// one 20 ms status period, shorter than handd's tick) resume nothing; the finger moves again
/// only after a SAFE_STOP of a new epoch and an ACTIVE after it.
#[test]
fn a_short_estop_resumes_nothing_until_a_new_epoch() {
    use embedded_can::nb::Can;
    use hand_dbc::messages::{EstopReason, EstopRequest, EstopSource, HandEstop};
    use hand_model::dbc::seal;

    let mut h = Harness::new();
    let mut mc_ep = h.bus.endpoint();
    let mut sp_ep = h.bus.endpoint();
    let mut tool_ep = h.bus.endpoint();
    let mut mc = FingerNode::try_new(FINGER, FingerConfig::default(), 0).expect("valid");
    let mut sp = SetpointSource::try_new(FINGER, 0).expect("valid");
    sp.set(FingerMode::Active, 5.0, 0.5).expect("in range");
    let estop = |req: EstopRequest, counter: u8| {
        let mut f = HandEstop::new(req, EstopSource::Tool, EstopReason::Technician)
            .expect("valid")
            .to_frame();
        seal(&mut f, HandEstop::E2E, counter, false);
        f
    };
    // (time, angle) every millisecond.
    let mut angles = Vec::new();
    h.run(1_000_000, |t| {
        match t {
            300_000 => {
                tool_ep
                    .transmit(&estop(EstopRequest::Stop, 0))
                    .expect("sent");
            }
            310_000 => {
                tool_ep
                    .transmit(&estop(EstopRequest::Release, 1))
                    .expect("sent");
            }
            700_000 => sp.new_epoch(),
            _ => {}
        }
        sp.poll(t, &mut sp_ep);
        mc.poll(t, &mut mc_ep);
        angles.push((t, mc.physics().angle_rad));
    });
    let angle_at = |t0: u64| {
        angles
            .iter()
            .find(|(t, _)| *t == t0)
            .map(|(_, a)| *a)
            .expect("sampled")
    };
    assert!(
        angle_at(300_000) > angle_at(200_000) + 0.04,
        "moving before the stop"
    );
    let stopped = angle_at(300_000);
    assert!(
        angles
            .iter()
            .filter(|(t, _)| (300_000..=700_000).contains(t))
            .all(|(_, a)| *a == stopped),
        "the finger moved after the RELEASE, before a new epoch"
    );
    let statuses = statuses(&h);
    let during = |lo: u64, hi: u64| statuses.iter().filter(move |(t, _)| (lo..hi).contains(t));
    assert!(during(301_000, 310_000).all(|(_, s)| s.state() == FingerState::Braked));
    // Released: stopped, not braked; 150 ms after the last frame it followed (250 ms: the
    // old epoch's frames since are ignored and feed no watchdog) it brakes by itself; never
    // is it ACTIVE.
    assert!(during(320_000, 390_000).all(|(_, s)| s.state() == FingerState::SafeStop));
    assert!(during(320_000, 700_000)
        .all(|(_, s)| matches!(s.state(), FingerState::SafeStop | FingerState::Braked)));
    assert!(
        during(320_000, 700_000).any(|(_, s)| s.faults() & (1 << 6) != 0),
        "the old epoch's ACTIVE setpoints are ignored and reported (fault bit 6)"
    );
    assert_eq!(
        mc.epoch_gate().retired(),
        Some(0),
        "the E-stop retired epoch 0"
    );
    assert!(
        angle_at(1_000_000) > stopped + 0.05,
        "moves again after a SAFE_STOP of epoch 1 and an ACTIVE"
    );
    assert_eq!(
        statuses.last().expect("status").1.state(),
        FingerState::Active
    );
}

#[test]
fn a_second_sender_interleaving_its_counters_moves_nothing_and_the_finger_brakes() {
    // handd's setpoints (5 N flexion) and, from 755 ms, a second sender's (5 N extension) on
    // the same id, both with correct CRCs, each counting from where the other would make its
    // frames look in sequence: the second sender's first counter (0) follows handd's last
    // (15, sent at 750 ms). With a reference that moves at once, every second frame is in
    // sequence and the extension gets through; with Profile 1's sync counter a repeat or a
    // jump needs two in-sequence frames before data is used again, which two interleaving
    // senders never give: the controller obeys neither and brakes by itself.
    const SECOND_AT_US: u64 = 755_000;
    let mut h = Harness::new();
    let mut mc_ep = h.bus.endpoint();
    let mut a_ep = h.bus.endpoint();
    let mut b_ep = h.bus.endpoint();
    let mut mc = FingerNode::try_new(FINGER, FingerConfig::default(), 0).expect("valid");
    let mut a = SetpointSource::try_new(FINGER, 0).expect("valid");
    a.set(FingerMode::Active, 5.0, 0.5).expect("in range");
    let mut b = SetpointSource::try_new(FINGER, SECOND_AT_US).expect("valid");
    b.set(FingerMode::Active, -5.0, -0.5).expect("in range");
    h.run(1_500_000, |t| {
        a.poll(t, &mut a_ep);
        if t >= SECOND_AT_US {
            b.poll(t, &mut b_ep);
        }
        mc.poll(t, &mut mc_ep);
    });
    let statuses = statuses(&h);
    let before = statuses
        .iter()
        .rev()
        .find(|(t, _)| *t < SECOND_AT_US)
        .expect("a status before the second sender");
    assert_eq!(before.1.state(), FingerState::Active);
    let pushed_back = statuses
        .iter()
        .filter(|(t, _)| *t >= SECOND_AT_US)
        .map(|(_, s)| s.force())
        .fold(f64::INFINITY, f64::min);
    assert!(
        pushed_back >= 0.0,
        "the second sender's extension reached the finger: force {pushed_back} N"
    );
    let braked_at = statuses
        .iter()
        .find(|(t, s)| *t >= SECOND_AT_US && s.state() == FingerState::Braked)
        .map(|(t, _)| *t)
        .expect("the controller must brake when two senders interleave");
    assert!(
        braked_at - SECOND_AT_US <= 200_000,
        "braked {} µs after the second sender started",
        braked_at - SECOND_AT_US
    );
}
