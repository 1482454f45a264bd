//! The product: the `handd` daemon (the 50 ms control loop, its safety state machine and
//! transports) and the technician CLI `handctl`.
