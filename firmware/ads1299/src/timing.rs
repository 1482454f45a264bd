//! Serial interface timing (SBAS499C, "Timing Requirements: Serial Interface" and the RESET
//! and power-up sections), for the nominal 2.048 MHz master clock (internal oscillator, or
//! the first chip's CLK output feeding the second).

/// Nominal master clock, Hz.
pub const F_CLK_HZ: u32 = 2_048_000;

/// One master clock period, ns, rounded up (488.28 ns).
pub const T_CLK_NS: u32 = 489;

/// tSDECODE: command decode time, 4 tCLK. Between the bytes of a multi-byte command (RREG,
/// WREG and their register bytes), one byte's end and the next must be this far apart.
pub const T_SDECODE_NS: u32 = 4 * T_CLK_NS;

/// tSCCS: last SCLK edge to CS high, 4 tCLK (so the last byte of a command is decoded).
pub const T_SCCS_NS: u32 = 4 * T_CLK_NS;

/// After a RESET command: 18 tCLK before the next command.
pub const T_RESET_NS: u32 = 18 * T_CLK_NS;

/// tPOR: from power-up (supplies settled) to the first command, 2^18 tCLK (128 ms).
pub const T_POR_NS: u32 = (1 << 18) * T_CLK_NS;
