//! Handing frames to the CAN controller: a refused frame is dropped and counted, a displaced
//! one is requeued first, a full controller stops the drain.

use std::collections::VecDeque;

use ads1299::{Code, Frame, Gain, LeadOff, Status};
use amp_node::{AmpNode, NodeSettings, SampleOutcome};
use embedded_can::StandardId;
use hand_dbc::messages::EmgStatus;
use hand_dbc::CanFrame;

/// What the controller answers to each transmit, in order; accepted frames are recorded.
enum Answer {
    Accept,
    Fail,
    Displace(CanFrame),
    Full,
}

struct Controller {
    answers: VecDeque<Answer>,
    sent: Vec<u32>,
    frames: Vec<CanFrame>,
}

impl embedded_can::nb::Can for Controller {
    type Frame = CanFrame;
    type Error = embedded_can::ErrorKind;

    fn transmit(&mut self, frame: &CanFrame) -> nb::Result<Option<CanFrame>, Self::Error> {
        match self.answers.pop_front().unwrap_or(Answer::Full) {
            Answer::Accept => {
                self.sent.push(frame.raw_id());
                self.frames.push(*frame);
                Ok(None)
            }
            Answer::Fail => Err(nb::Error::Other(embedded_can::ErrorKind::Bit)),
            Answer::Displace(back) => {
                self.sent.push(frame.raw_id());
                Ok(Some(back))
            }
            Answer::Full => Err(nb::Error::WouldBlock),
        }
    }

    fn receive(&mut self) -> nb::Result<CanFrame, Self::Error> {
        Err(nb::Error::WouldBlock)
    }
}

fn quiet() -> Frame {
    Frame {
        status: Status::new(0, 0, 0),
        codes: [Code::new(0).expect("24 bit"); 8],
    }
}

#[test]
fn refused_displaced_and_full() {
    let settings = NodeSettings::try_new(Gain::X8, LeadOff::Dc6nA).expect("settings");
    let mut node: AmpNode = AmpNode::new(&settings);
    assert!(node.on_frames(&quiet(), &quiet()) == SampleOutcome::Queued);
    assert!(node.queued_frames() == 3);
    let other = CanFrame::new(StandardId::new(0x301).expect("id"), &[0; 8]).expect("frame");
    let mut can = Controller {
        answers: VecDeque::from([Answer::Fail, Answer::Displace(other), Answer::Full]),
        sent: Vec::new(),
        frames: Vec::new(),
    };
    node.drain(&mut can);
    // G0 refused (dropped), G1 sent displacing 0x301, which waits first, then G2.
    assert!(can.sent == [0x101] && node.queued_frames() == 2);
    let c = node.counters();
    assert!(c.tx_errors == 1 && c.displaced == 1, "{c:?}");
    can.answers = VecDeque::from([Answer::Accept, Answer::Accept]);
    node.drain(&mut can);
    assert!(can.sent == [0x101, 0x301, 0x102] && node.queued_frames() == 0);
}

#[test]
fn gains_the_bus_cannot_name_are_refused() {
    for g in [Gain::X6, Gain::X12, Gain::X24] {
        let r = NodeSettings::try_new(g, LeadOff::Dc6nA);
        assert!(
            r == Err(amp_node::NodeSettingsError::GainNotOnBus { gain: g.factor() }),
            "{g:?}"
        );
    }
}

/// Conversions never read (the firmware held up past DRDY): no frames, the counter jumps
/// over them, and the status due among them says samples were dropped in the amplifier.
#[test]
fn missed_conversions_jump_the_counter_and_are_reported() {
    let settings = NodeSettings::try_new(Gain::X8, LeadOff::Dc6nA).expect("settings");
    let mut node: AmpNode = AmpNode::new(&settings);
    let mut can = Controller {
        answers: VecDeque::new(),
        sent: Vec::new(),
        frames: Vec::new(),
    };
    let accept = |node: &mut AmpNode, can: &mut Controller| {
        can.answers = (0..8).map(|_| Answer::Accept).collect();
        node.drain(can);
    };
    assert!(node.on_frames(&quiet(), &quiet()) == SampleOutcome::Queued);
    accept(&mut node, &mut can);
    for _ in 0..150 {
        node.on_missed();
    }
    // One status became due among the missed periods, and nothing else was queued.
    assert!(node.queued_frames() == 1, "{}", node.queued_frames());
    accept(&mut node, &mut can);
    assert!(can.sent == [0x100, 0x101, 0x102, 0x180], "{:x?}", can.sent);
    let status = EmgStatus::decode(can.frames[3].data()).expect("EMG_STATUS");
    assert!(status.faults() == 1 << 4, "{:#x}", status.faults());
    let c = node.counters();
    assert!(
        c.missed == 150 && c.periods == 151 && c.queued == 1,
        "{c:?}"
    );
    assert!(node.next_counter() == 151);
    assert!(node.on_frames(&quiet(), &quiet()) == SampleOutcome::Queued);
    assert!(node.queued_frames() == 3);
}
