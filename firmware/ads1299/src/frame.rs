//! One conversion as read in RDATAC mode: 24 status bits then 8 channels of 24 bits
//! (SBAS499C, "Data Output (DOUT)"), 27 bytes, most significant byte first.

/// Bytes in one data frame: 3 status + 8 x 3 channel bytes.
pub const FRAME_BYTES: usize = 27;

/// The status word's top nibble: always 1100.
const HEADER: u8 = 0b1100;

/// A 24-bit two's complement conversion result, sign-extended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Code(i32);

impl Code {
    /// Positive full scale: an input at or above +VREF / gain (a clipped channel).
    pub const POSITIVE_FULL_SCALE: Code = Code(0x7F_FFFF);
    /// Negative full scale: an input at or below -VREF / gain (a clipped channel).
    pub const NEGATIVE_FULL_SCALE: Code = Code(-0x80_0000);

    /// A code from its three bytes, most significant first.
    #[inline]
    pub const fn from_be_bytes(b: [u8; 3]) -> Self {
        // Put the 24 bits at the top of an i32 and shift back: arithmetic shift sign-extends.
        Self(i32::from_be_bytes([b[0], b[1], b[2], 0]) >> 8)
    }

    /// A code from a value, `None` outside the 24-bit range.
    pub const fn new(value: i32) -> Option<Self> {
        if value >= Self::NEGATIVE_FULL_SCALE.0 && value <= Self::POSITIVE_FULL_SCALE.0 {
            Some(Self(value))
        } else {
            None
        }
    }

    /// The code's three bytes, most significant first.
    #[inline]
    pub const fn to_be_bytes(self) -> [u8; 3] {
        let b = self.0.to_be_bytes();
        [b[1], b[2], b[3]]
    }

    /// The sign-extended value.
    #[inline]
    pub const fn get(self) -> i32 {
        self.0
    }

    /// Whether the code is one of the two full-scale (saturation) codes.
    #[inline]
    pub const fn is_saturated(self) -> bool {
        self.0 == Self::POSITIVE_FULL_SCALE.0 || self.0 == Self::NEGATIVE_FULL_SCALE.0
    }
}

/// The 24-bit status word: `1100`, LOFF_STATP\[7:0\], LOFF_STATN\[7:0\], GPIO\[7:4\].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Status([u8; 3]);

impl Status {
    /// A status word with the header, lead-off bits and GPIO data (low nibble of `gpio`).
    pub const fn new(loff_statp: u8, loff_statn: u8, gpio: u8) -> Self {
        Self([
            (HEADER << 4) | (loff_statp >> 4),
            (loff_statp << 4) | (loff_statn >> 4),
            (loff_statn << 4) | (gpio & 0x0F),
        ])
    }

    /// Whether the word starts with the 1100 header.
    #[inline]
    pub const fn header_ok(self) -> bool {
        self.0[0] >> 4 == HEADER
    }

    /// LOFF_STATP: bit n-1 set when channel n's positive electrode is off.
    #[inline]
    pub const fn loff_statp(self) -> u8 {
        (self.0[0] << 4) | (self.0[1] >> 4)
    }

    /// LOFF_STATN: bit n-1 set when channel n's negative electrode is off.
    #[inline]
    pub const fn loff_statn(self) -> u8 {
        (self.0[1] << 4) | (self.0[2] >> 4)
    }

    /// Bit n-1 set when either electrode of channel n is off.
    #[inline]
    pub const fn lead_off(self) -> u8 {
        self.loff_statp() | self.loff_statn()
    }

    /// GPIO\[4:1\] data bits (the word's low nibble).
    #[inline]
    pub const fn gpio(self) -> u8 {
        self.0[2] & 0x0F
    }

    /// The three bytes as sent.
    pub const fn to_bytes(self) -> [u8; 3] {
        self.0
    }
}

/// One data frame: status and eight channel codes (index 0 = channel 1).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Frame {
    /// The status word.
    pub status: Status,
    /// Channel 1..8 codes.
    pub codes: [Code; 8],
}

impl Frame {
    /// Parses the 27 bytes as read; the header is not checked here ([`Status::header_ok`]).
    #[inline]
    pub fn parse(bytes: &[u8; FRAME_BYTES]) -> Self {
        let status = Status([bytes[0], bytes[1], bytes[2]]);
        let codes = core::array::from_fn(|c| {
            let i = 3 + 3 * c;
            Code::from_be_bytes([bytes[i], bytes[i + 1], bytes[i + 2]])
        });
        Self { status, codes }
    }

    /// The 27 bytes this frame is sent as.
    pub fn to_bytes(&self) -> [u8; FRAME_BYTES] {
        let mut out = [0; FRAME_BYTES];
        out[..3].copy_from_slice(&self.status.0);
        for (c, code) in self.codes.iter().enumerate() {
            out[3 + 3 * c..6 + 3 * c].copy_from_slice(&code.to_be_bytes());
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn codes_sign_extend_and_round_trip() {
        let cases = [
            ([0x7F, 0xFF, 0xFF], 0x7F_FFFF, true),
            ([0x80, 0x00, 0x00], -0x80_0000, true),
            ([0xFF, 0xFF, 0xFF], -1, false),
            ([0x00, 0x00, 0x01], 1, false),
            ([0x80, 0x00, 0x01], -0x7F_FFFF, false),
        ];
        for (bytes, value, saturated) in cases {
            let c = Code::from_be_bytes(bytes);
            assert!(c.get() == value, "{bytes:02x?} -> {}", c.get());
            assert!(c.is_saturated() == saturated);
            assert!(c.to_be_bytes() == bytes);
        }
        assert!(Code::new(0x80_0000).is_none() && Code::new(-0x80_0001).is_none());
    }

    #[test]
    fn status_word_fields() {
        let s = Status::new(0b1010_0101, 0b0000_0011, 0b1001);
        assert!(s.header_ok());
        assert!(s.to_bytes() == [0xCA, 0x50, 0x39]);
        assert!(s.loff_statp() == 0b1010_0101 && s.loff_statn() == 0b11 && s.gpio() == 0b1001);
        assert!(s.lead_off() == 0b1010_0111);
        assert!(!Status([0x0A, 0, 0]).header_ok());
    }

    #[test]
    fn frame_round_trips() {
        let mut codes = [Code(0); 8];
        for (c, code) in codes.iter_mut().enumerate() {
            *code = Code::new(c as i32 * 1_000_003 - 4_000_000).expect("in range");
        }
        let f = Frame {
            status: Status::new(1, 2, 3),
            codes,
        };
        assert!(Frame::parse(&f.to_bytes()) == f);
    }
}
