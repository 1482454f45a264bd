//! End-to-end (E2E) protection of safety-relevant frames: an alive counter and a CRC-8.
//!
//! Layout (fixed for every protected message of hand.dbc, checked by the code generator):
//! byte 0 is the CRC, the low 4 or 8 bits of byte 1 are the alive counter. The CRC is CRC-8
//! SAE J1850 (poly 0x1D, init 0xFF, xorout 0xFF, not reflected) over the message's 16-bit data
//! id (low byte first) followed by payload bytes 1..DLC. Because the data id enters the CRC but
//! is never sent, a frame that is correct for one message is rejected when it arrives under
//! another id (a corrupted id, or a sender mixing up buffers).
//!
//! That holds only if no two protected messages of one length leave the CRC register in the
//! same state after their data ids: the data id reaches the CRC only through that 8-bit
//! register, so two such messages compute the same CRC over every payload (17 ids in 256
//! registers collide more often than not). The code generator therefore refuses hand.dbc when
//! two protected messages of equal length share the register, whatever their counter widths;
//! unequal registers give unequal CRCs for every payload, and unequal lengths fail the length
//! check. `cargo test -p hand-dbc-codegen --test refusals e2e_register_table -- --nocapture`
//! prints the table.
//!
//! The receiver side follows AUTOSAR E2E Profile 1: [`E2eChecker::check`] classifies each
//! reception as [`E2eStatus::Ok`], [`E2eStatus::Sync`], [`E2eStatus::Repeated`],
//! [`E2eStatus::WrongSequence`], [`E2eStatus::Error`] or [`E2eStatus::NoNewData`]. With
//! [`E2eCheckConfig::profile1`] a wrong sequence (a counter jump, or a repeat) is followed by a
//! resynchronisation: [`E2eCheckConfig::sync_counter`] consecutive in-sequence frames (default
//! 2) are reported `Sync` before the data is used again, so a single stray frame, a replay or a
//! second sender interleaving with the real one cannot slip data in right after it. Only `Ok`
//! means "use the data". [`E2eChecker::try_new`] builds a checker without that phase
//! ([`E2eCheckConfig::resync_at_once`]) for streams that must act on every correct frame.

use crate::frame::CanFrame;

/// CRC-8 SAE J1850 lookup table (poly 0x1D), built at compile time.
const CRC8_TABLE: [u8; 256] = {
    let mut table = [0u8; 256];
    let mut i = 0;
    while i < 256 {
        let mut crc = i as u8;
        let mut bit = 0;
        while bit < 8 {
            crc = if crc & 0x80 != 0 {
                (crc << 1) ^ 0x1D
            } else {
                crc << 1
            };
            bit += 1;
        }
        table[i] = crc;
        i += 1;
    }
    table
};

/// Bytes one slicing step takes.
const SLICE: usize = 8;

/// `CRC8_SLICES[k][i]` is the register after `i` then `k` zero bytes went through the table
/// (`T` applied `k + 1` times). The table is linear over GF(2) (`T[a ^ b] = T[a] ^ T[b]`), so
/// the register after bytes `b0..bn` (n < 8) from `crc` is
/// `S[n][crc ^ b0] ^ S[n-1][b1] ^ ... ^ S[0][bn]`: one dependent lookup per 8 bytes instead of
/// one per byte, the same value bit for bit.
const CRC8_SLICES: [[u8; 256]; SLICE] = {
    let mut s = [CRC8_TABLE; SLICE];
    let mut k = 1;
    while k < SLICE {
        let mut i = 0;
        while i < 256 {
            s[k][i] = CRC8_TABLE[s[k - 1][i] as usize];
            i += 1;
        }
        k += 1;
    }
    s
};

/// Feeds `data` into a running (not yet finalised) J1850 CRC register, up to 8 bytes at a
/// time ([`CRC8_SLICES`]).
#[inline]
fn crc8_update(mut crc: u8, data: &[u8]) -> u8 {
    for chunk in data.chunks(SLICE) {
        let last = chunk.len() - 1;
        let mut next = CRC8_SLICES[last][usize::from(crc ^ chunk[0])];
        for (j, &b) in chunk.iter().enumerate().skip(1) {
            next ^= CRC8_SLICES[last - j][usize::from(b)];
        }
        crc = next;
    }
    crc
}

/// [`crc8_update`] over exactly `N` (1..=8) bytes: one slicing step, unrolled. The
/// protected EMG and command frames are 8 bytes, so a check covers 7.
#[inline(always)]
fn crc8_block<const N: usize>(crc: u8, bytes: &[u8; N]) -> u8 {
    let mut next = CRC8_SLICES[N - 1][usize::from(crc ^ bytes[0])];
    for (j, &b) in bytes.iter().enumerate().skip(1) {
        next ^= CRC8_SLICES[N - 1 - j][usize::from(b)];
    }
    next
}

/// CRC-8 SAE J1850 of `data`: poly 0x1D, init 0xFF, xorout 0xFF (check value of "123456789"
/// is 0x4B).
pub fn crc8_j1850(data: &[u8]) -> u8 {
    crc8_update(0xFF, data) ^ 0xFF
}

/// What went wrong configuring or applying E2E protection.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum E2eError {
    /// Counter width other than 4 or 8 bits.
    #[error("E2E counter must be 4 or 8 bits wide, got {bits}")]
    CounterBits {
        /// The refused width.
        bits: u8,
    },
    /// A protected message needs at least the CRC byte and the counter byte.
    #[error("E2E-protected payload must be 2..=8 bytes, got {dlc}")]
    Dlc {
        /// The refused length.
        dlc: usize,
    },
    /// Max delta counter must be at least 1 and below the counter's modulus.
    #[error("max delta counter must be in 1..={max}, got {value}")]
    MaxDelta {
        /// The refused value.
        value: u16,
        /// Largest allowed value.
        max: u16,
    },
    /// A frame whose payload length differs from the profile's.
    #[error(
        "payload has {got} bytes, the E2E profile (data id {data_id:#06x}) expects {expected}"
    )]
    Length {
        /// Data id of the profile.
        data_id: u16,
        /// Length of the profile.
        expected: usize,
        /// Length given.
        got: usize,
    },
    /// A frame of another message handed to a protector.
    #[error("message with data id {got:#06x} handed to the protector of data id {expected:#06x}")]
    WrongMessage {
        /// The protector's data id.
        expected: u16,
        /// The message's data id.
        got: u16,
    },
}

/// The E2E parameters of one message (or one instance of a per-finger message).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct E2eProfile {
    data_id: u16,
    counter_bits: u8,
    dlc: u8,
    /// The CRC register after the data id (a function of `data_id`), so a check runs the
    /// table over the payload only.
    id_crc: u8,
}

/// The running J1850 register after the two data id bytes (low byte first), from init 0xFF:
/// [`crc8_update`]`(0xFF, &data_id.to_le_bytes())`, at compile time.
const fn crc_after_id(data_id: u16) -> u8 {
    let [lo, hi] = data_id.to_le_bytes();
    let after_lo = CRC8_TABLE[(0xFF ^ lo) as usize];
    CRC8_TABLE[(after_lo ^ hi) as usize]
}

impl E2eProfile {
    /// Builds a profile: `counter_bits` 4 or 8, `dlc` 2..=8.
    pub fn try_new(data_id: u16, counter_bits: u8, dlc: usize) -> Result<Self, E2eError> {
        if counter_bits != 4 && counter_bits != 8 {
            return Err(E2eError::CounterBits { bits: counter_bits });
        }
        if !(2..=8).contains(&dlc) {
            return Err(E2eError::Dlc { dlc });
        }
        Ok(Self {
            data_id,
            counter_bits,
            dlc: dlc as u8,
            id_crc: crc_after_id(data_id),
        })
    }

    /// Profile from hand.dbc; the code generator has validated the arguments.
    pub(crate) const fn from_dbc(data_id: u16, counter_bits: u8, dlc: u8) -> Self {
        Self {
            data_id,
            counter_bits,
            dlc,
            id_crc: crc_after_id(data_id),
        }
    }

    /// The data id that enters the CRC.
    pub fn data_id(&self) -> u16 {
        self.data_id
    }

    /// Width of the alive counter in bits (4 or 8).
    pub fn counter_bits(&self) -> u8 {
        self.counter_bits
    }

    /// Payload length of the protected message.
    #[inline]
    pub fn dlc(&self) -> usize {
        usize::from(self.dlc)
    }

    /// Number of distinct counter values (16 or 256).
    #[inline]
    pub fn counter_modulus(&self) -> u16 {
        1 << self.counter_bits
    }

    #[inline]
    fn counter_mask(&self) -> u8 {
        if self.counter_bits == 8 {
            0xFF
        } else {
            0x0F
        }
    }

    /// The CRC that `data` (a whole payload, byte 0 included but ignored) should carry.
    /// `data` must hold at least 1 byte; bytes past the first are covered.
    #[inline]
    pub fn crc(&self, data: &[u8]) -> u8 {
        let rest = data.get(1..).unwrap_or(&[]);
        let crc = match <&[u8; 7]>::try_from(rest) {
            Ok(seven) => crc8_block(self.id_crc, seven),
            Err(_) => crc8_update(self.id_crc, rest),
        };
        crc ^ 0xFF
    }

    /// The alive counter carried by `data` (0 if `data` has no counter byte).
    #[inline]
    pub fn counter(&self, data: &[u8]) -> u8 {
        data.get(1).map_or(0, |b| b & self.counter_mask())
    }
}

/// Sender side: stamps consecutive alive counters and the CRC into outgoing frames.
#[derive(Debug, Clone)]
pub struct E2eProtector {
    profile: E2eProfile,
    next_counter: u8,
}

impl E2eProtector {
    /// A protector whose first frame carries counter 0.
    pub fn new(profile: E2eProfile) -> Self {
        Self {
            profile,
            next_counter: 0,
        }
    }

    /// The profile in use.
    pub fn profile(&self) -> E2eProfile {
        self.profile
    }

    /// The counter the next protected frame will carry.
    pub fn next_counter(&self) -> u8 {
        self.next_counter
    }

    /// Sets the counter the next protected frame carries (masked to the counter's width). A
    /// sender that skipped samples (the amplifier node dropping whole samples on a full
    /// transmit queue) jumps its counter by as many, so the receiver sees the gap.
    pub fn set_next_counter(&mut self, counter: u8) {
        self.next_counter = counter & self.profile.counter_mask();
    }

    /// Writes the next counter into byte 1 (other bits of byte 1 kept) and the CRC into byte 0,
    /// then advances the counter (wrapping at 16 or 256, as AUTOSAR counters do). Returns the
    /// counter written.
    pub fn protect_bytes(&mut self, data: &mut [u8]) -> Result<u8, E2eError> {
        if data.len() != self.profile.dlc() {
            return Err(E2eError::Length {
                data_id: self.profile.data_id,
                expected: self.profile.dlc(),
                got: data.len(),
            });
        }
        let counter = self.next_counter;
        let mask = self.profile.counter_mask();
        data[1] = (data[1] & !mask) | counter;
        data[0] = self.profile.crc(data);
        self.next_counter = counter.wrapping_add(1) & mask;
        Ok(counter)
    }

    /// [`Self::protect_bytes`] on a frame's payload.
    pub fn protect(&mut self, frame: &mut CanFrame) -> Result<u8, E2eError> {
        self.protect_bytes(frame.data_mut())
    }

    /// Encodes a generated message, protects it and returns the frame to send.
    pub fn protect_message<M: Protected>(&mut self, message: &M) -> Result<CanFrame, E2eError> {
        let profile = message.e2e_profile();
        if profile != self.profile {
            return Err(E2eError::WrongMessage {
                expected: self.profile.data_id,
                got: profile.data_id,
            });
        }
        let mut frame = message.to_frame();
        self.protect(&mut frame)?;
        Ok(frame)
    }
}

/// A generated message type that carries E2E protection.
pub trait Protected {
    /// The message's (or this instance's) E2E profile from hand.dbc.
    fn e2e_profile(&self) -> E2eProfile;
    /// The message encoded into a frame, counter and CRC as currently set.
    fn to_frame(&self) -> CanFrame;
}

/// Receiver-side classification of one reception (AUTOSAR E2E Profile 1 semantics).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum E2eStatus {
    /// CRC correct and the counter advanced by 1..=allowed delta (lost frames in between are
    /// counted, see [`E2eChecker::lost_frames`]), no resynchronisation pending; also the first
    /// correct frame after start. The data may be used.
    Ok,
    /// CRC correct and the counter in sequence, but the stream is still resynchronising after
    /// a wrong sequence or too many repeated/empty receptions (Profile 1's SYNC): the data must
    /// not be used yet. See [`E2eCheckConfig::sync_counter`].
    Sync,
    /// CRC correct but the counter did not change: the same frame again. Counts against
    /// [`E2eCheckConfig::max_no_new_or_repeated`].
    Repeated,
    /// CRC correct but the counter jumped further than allowed (too many frames lost, a stale
    /// sender, or a second sender). The counter becomes the new reference and the next
    /// [`E2eCheckConfig::sync_counter`] in-sequence frames are [`E2eStatus::Sync`].
    WrongSequence,
    /// Wrong CRC (corruption, or a frame of another message) or wrong length.
    Error,
    /// Nothing was received for this check.
    NoNewData,
}

/// The receiver's parameters, as AUTOSAR E2E Profile 1 names them: MaxDeltaCounterInit,
/// SyncCounterInit and MaxNoNewOrRepeatedData. Validated once by [`E2eChecker::with_config`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct E2eCheckConfig {
    /// Largest counter step accepted as in sequence (1 = no loss tolerated; at most
    /// modulus - 1). Each reception without usable new data (nothing, a repeat, a wrong CRC)
    /// widens the next allowed step by one, since the sender kept counting.
    pub max_delta_counter: u16,
    /// In-sequence frames needed after a wrong sequence before the data is used again: that
    /// many frames are reported [`E2eStatus::Sync`], the one after is [`E2eStatus::Ok`].
    /// 0 accepts the first in-sequence frame after a jump (the reference moves at once).
    pub sync_counter: u8,
    /// Receptions with a repeated counter (or checks with no new data) tolerated between two
    /// in-sequence frames; one more and the stream resynchronises as after a jump: the next
    /// `sync_counter` in-sequence frames are [`E2eStatus::Sync`]. `u16::MAX` turns the rule
    /// off. A receiver that calls `check(None)` on every cycle without a frame must
    /// allow the cycles it may miss.
    pub max_no_new_or_repeated: u16,
}

impl E2eCheckConfig {
    /// Default [`Self::sync_counter`]: two in-sequence frames before data is used again. One
    /// frame in sequence proves little (a stray sender hits the next counter with a chance of
    /// 1 in 16 on a 4-bit counter); two consecutive ones, 1 in 256, while a 50 Hz status
    /// stream loses only 40 ms to a resynchronisation.
    pub const DEFAULT_SYNC_COUNTER: u8 = 2;
    /// Default [`Self::max_no_new_or_repeated`]: none. A receiver that checks on reception
    /// only never calls `check(None)`, and a repeated counter is a wrong sequence: CAN does not
    /// deliver a frame twice in normal operation, so a repeat is a replay or a second sender.
    pub const DEFAULT_MAX_NO_NEW_OR_REPEATED: u16 = 0;

    /// Profile 1 with the defaults above and `max_delta_counter`.
    pub const fn profile1(max_delta_counter: u16) -> Self {
        Self {
            max_delta_counter,
            sync_counter: Self::DEFAULT_SYNC_COUNTER,
            max_no_new_or_repeated: Self::DEFAULT_MAX_NO_NEW_OR_REPEATED,
        }
    }

    /// No resynchronisation phase: a jump moves the reference and the next in-sequence frame
    /// is `Ok`; repeats are only reported. For streams whose consumer handles jumps itself
    /// (the EMG front end bridges gaps by the counter) or must act on every correct frame
    /// whatever its counter (HAND_ESTOP, whose senders interleave counters).
    pub const fn resync_at_once(max_delta_counter: u16) -> Self {
        Self {
            max_delta_counter,
            sync_counter: 0,
            max_no_new_or_repeated: u16::MAX,
        }
    }
}

/// Receiver side: classifies each reception of one message stream, following the check state
/// machine of AUTOSAR E2E Profile 1 (with the reference counter moved on a wrong sequence, as
/// the profile does when its sync counter is in use).
#[derive(Debug, Clone)]
pub struct E2eChecker {
    profile: E2eProfile,
    config: E2eCheckConfig,
    last_counter: Option<u8>,
    /// Receptions since the last in-sequence frame that widen the allowed step.
    widen: u16,
    /// Profile 1's NoNewOrRepeatedDataCounter.
    no_new_or_repeated: u16,
    /// Profile 1's SyncCounter: in-sequence frames still to be reported as `Sync`.
    sync_left: u8,
    lost_frames: u64,
}

impl E2eChecker {
    /// A checker without a resynchronisation phase ([`E2eCheckConfig::resync_at_once`]) that
    /// accepts counter steps of up to `max_delta_counter` (1 = no loss tolerated; at most
    /// modulus - 1).
    pub fn try_new(profile: E2eProfile, max_delta_counter: u16) -> Result<Self, E2eError> {
        Self::with_config(profile, E2eCheckConfig::resync_at_once(max_delta_counter))
    }

    /// A checker with `config`, validated here: the max delta must be in 1..=modulus - 1.
    pub fn with_config(profile: E2eProfile, config: E2eCheckConfig) -> Result<Self, E2eError> {
        let max = profile.counter_modulus() - 1;
        if config.max_delta_counter == 0 || config.max_delta_counter > max {
            return Err(E2eError::MaxDelta {
                value: config.max_delta_counter,
                max,
            });
        }
        Ok(Self {
            profile,
            config,
            last_counter: None,
            widen: 0,
            no_new_or_repeated: 0,
            sync_left: 0,
            lost_frames: 0,
        })
    }

    /// The profile in use.
    pub fn profile(&self) -> E2eProfile {
        self.profile
    }

    /// The receiver parameters in use.
    pub fn config(&self) -> E2eCheckConfig {
        self.config
    }

    /// Frames skipped inside accepted counter steps since start.
    pub fn lost_frames(&self) -> u64 {
        self.lost_frames
    }

    /// Forgets the reference counter: the next correct frame is accepted as the first.
    pub fn reset(&mut self) {
        self.last_counter = None;
        self.widen = 0;
        self.no_new_or_repeated = 0;
        self.sync_left = 0;
    }

    /// Classifies one reception: `Some(payload)` for a received frame, `None` when the
    /// receiver's cycle found nothing new. Every reception without usable new data (`None`, a
    /// repeat, a wrong CRC) widens the allowed counter step of the next frame by one (up to
    /// modulus - 1), since the sender kept counting. Only [`E2eStatus::Ok`] means the data may
    /// be used.
    #[inline]
    pub fn check(&mut self, data: Option<&[u8]>) -> E2eStatus {
        let Some(data) = data else {
            self.widen = self.widen.saturating_add(1);
            self.no_new_or_repeated = self.no_new_or_repeated.saturating_add(1);
            return E2eStatus::NoNewData;
        };
        if data.len() != self.profile.dlc() || data[0] != self.profile.crc(data) {
            self.widen = self.widen.saturating_add(1);
            return E2eStatus::Error;
        }
        let counter = self.profile.counter(data);
        let Some(last) = self.last_counter else {
            self.last_counter = Some(counter);
            self.widen = 0;
            self.no_new_or_repeated = 0;
            self.sync_left = 0;
            return E2eStatus::Ok;
        };
        // The step modulo 16 or 256: both counters are masked to the width.
        let delta = u16::from(counter.wrapping_sub(last) & self.profile.counter_mask());
        if delta == 0 {
            self.widen = self.widen.saturating_add(1);
            self.no_new_or_repeated = self.no_new_or_repeated.saturating_add(1);
            return E2eStatus::Repeated;
        }
        let allowed = self
            .config
            .max_delta_counter
            .saturating_add(self.widen)
            .min(self.profile.counter_modulus() - 1);
        self.last_counter = Some(counter);
        self.widen = 0;
        if delta > allowed {
            self.no_new_or_repeated = 0;
            self.sync_left = self.config.sync_counter;
            return E2eStatus::WrongSequence;
        }
        self.lost_frames += u64::from(delta - 1);
        if self.no_new_or_repeated > self.config.max_no_new_or_repeated {
            // Too many repeats or empty cycles: resynchronise, this frame being the first of
            // the `sync_counter` in-sequence frames (Profile 1 reports it SYNC on top of them;
            // counting it makes "N frames in sequence after a repeat" the same rule as after
            // a jump).
            self.sync_left = self.config.sync_counter;
        }
        self.no_new_or_repeated = 0;
        if self.sync_left > 0 {
            self.sync_left -= 1;
            return E2eStatus::Sync;
        }
        E2eStatus::Ok
    }

    /// [`Self::check`] on a frame (a remote frame counts as an error).
    pub fn check_frame(&mut self, frame: Option<&CanFrame>) -> E2eStatus {
        match frame {
            Some(f) if f.is_remote() => E2eStatus::Error,
            Some(f) => self.check(Some(f.data())),
            None => self.check(None),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sliced_crc_equals_the_bytewise_table() {
        let bytewise = |mut crc: u8, data: &[u8]| {
            for &b in data {
                crc = CRC8_TABLE[usize::from(crc ^ b)];
            }
            crc
        };
        let mut x: u32 = 0x1234_5678;
        let mut data = [0u8; 40];
        for b in &mut data {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            *b = x as u8;
        }
        for len in 0..=data.len() {
            for init in [0x00, 0xFF, 0x5A] {
                assert_eq!(
                    crc8_update(init, &data[..len]),
                    bytewise(init, &data[..len]),
                    "len {len}"
                );
                if let Ok(seven) = <&[u8; 7]>::try_from(&data[..len]) {
                    assert_eq!(crc8_block(init, seven), bytewise(init, seven), "block");
                }
            }
        }
        assert_eq!(crc8_j1850(b"123456789"), 0x4B);
        for id in [0x0000, 0x1100, 0x12AB, 0xFFFF] {
            assert_eq!(
                crc_after_id(id),
                crc8_update(0xFF, &u16::to_le_bytes(id)),
                "{id:#x}"
            );
        }
    }
}
