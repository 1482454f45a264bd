//! The one error type of the simulator's set-up: every configuration is checked once, when a
//! node or script is built, so the per-sample and per-tick paths cannot fail.

/// A rejected simulator configuration or scenario.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SimError {
    /// A numeric parameter outside its allowed range.
    #[error("{name} = {value} is outside {allowed}")]
    OutOfRange {
        /// Parameter name as in the config struct.
        name: &'static str,
        /// The rejected value.
        value: f64,
        /// The allowed range, for the message.
        allowed: &'static str,
    },
    /// A finger index that is not 0 (thumb) ..= 4 (pinky).
    #[error("finger index {0} is not 0 (thumb) ..= 4 (pinky)")]
    BadFinger(usize),
    /// A script or scenario that cannot be run as given.
    #[error("invalid script: {0}")]
    BadScript(String),
    /// A node's bus handle could not be opened.
    #[error("cannot open the bus: {0}")]
    Transport(String),
    /// The amplifier node's firmware refused the simulated board's settings.
    #[error("the simulated amplifier board's settings: {0}")]
    AmpBoardSettings(#[from] amp_node::NodeSettingsError),
    /// The firmware's ADS1299 start-up failed on the simulated chips.
    #[error("the simulated amplifier board's chips did not start: {0}")]
    AmpBoardStart(#[from] ads1299::Error<embedded_hal::spi::ErrorKind>),
    /// An unknown scenario name.
    #[error("unknown scenario {0:?}; known: {1}")]
    UnknownScenario(String, String),
}

/// Checks `lo <= value <= hi` (and that it is finite).
pub(crate) fn check_range(
    name: &'static str,
    value: f64,
    lo: f64,
    hi: f64,
    allowed: &'static str,
) -> Result<(), SimError> {
    if value.is_finite() && value >= lo && value <= hi {
        Ok(())
    } else {
        Err(SimError::OutOfRange {
            name,
            value,
            allowed,
        })
    }
}
