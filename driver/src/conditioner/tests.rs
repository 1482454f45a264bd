use super::*;

const DT: f64 = 0.05;
const FREE: Feedback = Feedback {
    at_joint_limit: false,
};
const AT_LIMIT: Feedback = Feedback {
    at_joint_limit: true,
};

/// Test gains whose ramp is instantaneous, so the law's other parts show alone.
fn gains() -> FingerGains {
    FingerGains {
        kf: 8.0,
        kalpha: 3.0,
        omega_max: 1.0,
        deadband: 0.1,
        slew_per_s: 1000.0,
        ramp_s: 1e-9,
        ..FingerGains::default()
    }
}

/// Runs `n` ticks at `raw`; returns the last setpoint.
fn run(c: &mut FingerConditioner, g: &FingerGains, raw: f64, n: usize) -> Setpoint {
    let mut sp = Setpoint::default();
    for _ in 0..n {
        sp = c.step(raw, g, DT, FREE);
    }
    sp
}

#[test]
fn force_is_kf_times_label_and_deadband_is_continuous() {
    let mut c = FingerConditioner::default();
    let g = gains();
    assert_eq!(c.step(0.05, &g, DT, FREE).force, Newton(0.0));
    let sp = c.step(1.0, &g, DT, FREE);
    assert!((sp.force.0 - 8.0).abs() < 1e-12);
    let sp = c.step(0.55, &g, DT, FREE);
    assert!((sp.label - 0.5).abs() < 1e-12, "{}", sp.label);
    let sp = c.step(-3.0, &g, DT, FREE);
    assert!(
        (sp.label + 1.0).abs() < 1e-12,
        "clamped to -1, got {}",
        sp.label
    );
}

#[test]
fn the_papers_law_integrates_alpha_saturates_and_holds_at_rest() {
    let mut c = FingerConditioner::default();
    let g = gains().paper_law();
    let sp = c.step(1.0, &g, DT, FREE);
    assert!((sp.velocity.0 - 0.15).abs() < 1e-12);
    run(&mut c, &g, 1.0, 100);
    assert_eq!(c.omega(), 1.0);
    // The paper's law holds the velocity when the label returns to zero: the wind-up the
    // default law removes.
    let sp = c.step(0.0, &g, DT, FREE);
    assert_eq!(sp.velocity.0, 1.0);
}

/// A sustained grip, then rest, at the shipped defaults: the finger stops (|ω| < 0.05 rad/s)
/// within 0.5 s of the patient relaxing, where the paper's law keeps closing at ω_max.
#[test]
fn no_wind_up_a_finger_stops_within_half_a_second_of_rest() {
    let g = FingerGains::default();
    let mut c = FingerConditioner::default();
    run(&mut c, &g, 1.0, 200);
    assert!(c.omega() > 0.95 * g.omega_max, "grip: {}", c.omega());
    let mut stopped_after = None;
    for n in 1..=40 {
        let sp = c.step(0.0, &g, DT, FREE);
        if stopped_after.is_none() && sp.velocity.0.abs() < 0.05 {
            stopped_after = Some(n as f64 * DT);
        }
    }
    let t = stopped_after.expect("the finger stops");
    assert!(t <= 0.5, "stopped after {t} s");
    assert!(c.omega().abs() < 1e-6, "and comes to rest: {}", c.omega());

    let mut paper = FingerConditioner::default();
    run(&mut paper, &g.paper_law(), 1.0, 200);
    run(&mut paper, &g.paper_law(), 0.0, 40);
    assert_eq!(paper.omega(), g.omega_max, "the paper's law winds up");
}

/// A rest offset just above the deadband: the paper's law winds up to full speed (about 9 s
/// at the defaults), the default law settles at the proportional speed kα·x/d.
#[test]
fn a_rest_offset_above_the_deadband_gives_a_proportional_speed_not_full_speed() {
    let g = FingerGains::default();
    let x = deadband(0.12, g.deadband);
    let mut c = FingerConditioner::default();
    run(&mut c, &g, 0.12, 1200); // 60 s
    let steady = g.kalpha * x / g.damping_per_s;
    assert!(
        (c.omega() - steady).abs() < 1e-6 && steady < 0.1 * g.omega_max,
        "{} vs {steady}",
        c.omega()
    );
    let mut paper = FingerConditioner::default();
    let sp = run(&mut paper, &g.paper_law(), 0.12, 200); // 10 s
    assert_eq!(sp.velocity.0, g.omega_max);
}

/// Every damping and tick the config allows: from full speed at rest the velocity falls
/// monotonically to zero without ever changing sign, and under a steady label it approaches
/// its steady speed monotonically without overshoot (the explicit update flipped sign every
/// tick once d·dt > 1 and diverged past 2).
#[test]
fn damping_is_stable_for_every_allowed_damping_and_tick() {
    use crate::config::limits::{DAMPING, TICK_MS};
    let ticks = [TICK_MS.0, 20, 50, TICK_MS.1];
    let dampings = [0.0, 0.1, 1.5, 10.0, 19.9, 20.0, 25.0, 40.0, DAMPING.1];
    for tick_ms in ticks {
        let dt = tick_ms as f64 * 1e-3;
        for d in dampings {
            for rest in [0.0, d, DAMPING.1] {
                let g = FingerGains {
                    damping_per_s: d,
                    rest_damping_per_s: rest,
                    kalpha: 50.0,
                    omega_max: 10.0,
                    ..gains()
                };
                let mut c = FingerConditioner::default();
                let mut prev = 0.0;
                for _ in 0..400 {
                    let w = c.step(0.6, &g, dt, FREE).velocity.0;
                    assert!(w >= prev - 1e-12, "d {d} dt {dt}: {prev} -> {w}");
                    prev = w;
                }
                if d > 0.0 {
                    let x = deadband(0.6, g.deadband);
                    let steady = (g.kalpha * x / d).min(g.omega_max);
                    assert!(prev <= steady + 1e-9, "d {d} dt {dt}: {prev} > {steady}");
                }
                for _ in 0..400 {
                    let w = c.step(0.0, &g, dt, FREE).velocity.0;
                    assert!(
                        w >= 0.0 && w <= prev + 1e-12,
                        "d {d} rest {rest} dt {dt}: {prev} -> {w}"
                    );
                    prev = w;
                }
            }
        }
    }
}

#[test]
fn a_joint_limit_stops_integration_into_the_stop_and_lets_the_finger_leave() {
    let g = gains().paper_law();
    let mut c = FingerConditioner::default();
    run(&mut c, &g, 1.0, 3);
    assert!(c.omega() > 0.0);
    for _ in 0..50 {
        let sp = c.step(1.0, &g, DT, AT_LIMIT);
        assert!(sp.velocity.0 <= 0.0, "grew into the flexion stop");
        assert_eq!(
            sp.force,
            Newton(8.0),
            "it still pushes with the force asked"
        );
    }
    // Extension leaves the flexion stop while the limit is still reported.
    let sp = c.step(-1.0, &g, DT, AT_LIMIT);
    assert!(sp.velocity.0 < 0.0, "{}", sp.velocity.0);
    // A new limit while moving into extension is the extension stop.
    let mut c = FingerConditioner::default();
    run(&mut c, &g, -1.0, 3);
    c.step(0.0, &g, DT, FREE);
    assert!(c.step(-1.0, &g, DT, AT_LIMIT).velocity.0 >= 0.0);
    assert!(c.step(1.0, &g, DT, AT_LIMIT).velocity.0 > 0.0);
}

/// A live tune from kF 2 to 40 under a full grip: the force moves at most KF_MAX·dt/ramp_s
/// per tick, never in one step.
#[test]
fn a_tune_ramps_the_force_instead_of_jumping() {
    let mut g = FingerGains {
        kf: 2.0,
        slew_per_s: 10.0,
        ..FingerGains::default()
    };
    let mut c = FingerConditioner::default();
    let mut prev = run(&mut c, &g, 1.0, 100).force.0;
    assert!((prev - 2.0).abs() < 1e-9);
    g.kf = 40.0;
    let bound = KF_MAX * DT / g.ramp_s + 1e-9;
    let mut ticks = 0;
    while prev < 40.0 - 1e-9 {
        let f = c.step(1.0, &g, DT, FREE).force.0;
        assert!(f - prev <= bound, "step {} N > {bound} N", f - prev);
        prev = f;
        ticks += 1;
    }
    assert_eq!(ticks, 19, "38 N at 2 N per tick");
    g.kalpha = 50.0;
    let mut w = c.omega();
    for _ in 0..40 {
        let next = c.step(1.0, &g, DT, FREE).velocity.0;
        assert!((next - w).abs() <= KALPHA_MAX * DT + 1e-9);
        w = next;
    }
}

/// After a reset (arm, a model swap, any safe stop) the finger starts from rest and its gains
/// ramp in: the first ticks' force is bounded by the ramp, not by kF, whatever the label.
#[test]
fn after_a_reset_force_and_velocity_start_from_rest() {
    let g = FingerGains {
        kf: 40.0,
        slew_per_s: 10.0,
        ..FingerGains::default()
    };
    let mut c = FingerConditioner::default();
    run(&mut c, &g, 1.0, 100);
    assert!((c.step(1.0, &g, DT, FREE).force.0 - 40.0).abs() < 1e-9);
    c.reset();
    assert_eq!(c, FingerConditioner::default());
    let mut prev = Setpoint::default();
    for n in 1..=30 {
        let sp = c.step(1.0, &g, DT, FREE);
        let kf_bound = (KF_MAX * DT * n as f64 / g.ramp_s).min(g.kf);
        assert!(sp.force.0 <= kf_bound * sp.label + 1e-9, "tick {n}");
        assert!(sp.force.0 - prev.force.0 <= KF_MAX * DT / g.ramp_s + g.kf * 0.5 * 0.5);
        assert!(sp.velocity.0 - prev.velocity.0 <= KALPHA_MAX * DT + 1e-9);
        prev = sp;
    }
}

#[test]
fn slew_limit_bounds_the_change_per_tick() {
    let mut c = FingerConditioner::default();
    let g = FingerGains {
        slew_per_s: 2.0,
        deadband: 0.0,
        ..gains()
    };
    let sp = c.step(1.0, &g, DT, FREE);
    assert!((sp.label - 0.1).abs() < 1e-12);
    let sp = c.step(-1.0, &g, DT, FREE);
    assert!(sp.label.abs() < 1e-12);
}

#[test]
fn non_finite_label_commands_nothing() {
    let mut c = FingerConditioner::default();
    let sp = c.step(f64::NAN, &gains(), DT, FREE);
    assert_eq!(sp, Setpoint::default());
}
