//! Running a world on the in-memory bus faster than real time while a monitor sees every
//! frame with its receive time: what `handsim --mem` and the daemon's demo calibration use to
//! record a session.

use hand_dbc::CanFrame;

use crate::bus::MemBus;
use crate::clock::VirtualClock;
use crate::error::SimError;
use crate::world::{PatientMode, World, WorldConfig};

/// Steps a world built from `cfg` and `patient` on a fresh in-memory bus, in 1 ms steps of a
/// virtual clock from 0 to `duration_us`, and hands every frame on the bus, with its time, to
/// `sink` (which may stop the run with an error).
pub fn run_on_mem_bus<E>(
    cfg: WorldConfig,
    patient: PatientMode,
    duration_us: u64,
    mut sink: impl FnMut(u64, &CanFrame) -> Result<(), E>,
) -> Result<Result<(), E>, SimError> {
    let clock = VirtualClock::new();
    let bus = MemBus::with_clock(clock.clone()).with_capacity(1 << 16);
    let mut monitor = bus.endpoint();
    let mut world = World::try_new(cfg, patient, || {
        Ok::<_, std::convert::Infallible>(bus.endpoint())
    })?;
    let mut t = 0;
    while t <= duration_us {
        clock.set_us(t);
        world.step(t);
        while let Some(r) = monitor.receive_timestamped() {
            if let Err(e) = sink(r.time_us.unwrap_or(t), &r.frame) {
                return Ok(Err(e));
            }
        }
        t += 1000;
    }
    Ok(Ok(()))
}
