//! The few things the simulator takes from hand.dbc beyond the generated messages, and the
//! E2E sealing every node uses.

use hand_dbc::e2e::E2eProfile;
pub use hand_dbc::CanFrame;

/// ADC resolution of the EMG signals: µV per count (hand.dbc EMG_SAMPLES factor).
pub const EMG_LSB_UV: f64 = hand_dbc::emg::EMG_LSB_UV;

/// Writes `counter` into the alive-counter bits of byte 1 and the CRC into byte 0.
///
/// The nodes seal frames themselves rather than through `E2eProtector` because faults need
/// to choose the counter (jumps, stuck counters) and the three EMG groups share one sample
/// counter. `corrupt_crc` flips the CRC's bits, for the bad-CRC fault.
pub fn seal(frame: &mut CanFrame, profile: E2eProfile, counter: u8, corrupt_crc: bool) {
    let mask = if profile.counter_bits() == 8 {
        0xFF
    } else {
        0x0F
    };
    let data = frame.data_mut();
    if data.len() < 2 {
        return;
    }
    data[1] = (data[1] & !mask) | (counter & mask);
    let crc = profile.crc(data);
    data[0] = if corrupt_crc { !crc } else { crc };
}
