//! The simulated world on the bus: an sEMG amplifier node, finger motor-controller nodes and a
//! simulated patient, so that the daemon can be calibrated, run and broken without a person or
//! a prosthesis.
