//! Issue 30 on the in-memory bus, through a transport that misbehaves on cue as real CAN
//! controllers do and vcan never does: error-passive, a full transmit queue, a controller that
//! reopens but cannot send.

mod common;

use std::sync::{Arc, Mutex};

use common::{random_predictor, Rig};
use driver::daemon::SPIN_BACKOFF_MAX_US;
use driver::engine::Command;
use driver::mem_transport::MemTransport;
use driver::safety::{DaemonState, Fault};
use driver::transport::{BusHealth, ControllerState, Timestamped, Transport, TransportError};
use hand_clock::VirtualClock;
use hand_dbc::CanFrame;
use hand_model::faults::FaultPlan;
use hand_model::patient::Script;
use hand_model::world::PatientMode;

const ONSET: u64 = 2_000_000;

/// What the misbehaving transport does now.
#[derive(Debug, Default)]
struct Cue {
    state: ControllerState,
    /// Every send is refused with ENOBUFS.
    queue_full: bool,
    /// Every send fails with bus-off (a reopen still succeeds: the interface is up).
    sends_fail: bool,
    reopens: u64,
}

struct Flaky {
    inner: MemTransport<VirtualClock>,
    cue: Arc<Mutex<Cue>>,
}

impl Transport for Flaky {
    fn try_recv(&mut self) -> Result<Option<Timestamped>, TransportError> {
        self.inner.try_recv()
    }
    fn send(&mut self, frame: &CanFrame) -> Result<(), TransportError> {
        let c = self.cue.lock().unwrap();
        if c.sends_fail {
            return Err(TransportError::BusOff);
        }
        if c.queue_full {
            return Err(TransportError::QueueFull);
        }
        drop(c);
        self.inner.send(frame)
    }
    fn drop_queued(&mut self) {}
    fn reopen(&mut self) -> Result<(), TransportError> {
        self.cue.lock().unwrap().reopens += 1;
        Ok(())
    }
    fn health(&self) -> BusHealth {
        BusHealth {
            state: self.cue.lock().unwrap().state,
            ..BusHealth::default()
        }
    }
}

fn rig() -> (Rig<Flaky>, Arc<Mutex<Cue>>) {
    let cue = Arc::new(Mutex::new(Cue::default()));
    let c = Arc::clone(&cue);
    let r = Rig::with_transport(
        FaultPlan::new(),
        PatientMode::Script(Script::resting(20_000_000)),
        random_predictor(7),
        move |inner| Flaky { inner, cue: c },
    );
    (r, cue)
}

fn running_before(r: &mut Rig<Flaky>) {
    r.run_until(ONSET);
    assert_eq!(r.runner.engine().state(), DaemonState::Running);
}

#[test]
fn error_passive_stops_the_hand_while_it_lasts_and_clears_by_itself() {
    let (mut r, cue) = rig();
    running_before(&mut r);
    cue.lock().unwrap().state = ControllerState::ErrorPassive;
    r.run_until(ONSET + 60_000);
    let faults = r.runner.engine().faults();
    assert_eq!(r.runner.engine().state(), DaemonState::Safe);
    assert!(faults.contains(Fault::BusDegraded), "{faults}");
    assert!(
        !faults.contains(Fault::BusOff),
        "error-passive latched as bus-off: {faults}"
    );
    r.run_until(ONSET + 300_000);
    cue.lock().unwrap().state = ControllerState::ErrorActive;
    // Transient: RUNNING again after the recovery time (500 ms), no arm.
    r.run_until(ONSET + 300_000 + 700_000);
    assert_eq!(
        r.runner.engine().state(),
        DaemonState::Running,
        "{}",
        r.runner.engine().faults()
    );
}

#[test]
fn a_full_transmit_queue_is_counted_and_only_a_lasting_one_is_a_transient_fault() {
    let (mut r, cue) = rig();
    running_before(&mut r);
    // 100 ms full: shorter than the controllers' own timeout, counted only.
    cue.lock().unwrap().queue_full = true;
    r.run_until(ONSET + 100_000);
    cue.lock().unwrap().queue_full = false;
    r.run_until(ONSET + 200_000);
    assert_eq!(
        r.runner.engine().state(),
        DaemonState::Running,
        "{}",
        r.runner.engine().faults()
    );
    let counted = r.runner.bus_health().counters.tx_queue_full;
    assert!(counted >= 2, "{counted} refusals counted");
    // 400 ms full: a transient fault, never a latched one, gone after the recovery time.
    cue.lock().unwrap().queue_full = true;
    r.run_until(ONSET + 600_000);
    let faults = r.runner.engine().faults();
    assert_eq!(r.runner.engine().state(), DaemonState::Safe);
    assert!(faults.contains(Fault::BusDegraded), "{faults}");
    assert!(!faults.contains(Fault::InterfaceDown), "latched: {faults}");
    cue.lock().unwrap().queue_full = false;
    r.run_until(ONSET + 1_400_000);
    assert_eq!(
        r.runner.engine().state(),
        DaemonState::Running,
        "{}",
        r.runner.engine().faults()
    );
}

#[test]
fn a_bus_that_reopens_but_cannot_send_backs_off_instead_of_spinning() {
    let (mut r, cue) = rig();
    running_before(&mut r);
    cue.lock().unwrap().sends_fail = true;
    r.run_until(ONSET + 3_000_000);
    let reopens = cue.lock().unwrap().reopens;
    let epochs = r.runner.engine().epochs_begun(0);
    println!("3 s of a bus that takes no frame: {reopens} reopens, {epochs} epochs begun");
    // 10 ms doubling to 1 s: 10+20+...+640+1000+1000 ms passes 3 s after 9 or 10 attempts.
    // Before the backoff grew across reopens, it was one attempt a tick or more (>= 60).
    assert!(reopens <= 12, "{reopens} reopens in 3 s");
    assert!(epochs <= 14, "{epochs} epochs begun");
    // The bus works again: the next reopen sticks, the backoff resets once frames arrive, and
    // arm brings the hand back.
    cue.lock().unwrap().sends_fail = false;
    r.run_until(ONSET + 3_000_000 + SPIN_BACKOFF_MAX_US + 200_000);
    let now = r.clock_now();
    r.runner.engine_mut().command(now, Command::Arm).unwrap();
    r.run_until(now + 1_000_000);
    assert_eq!(r.runner.engine().state(), DaemonState::Running);
}
