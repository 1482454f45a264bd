//! Reading what the monitor saw: the scenario's start, the setpoints and finger statuses, and
//! when the daemon first commanded a safe stop.

use hand_dbc::messages::{FingerMode, FingerSetpoint, FingerState, FingerStatus, HandHeartbeat};

use super::monitor::Seen;

/// EMG_SAMPLES_G0's id: its sample counter is 0 at handsim's scenario start.
const EMG_G0_ID: u32 = 0x100;

/// Receive time of handsim's first EMG sample (EMG_SAMPLES_G0 with counter 0): the scenario's
/// time 0 on the kernel's time base. Panics if the monitor started after handsim.
pub fn scenario_start_us(seen: &[Seen]) -> u64 {
    let first = seen
        .iter()
        .find(|s| s.frame.as_ref().is_some_and(|f| f.raw_id() == EMG_G0_ID))
        .expect("no EMG_SAMPLES_G0 frame on the bus: did handsim's amplifier run?");
    let f = first.frame.as_ref().expect("a data frame");
    assert_eq!(
        f.data()[1],
        0,
        "the first EMG sample seen has counter {}: the monitor started after handsim",
        f.data()[1]
    );
    first.time_us
}

/// One setpoint frame the daemon sent.
#[derive(Debug, Clone, Copy)]
pub struct SetpointRecord {
    /// Receive time, µs since the epoch.
    pub time_us: u64,
    /// Finger 0..4.
    pub finger: usize,
    /// Mode.
    pub mode: FingerMode,
    /// Force, N.
    pub force: f64,
    /// Velocity, rad/s.
    pub velocity: f64,
}

/// Every decodable FINGER_SETPOINT frame, in order.
pub fn setpoints_of(seen: &[Seen]) -> Vec<SetpointRecord> {
    seen.iter()
        .filter_map(|s| {
            let f = s.frame.as_ref()?;
            let finger = FingerSetpoint::instance_of(f.raw_id())?;
            let sp = FingerSetpoint::decode(f.raw_id(), f.data()).ok()?;
            Some(SetpointRecord {
                time_us: s.time_us,
                finger,
                mode: sp.mode(),
                force: sp.force(),
                velocity: sp.velocity(),
            })
        })
        .collect()
}

/// One FINGER_STATUS frame a controller sent.
#[derive(Debug, Clone, Copy)]
pub struct StatusRecord {
    /// Receive time, µs since the epoch.
    pub time_us: u64,
    /// Finger 0..4.
    pub finger: usize,
    /// State.
    pub state: FingerState,
    /// Force, N.
    pub force: f64,
    /// Velocity, rad/s.
    pub velocity: f64,
}

/// Every decodable FINGER_STATUS frame, in order.
pub fn statuses_of(seen: &[Seen]) -> Vec<StatusRecord> {
    seen.iter()
        .filter_map(|s| {
            let f = s.frame.as_ref()?;
            let finger = FingerStatus::instance_of(f.raw_id())?;
            let st = FingerStatus::decode(f.raw_id(), f.data()).ok()?;
            Some(StatusRecord {
                time_us: s.time_us,
                finger,
                state: st.state(),
                force: st.force(),
                velocity: st.velocity(),
            })
        })
        .collect()
}

/// The time of the first setpoint frame at or after `from_us` that commands a safe stop (not
/// ACTIVE, zero force and velocity) for each finger in `fingers`, i.e. when the last of them
/// was first stopped; None if some finger never was.
pub fn first_safe_stop_after(
    sps: &[SetpointRecord],
    from_us: u64,
    fingers: &[usize],
) -> Option<u64> {
    let mut latest = 0;
    for &f in fingers {
        let t = sps.iter().find(|s| {
            s.finger == f
                && s.time_us >= from_us
                && s.mode != FingerMode::Active
                && s.force == 0.0
                && s.velocity == 0.0
        })?;
        latest = latest.max(t.time_us);
    }
    Some(latest)
}

/// The HAND_HEARTBEAT a seen frame carries, if it is one and decodes.
pub fn heartbeat(s: &Seen) -> Option<HandHeartbeat> {
    s.frame
        .as_ref()
        .filter(|f| f.raw_id() == HandHeartbeat::ID)
        .and_then(|f| HandHeartbeat::decode(f.data()).ok())
}

/// The names of the faults in a HAND_HEARTBEAT's FaultMask, as `handctl status` names them.
pub fn fault_names(mask: u16) -> Vec<&'static str> {
    driver::safety::Fault::ALL
        .iter()
        .filter(|f| mask & f.bit() != 0)
        .map(|f| f.name())
        .collect()
}
