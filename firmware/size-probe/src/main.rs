//! The amplifier node's code-size probe (see Cargo.toml): both chips' start-up and read, the
//! node core with its decimating FIR, drain into a CAN controller; nothing here runs.
#![no_std]
#![no_main]

use ads1299::Ads1299;
use ads1299::{Gain, LeadOff};
use amp_node::{AmpNode, NodeRate, NodeSettings};
use core::hint::black_box;
use embedded_hal::spi::{ErrorType, Operation, SpiDevice};
use hand_dbc_core::CanFrame;

struct Spi(u8);
impl ErrorType for Spi {
    type Error = core::convert::Infallible;
}
impl SpiDevice for Spi {
    fn transaction(&mut self, ops: &mut [Operation<'_, u8>]) -> Result<(), Self::Error> {
        for op in ops {
            match op {
                Operation::Read(b) | Operation::TransferInPlace(b) => {
                    for x in b.iter_mut() {
                        self.0 = self.0.wrapping_mul(31).wrapping_add(7);
                        *x = black_box(self.0);
                    }
                }
                Operation::Transfer(r, _) => {
                    for x in r.iter_mut() {
                        *x = black_box(self.0);
                    }
                }
                Operation::Write(w) => self.0 ^= w.first().copied().unwrap_or(0),
                Operation::DelayNs(_) => {}
            }
        }
        Ok(())
    }
}

struct Can(u32);
impl embedded_can::nb::Can for Can {
    type Frame = CanFrame;
    type Error = embedded_can::ErrorKind;
    fn transmit(&mut self, f: &CanFrame) -> nb::Result<Option<CanFrame>, Self::Error> {
        self.0 = self.0.wrapping_add(u32::from(f.data()[0]));
        Ok(None)
    }
    fn receive(&mut self) -> nb::Result<CanFrame, Self::Error> {
        Err(nb::Error::WouldBlock)
    }
}

fn run(rate: NodeRate) -> u32 {
    let Ok(settings) = NodeSettings::try_with_rate(black_box(rate), Gain::X8, LeadOff::Dc6nA)
    else {
        return 0;
    };
    let mut a = Ads1299::new(Spi(1));
    let mut b = Ads1299::new(Spi(2));
    if a.init(settings.first_chip()).is_err() || b.init(settings.second_chip()).is_err() {
        return 1;
    }
    let _ = a.start();
    let _ = b.start();
    let mut node: AmpNode = AmpNode::new(&settings);
    let mut can = Can(0);
    for _ in 0..black_box(1000) {
        black_box(node.sample(&mut a, &mut b));
        node.drain(&mut can);
    }
    can.0
}

#[no_mangle]
pub extern "C" fn _start() -> ! {
    // The rate is a run-time setting: both paths are in the image whichever runs.
    let r = if black_box(true) {
        run(NodeRate::Sps2000Decimated)
    } else {
        run(NodeRate::Sps1000)
    };
    black_box(r);
    loop {}
}

#[panic_handler]
fn panic(_: &core::panic::PanicInfo<'_>) -> ! {
    loop {}
}
