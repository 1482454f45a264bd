//! Issue 13: what a live line says, checked against the bus itself. The loop runs with the
//! simulated world on the in-memory bus (virtual clock); a probe records every frame, and the
//! frame counters, the bus load (hand.dbc's worst-case formula, recomputed here), the finger
//! positions and forces the controllers reported are recomputed from what it saw.

mod common;

use common::Rig;
use driver::live::{Live, ModelInfo};
use hand_dbc::messages::{FingerSetpoint, FingerStatus, HandDiag, HandHeartbeat};
use hand_dbc::CanFrame;
use hand_model::faults::FaultPlan;
use hand_model::patient::{Intent, Script};

fn from_daemon(f: &CanFrame) -> bool {
    let id = f.raw_id();
    FingerSetpoint::instance_of(id).is_some() || id == HandDiag::ID || id == HandHeartbeat::ID
}

/// hand.dbc's comment: bits per frame = 47 + 8*DLC + floor((34 + 8*DLC - 1)/4).
fn worst_case_bits(f: &CanFrame) -> u64 {
    let d = 8 * f.data().len() as u64;
    47 + d + (34 + d - 1) / 4
}

/// Fingers against the controllers' last reports, channels against the engine's features.
fn check_fingers_and_channels(live: &Live, upto: &[&(u64, CanFrame)], features: &[f64]) {
    for f in 0..5 {
        let last = upto
            .iter()
            .rev()
            .find(|(_, fr)| FingerStatus::instance_of(fr.raw_id()) == Some(f))
            .map(|(_, fr)| FingerStatus::decode(fr.raw_id(), fr.data()).expect("decodes"))
            .expect("the controller reported");
        let fl = &live.fingers[f];
        assert_eq!(fl.reported_position_rad, last.position(), "finger {f}");
        assert_eq!(fl.reported_force_n, last.force(), "finger {f}");
        assert!(fl.active && !fl.disabled, "finger {f}: {fl:?}");
    }
    assert_eq!(live.channels.len(), 12);
    for (c, ch) in live.channels.iter().enumerate() {
        assert!(ch.rms_uv > 0.0, "channel {c}");
        assert_eq!(ch.rms_uv, features[c * 8], "channel {c}: the RMS feature");
        assert!(!ch.lead_off && !ch.saturated, "channel {c}");
    }
}

#[test]
fn a_live_line_matches_the_bus() {
    let mut script = Script::new();
    script
        .rest(500_000)
        .hold(Intent::finger(1, 0.6), 10_000_000);
    let mut rig = Rig::new(FaultPlan::new(), script);
    rig.run_until(3_010_000);
    let snap = *rig.runner.snapshot().lock().expect("snapshot");
    let model = ModelInfo {
        id: "12345678".into(),
        path: "m.hsm".into(),
        kind: "ResDD".into(),
    };
    let rest = [1.5; 12];
    let live = Live::from_snapshot(&snap, &model, Some(&rest));
    assert_eq!(live.rest_rms_uv.as_deref(), Some(&rest[..]));
    assert_eq!(Live::from_snapshot(&snap, &model, None).rest_rms_uv, None);
    let t = live.t_us;
    assert_eq!(t, 3_000_000, "the last tick's deadline");
    assert_eq!(live.tick, 60);
    assert_eq!(live.state, "RUNNING", "{live:?}");
    assert!(live.faults.is_empty(), "{:?}", live.faults);

    let upto: Vec<&(u64, CanFrame)> = rig.seen.iter().filter(|(ts, _)| *ts <= t).collect();
    let tx = upto.iter().filter(|(_, f)| from_daemon(f)).count() as u64;
    let rx = upto.len() as u64 - tx;
    assert_eq!(live.counters.frames_tx, tx);
    assert_eq!(live.counters.frames_rx, rx);

    let bits: u64 = upto
        .iter()
        .filter(|(ts, _)| *ts > t - 1_000_000)
        .map(|(_, f)| worst_case_bits(f))
        .sum();
    let load = bits as f64 / 1e6;
    assert!(
        (live.bus_load - load).abs() < 1e-9,
        "{} vs {load}",
        live.bus_load
    );
    println!("bus load over the last second: {:.3}", live.bus_load);

    check_fingers_and_channels(&live, &upto, rig.runner.engine().model_features());

    let line = serde_json::to_string(&live).expect("serialises");
    let back: Live = serde_json::from_str(&line).expect("parses");
    assert_eq!(back, live);
    // Fields added later do not break a reader.
    let newer = line.replacen('{', "{\"added_later\":1,", 1);
    assert_eq!(serde_json::from_str::<Live>(&newer).expect("parses"), live);
}
