//! The simulated chip: register file, command decoder, data frames served in RDATAC, the
//! serial timing checked.

use std::collections::VecDeque;
use std::sync::{Arc, Mutex, MutexGuard, PoisonError};

use ads1299::registers::{channel_masks, config1, config2, config3, gpio};
use ads1299::{command, Frame, FRAME_BYTES};
use embedded_hal::spi::{ErrorKind, ErrorType, Operation, SpiDevice};

/// 4 tCLK at 2.048 MHz, ns.
const FOUR_TCLK_NS: f64 = 4.0 * 1e9 / 2.048e6;

/// The chip's state, shared between the test and the driver's handle.
#[derive(Debug, Clone)]
pub struct SimState {
    /// Registers 00h..17h.
    pub regs: [u8; 0x18],
    /// Read data continuous mode.
    pub rdatac: bool,
    /// START was sent.
    pub started: bool,
    /// The conversion a data read returns (a new one replaces one never read, as on the chip).
    pub frames: VecDeque<[u8; FRAME_BYTES]>,
    /// The next transaction fails (an SPI error).
    pub fail_next: bool,
    /// Bytes of a command that followed the previous one sooner than 4 tCLK.
    pub timing_violations: u32,
    /// Register commands sent while in RDATAC (the chip ignores them).
    pub ignored_commands: u32,
}

impl SimState {
    fn reset(&mut self) {
        self.regs = [0; 0x18];
        self.regs[0x00] = 0x3E;
        self.regs[usize::from(config1::ADDRESS)] = config1::RESET;
        self.regs[usize::from(config2::ADDRESS)] = config2::RESET;
        self.regs[usize::from(config3::ADDRESS)] = config3::RESET;
        for ch in 0x05..=0x0C {
            self.regs[ch] = 0x61;
        }
        self.regs[usize::from(gpio::ADDRESS)] = gpio::RESET;
        self.rdatac = true;
        self.started = false;
    }
}

/// A handle to one simulated chip (clones share the chip: one for the driver, one for the
/// test or simulator that serves its conversions).
#[derive(Debug, Clone)]
pub struct SimAds1299(Arc<Mutex<SimState>>);

impl Default for SimAds1299 {
    fn default() -> Self {
        Self::new()
    }
}

impl SimAds1299 {
    /// A chip just powered (registers at reset, RDATAC).
    pub fn new() -> Self {
        let mut s = SimState {
            regs: [0; 0x18],
            rdatac: true,
            started: false,
            frames: VecDeque::new(),
            fail_next: false,
            timing_violations: 0,
            ignored_commands: 0,
        };
        s.reset();
        Self(Arc::new(Mutex::new(s)))
    }

    /// A chip in `state` (a copy of another's: see [`SimAds1299::state`]).
    pub fn from_state(state: SimState) -> Self {
        Self(Arc::new(Mutex::new(state)))
    }

    /// The chip's state, to read or script (a poisoned lock is taken as it is: the state is
    /// plain data).
    pub fn state(&self) -> MutexGuard<'_, SimState> {
        self.0.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// A new conversion: the frame the next data read returns (replacing one never read).
    pub fn serve(&self, frame: &Frame) {
        self.serve_bytes(frame.to_bytes());
    }

    /// A new conversion as raw bytes (a corrupted frame).
    pub fn serve_bytes(&self, bytes: [u8; FRAME_BYTES]) {
        let mut s = self.state();
        s.frames.clear();
        s.frames.push_back(bytes);
    }
}

/// Where the command decoder is within one transaction.
enum Step {
    Opcode,
    Count { write: bool, address: u8 },
    Data { write: bool, address: u8, left: u8 },
}

impl Step {
    /// The step after the chip has taken `b` (an opcode, a register count or a register's
    /// value; RDATAC keeps the registers as they are).
    fn written(self, s: &mut SimState, b: u8) -> Step {
        match self {
            Step::Opcode => decode(s, b),
            Step::Count { write, address } => Step::Data {
                write,
                address,
                left: (b & 0x1F) + 1,
            },
            Step::Data {
                write,
                address,
                left,
            } => {
                if write && !s.rdatac && !read_only(address) {
                    s.regs[usize::from(address)] = b;
                }
                next(write, address, left)
            }
        }
    }

    /// The byte the chip shifts out on a read here (a register's value inside RREG, 0
    /// elsewhere and in RDATAC), and the step after it.
    fn read(self, s: &SimState) -> (u8, Step) {
        match self {
            Step::Data {
                write: false,
                address,
                left,
            } => {
                let out = if s.rdatac {
                    0
                } else {
                    s.regs[usize::from(address)]
                };
                (out, next(false, address, left))
            }
            other => (0, other),
        }
    }
}

impl ErrorType for SimAds1299 {
    type Error = ErrorKind;
}

impl SpiDevice for SimAds1299 {
    fn transaction(&mut self, ops: &mut [Operation<'_, u8>]) -> Result<(), ErrorKind> {
        let mut s = self.state();
        if s.fail_next {
            s.fail_next = false;
            return Err(ErrorKind::Other);
        }
        // A data read in RDATAC: one read of the frame's length, nothing written.
        if let [Operation::Read(buf)] = ops {
            if s.rdatac && buf.len() == FRAME_BYTES {
                let frame = s.frames.pop_front().unwrap_or([0; FRAME_BYTES]);
                buf.copy_from_slice(&frame);
                return Ok(());
            }
        }
        let mut step = Step::Opcode;
        // Time since the previous byte of this command, ns; None before the first byte.
        let mut since: Option<f64> = None;
        let byte_gap = |s: &mut SimState, since: &mut Option<f64>| {
            if since.is_some_and(|t| t < FOUR_TCLK_NS) {
                s.timing_violations += 1;
            }
            *since = Some(0.0);
        };
        for op in ops.iter_mut() {
            match op {
                Operation::DelayNs(ns) => {
                    if let Some(t) = since.as_mut() {
                        *t += f64::from(*ns);
                    }
                }
                Operation::Write(bytes) => {
                    for &b in bytes.iter() {
                        byte_gap(&mut s, &mut since);
                        step = step.written(&mut s, b);
                    }
                }
                Operation::Read(buf) => {
                    for out in buf.iter_mut() {
                        byte_gap(&mut s, &mut since);
                        (*out, step) = step.read(&s);
                    }
                }
                _ => return Err(ErrorKind::Other),
            }
        }
        Ok(())
    }
}

fn next(write: bool, address: u8, left: u8) -> Step {
    if left > 1 && address < 0x17 {
        Step::Data {
            write,
            address: address + 1,
            left: left - 1,
        }
    } else {
        Step::Opcode
    }
}

fn read_only(address: u8) -> bool {
    address == 0x00 || address == channel_masks::LOFF_STATP || address == channel_masks::LOFF_STATN
}

fn decode(s: &mut SimState, b: u8) -> Step {
    match b {
        command::RESET => s.reset(),
        command::SDATAC => s.rdatac = false,
        command::RDATAC => s.rdatac = true,
        command::START => s.started = true,
        _ if b & 0xE0 == command::RREG || b & 0xE0 == command::WREG => {
            if s.rdatac {
                s.ignored_commands += 1;
            }
            return Step::Count {
                write: b & 0xE0 == command::WREG,
                address: b & 0x1F,
            };
        }
        _ => {}
    }
    Step::Opcode
}
