//! Bad input: arbitrary frames into every decoder and state machine give a value or a named
//! error, never a panic; what decodes re-encodes to the same bytes.

use hand_canopen::cia402::{DriverStep, PowerDriver, STATE_TABLE};
use hand_canopen::emcy::Emcy;
use hand_canopen::heartbeat::HeartbeatConsumer;
use hand_canopen::nmt::{ErrorControl, NmtMessage};
use hand_canopen::pdo::finger_pdos;
use hand_canopen::sdo::{SdoReply, SdoRequest};
use hand_canopen::sim::SimDrive;
use hand_canopen::startup::{Startup, StartupSettings};
use hand_canopen::{
    CanFrame, Controlword, Mode, NodeId, ObjectAddr, SdoClient, StartupStatus, Statusword,
};
use proptest::prelude::*;

const DRIVE: u8 = 3;

fn node(id: u8) -> NodeId {
    NodeId::try_new(id).expect("in range")
}

/// Frames: any id and payload, biased towards the ids and command bytes CANopen uses for
/// node 3 so the state machines see plausible but wrong traffic.
fn arb_frame() -> impl Strategy<Value = CanFrame> {
    let id = prop_oneof![
        0u16..0x800,
        Just(0x000),
        Just(0x080),
        Just(0x083),
        Just(0x183),
        Just(0x203),
        Just(0x283),
        Just(0x583),
        Just(0x603),
        Just(0x703),
        Just(0x764),
    ];
    let data = prop_oneof![
        prop::collection::vec(any::<u8>(), 0..=8),
        (
            prop::sample::select(vec![
                0x40u8, 0x43, 0x4B, 0x4F, 0x42, 0x41, 0x60, 0x80, 0x23, 0x2B
            ]),
            prop::sample::select(vec![
                0x1018u16, 0x6041, 0x6502, 0x1016, 0x1600, 0x6040, 0x2000
            ]),
            0u8..5,
            any::<u32>()
        )
            .prop_map(|(c, i, s, v)| {
                let i = i.to_le_bytes();
                let v = v.to_le_bytes();
                vec![c, i[0], i[1], s, v[0], v[1], v[2], v[3]]
            }),
    ];
    (id, data).prop_map(|(id, d)| CanFrame::new(id, &d).expect("id < 0x800, <= 8 bytes"))
}

fn settings() -> StartupSettings {
    StartupSettings {
        node: node(DRIVE),
        master: node(100),
        mode: Mode::CyclicSyncTorque,
        sync_period_us: 10_000,
        sync_cob_id: hand_canopen::CobId::try_new(0x07F).expect("11 bits"),
        master_heartbeat_timeout_ms: 100,
        drive_heartbeat_ms: 20,
        abort_connection: 3,
        quick_stop_option: 2,
        sdo_timeout_us: 5_000,
        step_timeout_us: 20_000,
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    #[test]
    fn decoders_give_values_or_errors(f in arb_frame()) {
        let p = f.payload();
        if let Ok(m) = NmtMessage::decode(&f) {
            prop_assert_eq!(m.command.frame(m.node), f);
        }
        if let Ok(ec) = ErrorControl::decode(&f) {
            prop_assert_eq!(ec.state.byte(), p[0] & 0x7F);
        }
        if let Ok(e) = Emcy::decode(&f) {
            prop_assert_eq!(e.frame(), f);
            prop_assert!(!e.meaning().is_empty());
        }
        if let Ok(r) = SdoRequest::decode(&f, node(DRIVE)) {
            prop_assert_eq!(r.addr(), ObjectAddr::new(u16::from_le_bytes([p[1], p[2]]), p[3]));
        }
        if let Ok(r) = SdoReply::decode(&f, node(DRIVE)) {
            prop_assert_eq!(r.addr(), ObjectAddr::new(u16::from_le_bytes([p[1], p[2]]), p[3]));
            if let SdoReply::Abort(_, code) = r {
                prop_assert_eq!(code.raw(), u32::from_le_bytes([p[4], p[5], p[6], p[7]]));
            }
        }
        for pdo in finger_pdos(node(DRIVE), Mode::CyclicSyncVelocity) {
            match pdo.decode(&f) {
                Ok(values) => {
                    let back = pdo.encode(&values);
                    prop_assert_eq!(back.map(|b| b.payload().to_vec()), Ok(p.to_vec()));
                }
                Err(e) => prop_assert!(!e.to_string().is_empty()),
            }
        }
        if p.len() >= 2 {
            let sw = Statusword(u16::from_le_bytes([p[0], p[1]]));
            if let Some(s) = sw.state() {
                let (_, mask, value) = STATE_TABLE.iter().find(|(t, _, _)| *t == s).copied().expect("row");
                prop_assert_eq!(sw.0 & mask, value);
            }
        }
    }

    #[test]
    fn sdo_client_takes_any_replies(frames in prop::collection::vec(arb_frame(), 1..20)) {
        let mut c = SdoClient::new(node(DRIVE), 1_000);
        for f in frames {
            if !c.is_busy() {
                let req = c.upload(ObjectAddr::new(0x1018, 1), 0).expect("idle");
                prop_assert_eq!(req.cob_id(), 0x603);
            }
            let ended = c.on_frame(&f);
            prop_assert_eq!(ended.is_some(), f.cob_id() == 0x583);
            prop_assert_eq!(c.is_busy(), ended.is_none());
        }
    }

    #[test]
    fn startup_takes_any_frames(frames in prop::collection::vec((0u64..3_000, arb_frame()), 1..40)) {
        let s = settings();
        let mut st = Startup::new(s.node, s.plan().expect("valid"), s.sdo_timeout_us, s.step_timeout_us);
        let mut now = 0;
        let mut sent = Vec::new();
        for (dt, f) in frames {
            now += dt;
            while let Some(out) = st.poll(now) {
                sent.push(out);
            }
            sent.extend(st.on_frame(&f, now));
        }
        // Whatever it heard, it only ever talks to its drive: NMT or the drive's SDO channel.
        for f in &sent {
            prop_assert!(f.cob_id() == 0x000 || f.cob_id() == 0x603, "{:?}", f);
        }
        if let StartupStatus::Failed(e) = st.status() {
            prop_assert!(e.to_string().contains("start-up step"));
        }
    }

    #[test]
    fn simulated_drive_takes_any_frames(frames in prop::collection::vec((0u64..20_000, arb_frame()), 1..40)) {
        let mut d = SimDrive::new(node(DRIVE));
        let mut out = Vec::new();
        d.power_on(0, &mut out);
        let mut now = 0;
        for (dt, f) in frames {
            now += dt;
            d.on_frame(&f, now, &mut out);
            d.poll(now, &mut out);
            let sw = Statusword(d.od().get(ObjectAddr::new(0x6041, 0)) as u16);
            prop_assert_eq!(sw.state(), Some(d.power_state()));
        }
        prop_assert!(out.iter().all(|f| f.payload().len() <= 8));
    }

    #[test]
    fn heartbeat_consumer_takes_any_frames(frames in prop::collection::vec((0u64..200, arb_frame()), 1..40)) {
        let mut c = HeartbeatConsumer::new();
        c.watch(node(DRIVE), 100);
        let mut now = 0;
        let mut lost = 0;
        for (dt, f) in frames {
            now += dt;
            let event = c.on_frame(&f, now);
            prop_assert!(event.is_none() || f.cob_id() == 0x703);
            c.poll(now, |n| {
                assert_eq!(n, node(DRIVE));
                lost += 1;
            });
        }
        prop_assert!(c.status(node(DRIVE)).is_some());
        prop_assert!(lost <= 40);
    }

    #[test]
    fn power_driver_takes_any_statuswords(sws in prop::collection::vec((any::<u16>(), 0u64..500), 1..40)) {
        let mut d = PowerDriver::new(1_000);
        let mut now = 0;
        let known = [0x0000u16, 0x0006, 0x0007, 0x000F, 0x0080];
        for (sw, dt) in sws {
            now += dt;
            if let Ok(DriverStep::Send(Controlword(cw))) = d.step(Statusword(sw), now) {
                prop_assert!(known.contains(&cw), "controlword 0x{:04X}", cw);
            }
        }
    }
}
