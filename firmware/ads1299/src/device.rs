//! One ADS1299 on an SPI device (its own chip select).

use embedded_hal::spi::{Operation, SpiDevice};

use crate::command;
use crate::registers::id;
use crate::settings::{BLOCK_A_LEN, BLOCK_A_START, BLOCK_B_START};
use crate::timing::{T_RESET_NS, T_SCCS_NS, T_SDECODE_NS};
use crate::{Error, Frame, Settings, FRAME_BYTES};

/// Most bytes in one register command: 2 opcode bytes + the longest block.
const MAX_COMMAND: usize = 2 + BLOCK_A_LEN;
/// Operations for such a command: every byte followed by a delay.
const MAX_OPS: usize = 2 * MAX_COMMAND;

/// One ADS1299. Build with [`Ads1299::new`], configure with [`Ads1299::init`] (reset,
/// SDATAC, id check, registers written and read back, RDATAC), then raise START (the pin
/// shared by all chips, or [`Ads1299::start`]) and read a frame at every DRDY with
/// [`Ads1299::read_frame`].
#[derive(Debug)]
pub struct Ads1299<SPI> {
    spi: SPI,
}

impl<SPI: SpiDevice> Ads1299<SPI> {
    /// The driver over `spi` (SPI mode 1: CPOL 0, CPHA 1; at most 20 MHz SCLK). Power-up
    /// (tPOR, [`crate::timing::T_POR_NS`] after the supplies settle) is the caller's.
    pub fn new(spi: SPI) -> Self {
        Self { spi }
    }

    /// The SPI device back.
    pub fn release(self) -> SPI {
        self.spi
    }

    /// A one-byte command, CS held tSCCS after it (and 18 tCLK after RESET).
    pub fn command(&mut self, opcode: u8) -> Result<(), Error<SPI::Error>> {
        let wait = if opcode == command::RESET {
            T_RESET_NS
        } else {
            T_SCCS_NS
        };
        self.spi
            .transaction(&mut [Operation::Write(&[opcode]), Operation::DelayNs(wait)])?;
        Ok(())
    }

    /// Writes `values` to consecutive registers from `start` (WREG), tSDECODE between bytes;
    /// 1 to 17 registers (the longest writable block), else [`Error::Length`].
    pub fn write_registers(&mut self, start: u8, values: &[u8]) -> Result<(), Error<SPI::Error>> {
        let n = values.len();
        if n == 0 || n > BLOCK_A_LEN {
            return Err(Error::Length { len: n });
        }
        let mut bytes = [0u8; MAX_COMMAND];
        bytes[0] = command::WREG | (start & 0x1F);
        bytes[1] = (n - 1) as u8;
        bytes[2..2 + n].copy_from_slice(values);
        let mut ops: [Operation<'_, u8>; MAX_OPS] = core::array::from_fn(|_| Operation::DelayNs(0));
        let mut k = 0;
        for (i, b) in bytes[..2 + n].chunks(1).enumerate() {
            ops[k] = Operation::Write(b);
            ops[k + 1] = Operation::DelayNs(if i + 1 < 2 + n {
                T_SDECODE_NS
            } else {
                T_SCCS_NS
            });
            k += 2;
        }
        self.spi.transaction(&mut ops[..k])?;
        Ok(())
    }

    /// Reads consecutive registers from `start` into `out` (RREG), tSDECODE between bytes; 1 to
    /// 17 registers, else [`Error::Length`].
    pub fn read_registers(&mut self, start: u8, out: &mut [u8]) -> Result<(), Error<SPI::Error>> {
        let n = out.len();
        if n == 0 || n > BLOCK_A_LEN {
            return Err(Error::Length { len: n });
        }
        let opcode = [command::RREG | (start & 0x1F), (n - 1) as u8];
        let mut ops: [Operation<'_, u8>; MAX_OPS] = core::array::from_fn(|_| Operation::DelayNs(0));
        ops[0] = Operation::Write(&opcode[..1]);
        ops[1] = Operation::DelayNs(T_SDECODE_NS);
        ops[2] = Operation::Write(&opcode[1..]);
        ops[3] = Operation::DelayNs(T_SDECODE_NS);
        let mut k = 4;
        for (i, b) in out.chunks_mut(1).enumerate() {
            ops[k] = Operation::Read(b);
            ops[k + 1] = Operation::DelayNs(if i + 1 < n { T_SDECODE_NS } else { T_SCCS_NS });
            k += 2;
        }
        self.spi.transaction(&mut ops[..k])?;
        Ok(())
    }

    /// The ID register.
    pub fn read_id(&mut self) -> Result<u8, Error<SPI::Error>> {
        let mut v = [0];
        self.read_registers(id::ADDRESS, &mut v)?;
        Ok(v[0])
    }

    /// The start-up: RESET, SDATAC (the chip wakes in RDATAC, which ignores register
    /// commands), the id check, the two register blocks written and read back, RDATAC.
    /// Conversions start with START (pin or [`Ads1299::start`]).
    pub fn init(&mut self, settings: &Settings) -> Result<(), Error<SPI::Error>> {
        self.command(command::RESET)?;
        self.command(command::SDATAC)?;
        let found = self.read_id()?;
        if found & !id::REV_ID_MASK != id::EXPECTED_8CH {
            return Err(Error::WrongId { found });
        }
        self.write_and_verify(BLOCK_A_START, &settings.block_a())?;
        self.write_and_verify(BLOCK_B_START, &settings.block_b())?;
        self.command(command::RDATAC)
    }

    fn write_and_verify(&mut self, start: u8, values: &[u8]) -> Result<(), Error<SPI::Error>> {
        self.write_registers(start, values)?;
        let mut back = [0u8; BLOCK_A_LEN];
        let back = &mut back[..values.len()];
        self.read_registers(start, back)?;
        for (i, (&wrote, &read)) in values.iter().zip(back.iter()).enumerate() {
            if wrote != read {
                return Err(Error::Verify {
                    address: start + i as u8,
                    wrote,
                    read,
                });
            }
        }
        Ok(())
    }

    /// The START command (for a single chip; two chips share the START pin instead, so that
    /// they convert in step).
    pub fn start(&mut self) -> Result<(), Error<SPI::Error>> {
        self.command(command::START)
    }

    /// Reads one data frame in RDATAC mode (after DRDY went low): 27 bytes in one
    /// transaction, no opcode. A status word without the 1100 header is
    /// [`Error::BadHeader`].
    #[inline]
    pub fn read_frame(&mut self) -> Result<Frame, Error<SPI::Error>> {
        let mut bytes = [0u8; FRAME_BYTES];
        self.spi.read(&mut bytes)?;
        let frame = Frame::parse(&bytes);
        if !frame.status.header_ok() {
            return Err(Error::BadHeader { first: bytes[0] });
        }
        Ok(frame)
    }
}
