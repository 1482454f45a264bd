//! Waiting for DRDY (active low: a conversion is ready) with a bound.

use embedded_hal::delay::DelayNs;
use embedded_hal::digital::InputPin;

use crate::Error;

/// Polls `drdy` every `poll_ns` until it reads low, at most `max_polls` times: `Ok` when it
/// went low, [`Error::DrdyTimeout`] when it never did, [`Error::DrdyPin`] when the pin could
/// not be read. Pick the bound from the data rate: a couple of sample periods.
pub fn wait_drdy<P: InputPin, D: DelayNs, E>(
    drdy: &mut P,
    delay: &mut D,
    poll_ns: u32,
    max_polls: u32,
) -> Result<(), Error<E>> {
    for _ in 0..max_polls {
        if drdy.is_low().map_err(|_| Error::DrdyPin)? {
            return Ok(());
        }
        delay.delay_ns(poll_ns);
    }
    Err(Error::DrdyTimeout)
}
