//! The in-memory bus: broadcast to others in order, timestamps, bounded queues, bus-off, and
//! the blocking API across threads.

use std::time::Duration;

use embedded_can::{blocking, nb as can_nb, StandardId};
use hand_model::bus::{MemBus, MemBusError};
use hand_model::clock::VirtualClock;
use hand_model::dbc::CanFrame;

fn frame(id: u16, b: u8) -> CanFrame {
    CanFrame::new(StandardId::new(id).expect("11-bit"), &[b]).expect("valid")
}

#[test]
fn every_other_endpoint_sees_each_frame_in_order_with_its_time() {
    let clock = VirtualClock::new();
    let bus = MemBus::with_clock(clock.clone());
    let mut a = bus.endpoint();
    let mut b = bus.endpoint();
    let mut c = bus.endpoint();
    clock.set_us(10);
    can_nb::Can::transmit(&mut a, &frame(0x10, 1)).expect("sent");
    clock.set_us(20);
    can_nb::Can::transmit(&mut b, &frame(0x20, 2)).expect("sent");
    assert_eq!(
        can_nb::Can::receive(&mut a).expect("from b"),
        frame(0x20, 2)
    );
    assert!(
        matches!(can_nb::Can::receive(&mut a), Err(nb::Error::WouldBlock)),
        "not its own"
    );
    let r1 = c.receive_timestamped().expect("first");
    let r2 = c.receive_timestamped().expect("second");
    assert_eq!((r1.frame, r1.time_us), (frame(0x10, 1), Some(10)));
    assert_eq!((r2.frame, r2.time_us), (frame(0x20, 2), Some(20)));
    assert_eq!(bus.frames_sent(), 2);
}

#[test]
fn full_queues_drop_the_newest_and_count_it() {
    let bus = MemBus::new().with_capacity(3);
    let mut tx = bus.endpoint();
    let mut rx = bus.endpoint();
    for i in 0..5 {
        tx.send(&frame(0x100, i)).expect("sent");
    }
    assert_eq!(rx.pending(), 3);
    assert_eq!(rx.overflows(), 2);
    let got: Vec<u8> = std::iter::from_fn(|| rx.receive_timestamped())
        .map(|r| r.frame.data()[0])
        .collect();
    assert_eq!(got, vec![0, 1, 2]);
}

#[test]
fn bus_off_refuses_transmits() {
    let bus = MemBus::new();
    let mut a = bus.endpoint();
    let _b = bus.endpoint();
    bus.set_bus_off(true);
    assert!(matches!(
        can_nb::Can::transmit(&mut a, &frame(1, 0)),
        Err(nb::Error::Other(MemBusError::BusOff))
    ));
    bus.set_bus_off(false);
    assert!(can_nb::Can::transmit(&mut a, &frame(1, 0)).is_ok());
}

#[test]
fn blocking_receive_waits_for_another_thread_and_refuses_to_wait_alone() {
    let bus = MemBus::new();
    let mut rx = bus.endpoint();
    let mut tx = bus.endpoint();
    let h = std::thread::spawn(move || {
        std::thread::sleep(Duration::from_millis(20));
        blocking::Can::transmit(&mut tx, &frame(0x42, 7)).expect("sent");
    });
    assert_eq!(
        blocking::Can::receive(&mut rx).expect("frame"),
        frame(0x42, 7)
    );
    h.join().expect("thread");
    // The sender is gone: a blocking receive would wait forever, so it fails.
    assert_eq!(blocking::Can::receive(&mut rx), Err(MemBusError::NoPeers));
    assert_eq!(bus.endpoints(), 1);
}
