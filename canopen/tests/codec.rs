//! Codecs and state machines against CiA 301 / CiA 402 as written in the standards.

use hand_canopen::cia402::{
    transition_for, Cia402Error, Command, DriverStep, PowerDriver, STATE_TABLE, TRANSITIONS,
};
use hand_canopen::emcy::{meaning, Emcy, ErrorClass};
use hand_canopen::heartbeat::{
    HeartbeatConsumer, HeartbeatEvent, HeartbeatProducer, HeartbeatStatus,
};
use hand_canopen::ids::Function;
use hand_canopen::nmt::{ErrorControl, NmtMessage, NMT_COMMANDS};
use hand_canopen::pdo::{finger_pdos, Direction, PdoError, PDO_INVALID};
use hand_canopen::scaling::{ScalingError, ScalingSettings};
use hand_canopen::sdo::{SdoDone, SdoFrameError, SdoReply, SdoRequest, ABORT_CODES};
use hand_canopen::startup::{interpolation_period, SettingsError, StartupSettings};
use hand_canopen::{
    AbortCode, CanFrame, CobId, Controlword, Mode, NmtCommand, NmtState, NodeId, ObjectAddr,
    PowerState, SdoClient, SdoData, SdoError, Statusword, SyncProducer,
};

fn node(id: u8) -> NodeId {
    NodeId::try_new(id).expect("in range")
}

fn frame(id: u16, d: &[u8]) -> CanFrame {
    CanFrame::new(id, d).expect("valid frame")
}

#[test]
fn node_ids_are_1_to_127() {
    assert!(NodeId::try_new(0).is_err());
    assert!(NodeId::try_new(128).is_err());
    assert_eq!(NodeId::try_new(1).map(NodeId::get), Ok(1));
    assert_eq!(NodeId::try_new(127).map(NodeId::get), Ok(127));
}

#[test]
fn cob_ids_split_back_into_function_and_node() {
    let functions = [
        Function::Emcy,
        Function::Tpdo(1),
        Function::Tpdo(4),
        Function::Rpdo(1),
        Function::Rpdo(4),
        Function::SdoTx,
        Function::SdoRx,
        Function::Heartbeat,
    ];
    for id in 1..=127 {
        let n = node(id);
        for f in functions {
            let cob = CobId::of(f, n).expect("a COB-ID");
            assert_eq!(cob.split(), Some((f, Some(n))), "{f:?} {n}");
        }
        let all = CobId::all_of(n);
        assert!(all.contains(&CobId::of(Function::Heartbeat, n).expect("hb")));
        let mut sorted = all.to_vec();
        sorted.sort();
        sorted.dedup();
        assert_eq!(sorted.len(), all.len());
    }
    // The predefined connection set's bases (CiA 301 table 72).
    let n = node(5);
    assert_eq!(CobId::of(Function::Tpdo(1), n).map(CobId::raw), Some(0x185));
    assert_eq!(CobId::of(Function::Rpdo(2), n).map(CobId::raw), Some(0x305));
    assert_eq!(CobId::of(Function::Tpdo(5), n), None);
}

#[test]
fn nmt_commands_and_error_control() {
    let specifiers = [0x01, 0x02, 0x80, 0x81, 0x82];
    for (c, cs) in NMT_COMMANDS.into_iter().zip(specifiers) {
        let f = c.frame(Some(node(9)));
        assert_eq!((f.cob_id(), f.payload()), (0x000, &[cs, 9][..]));
        let m = NmtMessage::decode(&f).expect("decodes");
        assert_eq!((m.command, m.node), (c, Some(node(9))));
        assert!(m.addresses(node(9)) && !m.addresses(node(8)));
        let all = NmtMessage::decode(&c.frame(None)).expect("broadcast");
        assert!(all.addresses(node(8)));
    }
    assert!(NmtMessage::decode(&frame(0, &[0x03, 1])).is_err());
    assert!(NmtMessage::decode(&frame(0, &[0x01, 200])).is_err());
    let boot = ErrorControl::decode(&frame(0x703, &[0x00])).expect("boot-up");
    assert!(boot.is_boot_up() && boot.node == node(3));
    for (b, s) in [
        (0x04, NmtState::Stopped),
        (0x05, NmtState::Operational),
        (0x7F, NmtState::PreOperational),
    ] {
        let hb = ErrorControl::decode(&frame(0x77F, &[b])).expect("heartbeat");
        assert_eq!(hb.state, s);
        assert_eq!(hb.frame(), frame(0x77F, &[b]));
    }
    assert!(ErrorControl::decode(&frame(0x703, &[0x06])).is_err());
    assert!(ErrorControl::decode(&frame(0x703, &[])).is_err());
}

#[test]
fn sdo_command_bytes_follow_cia_301() {
    let n = node(2);
    let a = ObjectAddr::new(0x6071, 0);
    // Expedited download: 0x23 / 0x27 / 0x2B / 0x2F for 4 / 3 / 2 / 1 bytes.
    for (len, cmd) in [(4, 0x23), (3, 0x27), (2, 0x2B), (1, 0x2F)] {
        let d = SdoData::new(&[0x11, 0x22, 0x33, 0x44][..len]).expect("1..=4");
        let f = SdoRequest::Download(a, d).frame(n);
        assert_eq!(f.cob_id(), 0x602);
        assert_eq!(f.payload()[..4], [cmd, 0x71, 0x60, 0x00]);
        assert_eq!(SdoRequest::decode(&f, n), Ok(SdoRequest::Download(a, d)));
        let up = SdoReply::Uploaded(a, d).frame(n);
        assert_eq!((up.cob_id(), up.payload()[0]), (0x582, cmd + 0x20));
        assert_eq!(SdoReply::decode(&up, n), Ok(SdoReply::Uploaded(a, d)));
    }
    assert_eq!(SdoRequest::Upload(a).frame(n).payload()[0], 0x40);
    assert_eq!(SdoReply::Downloaded(a).frame(n).payload()[0], 0x60);
    // Size not indicated: 4 bytes.
    let f = frame(0x582, &[0x42, 0x71, 0x60, 0, 1, 2, 3, 4]);
    let Ok(SdoReply::Uploaded(_, d)) = SdoReply::decode(&f, n) else {
        panic!("0x42 is an expedited upload")
    };
    assert_eq!(d.bytes(), &[1, 2, 3, 4]);
    // Segmented, unknown, short, other node.
    let seg = frame(0x582, &[0x41, 0x71, 0x60, 0, 8, 0, 0, 0]);
    assert_eq!(
        SdoReply::decode(&seg, n),
        Err(SdoFrameError::NotExpedited(0x41))
    );
    let unknown = frame(0x582, &[0xE0, 0, 0, 0, 0, 0, 0, 0]);
    assert_eq!(
        SdoReply::decode(&unknown, n),
        Err(SdoFrameError::UnknownCommand(0xE0))
    );
    assert_eq!(
        SdoReply::decode(&frame(0x582, &[0x60, 0x71]), n),
        Err(SdoFrameError::Length(2))
    );
    assert_eq!(
        SdoReply::decode(&SdoReply::Downloaded(a).frame(node(3)), n),
        Err(SdoFrameError::WrongNode {
            expected: 2,
            got: 3
        })
    );
    // Signed values sign-extend from their length.
    assert_eq!(SdoData::i8(-3).as_i32(), -3);
    assert_eq!(SdoData::i16(-300).as_i32(), -300);
    assert_eq!(SdoData::u16(0xFFFF).as_u32(), 0xFFFF);
}

#[test]
fn abort_codes_are_a_complete_table() {
    let mut codes: Vec<u32> = ABORT_CODES.iter().map(|(_, c, _)| *c).collect();
    let n = codes.len();
    codes.sort();
    codes.dedup();
    assert_eq!(codes.len(), n, "duplicate abort codes");
    for (a, c, m) in ABORT_CODES {
        assert_eq!(AbortCode::from_raw(*c), *a);
        assert_eq!(a.raw(), *c);
        assert_eq!(a.meaning(), *m);
    }
    assert_eq!(AbortCode::from_raw(0x0503_0000), AbortCode::ToggleBit);
    assert_eq!(AbortCode::from_raw(0x0800_0000), AbortCode::General);
    let other = AbortCode::from_raw(0x1234_5678);
    assert_eq!(other, AbortCode::Other(0x1234_5678));
    assert!(other.to_string().contains("0x12345678"));
}

#[test]
fn sdo_client_names_every_failure() {
    let n = node(4);
    let a = ObjectAddr::new(0x1018, 1);
    let mut c = SdoClient::new(n, 1_000);
    let req = c.upload(a, 0).expect("idle");
    assert_eq!(req.cob_id(), 0x604);
    assert!(matches!(c.upload(a, 0), Err(SdoError::Busy { .. })));
    // Another node's reply is not this client's business.
    assert_eq!(c.on_frame(&SdoReply::Downloaded(a).frame(node(5))), None);
    // Wrong object echoed.
    let wrong = SdoReply::Uploaded(ObjectAddr::new(0x1018, 2), SdoData::u32(1)).frame(n);
    assert!(matches!(
        c.on_frame(&wrong),
        Some(Err(SdoError::WrongObject { .. }))
    ));
    // Download confirmation to an upload.
    c.upload(a, 0).expect("idle again");
    let mismatch = SdoReply::Downloaded(a).frame(n);
    assert!(matches!(
        c.on_frame(&mismatch),
        Some(Err(SdoError::Mismatch { .. }))
    ));
    // Short reply.
    c.upload(a, 0).expect("idle again");
    assert!(matches!(
        c.on_frame(&frame(0x584, &[0x43])),
        Some(Err(SdoError::Malformed {
            error: SdoFrameError::Length(1),
            ..
        }))
    ));
    // Success.
    c.upload(a, 0).expect("idle again");
    let ok = SdoReply::Uploaded(a, SdoData::u32(0xA1D)).frame(n);
    assert_eq!(
        c.on_frame(&ok),
        Some(Ok(SdoDone::Uploaded(SdoData::u32(0xA1D))))
    );
    // Timeout: the error and an abort 0x0504_0000 to the server.
    c.upload(a, 10).expect("idle again");
    assert!(c.poll(1_009).is_none());
    let (e, abort) = c.poll(1_010).expect("timed out");
    assert!(matches!(
        e,
        SdoError::Timeout {
            timeout_us: 1_000,
            ..
        }
    ));
    assert_eq!(
        SdoRequest::decode(&abort, n),
        Ok(SdoRequest::Abort(a, AbortCode::Timeout))
    );
    assert!(!c.is_busy());
}

#[test]
fn a_late_reply_to_a_transfer_given_up_is_ignored_once_where_it_does_not_fit() {
    // Session 27's fresh-clone run: a drive booted again while handd read 0x1018:01; handd
    // cancelled and read 0x1018:01 again; the drive answered both requests, and the second
    // answer arrived while handd read 0x1018:02 ("SDO reply for 0x1018:01, expected 0x1018:02").
    let n = node(6);
    let (vendor, product) = (ObjectAddr::new(0x1018, 1), ObjectAddr::new(0x1018, 2));
    let reply = |addr, v| SdoReply::Uploaded(addr, SdoData::u32(v)).frame(n);
    let mut c = SdoClient::new(n, 300_000);
    c.upload(vendor, 0).expect("idle");
    c.cancel();
    assert!(!c.is_busy());
    c.upload(vendor, 10).expect("idle after the cancel");
    // The first request's answer fits the second (the same object): taken.
    assert_eq!(
        c.on_frame(&reply(vendor, 7)),
        Some(Ok(SdoDone::Uploaded(SdoData::u32(7))))
    );
    c.upload(product, 20).expect("idle");
    // The second request's answer, late: ignored, the transfer in flight goes on ...
    assert_eq!(c.on_frame(&reply(vendor, 7)), None);
    assert!(c.is_busy());
    assert_eq!(
        c.on_frame(&reply(product, 42)),
        Some(Ok(SdoDone::Uploaded(SdoData::u32(42))))
    );
    // ... but only once: a wrong object after that is an error again.
    c.upload(product, 30).expect("idle");
    assert!(matches!(
        c.on_frame(&reply(vendor, 7)),
        Some(Err(SdoError::WrongObject { .. }))
    ));
    // After a timeout too, and never an object other than the one given up.
    c.upload(vendor, 40).expect("idle");
    assert!(c.poll(400_000).is_some());
    c.upload(product, 400_010).expect("idle");
    let other = ObjectAddr::new(0x6060, 0);
    assert!(matches!(
        c.on_frame(&reply(other, 1)),
        Some(Err(SdoError::WrongObject { .. }))
    ));
    c.upload(product, 400_020).expect("idle");
    assert_eq!(c.on_frame(&reply(vendor, 7)), None);
    assert!(c.is_busy());
}

#[test]
fn emcy_decodes_and_names_its_class() {
    let f = frame(0x08A, &[0x30, 0x81, 0x11, 1, 2, 3, 4, 5]);
    let e = Emcy::decode(&f).expect("EMCY");
    assert_eq!(
        (e.node, e.code, e.register, e.vendor),
        (node(10), 0x8130, 0x11, [1, 2, 3, 4, 5])
    );
    assert_eq!(e.frame(), f);
    assert_eq!(e.class(), ErrorClass::Monitoring);
    assert!(e.meaning().contains("heartbeat"));
    assert!(Emcy::decode(&frame(0x08A, &[0x30, 0x81])).is_err());
    assert!(Emcy::decode(&frame(0x080, &[0; 8])).is_err());
    // Unknown codes fall back to their group, then their class.
    assert_eq!(meaning(0x2399), meaning(0x2300));
    assert_eq!(meaning(0x4999), meaning(0x4000));
    assert_eq!(ErrorClass::of(0x0000), ErrorClass::NoError);
    assert_eq!(ErrorClass::of(0xFF01), ErrorClass::DeviceSpecific);
    assert_eq!(ErrorClass::of(0xF001), ErrorClass::AdditionalFunctions);
    assert_eq!(ErrorClass::of(0xA000), ErrorClass::Reserved);
}

#[test]
fn statusword_table_and_transitions() {
    for (s, _, _) in STATE_TABLE {
        assert_eq!(Statusword::of(s).state(), Some(s));
        // Bits 7..15 (warning, remote, target reached, ...) do not change the state.
        assert_eq!(Statusword(Statusword::of(s).0 | 0xFF80).state(), Some(s));
    }
    for t in TRANSITIONS {
        let cw = t.command.controlword();
        assert!(t.command.matches(cw) || t.command == Command::FaultReset);
        let prev = Controlword::FAULT_RESET_LOW;
        assert_eq!(
            transition_for(t.from, prev, cw).map(|x| x.to),
            Some(t.to),
            "{t:?}"
        );
    }
    // Fault reset needs the edge: bit 7 held high does nothing.
    let reset = Command::FaultReset.controlword();
    assert!(transition_for(PowerState::Fault, reset, reset).is_none());
    // Controlword values of CiA 402 table 28.
    assert_eq!(Command::Shutdown.controlword(), Controlword(0x06));
    assert_eq!(Command::SwitchOn.controlword(), Controlword(0x07));
    assert_eq!(Command::EnableOperation.controlword(), Controlword(0x0F));
    assert_eq!(Command::QuickStop.controlword(), Controlword(0x02));
}

/// A drive that follows the transition table, walked by the driver from every state.
#[test]
fn driver_walks_to_operation_enabled_from_every_state() {
    for (start, _, _) in STATE_TABLE {
        let mut state = match start {
            PowerState::NotReadyToSwitchOn | PowerState::FaultReactionActive => continue,
            s => s,
        };
        let mut prev = Controlword(0);
        let mut d = PowerDriver::new(1_000);
        let mut sent = Vec::new();
        for now in 0..10u64 {
            match d.step(Statusword::of(state), now).expect("no timeout") {
                DriverStep::Reached => break,
                DriverStep::Wait => {}
                DriverStep::Send(cw) => {
                    sent.push(cw);
                    if let Some(t) = transition_for(state, prev, cw) {
                        state = t.to;
                    }
                    prev = cw;
                }
            }
        }
        assert_eq!(state, PowerState::OperationEnabled, "from {start}");
        if start == PowerState::Fault {
            assert_eq!(&sent[..2], &[Controlword(0x0000), Controlword(0x0080)]);
        }
    }
}

#[test]
fn driver_times_out_per_step() {
    let mut d = PowerDriver::new(1_000);
    let sw = Statusword::of(PowerState::SwitchOnDisabled);
    assert_eq!(d.step(sw, 0), Ok(DriverStep::Send(Controlword(0x06))));
    assert_eq!(d.step(sw, 999), Ok(DriverStep::Wait));
    assert_eq!(
        d.step(sw, 1_000),
        Err(Cia402Error::StepTimeout {
            state: PowerState::SwitchOnDisabled,
            sent: Some(Command::Shutdown),
            timeout_us: 1_000
        })
    );
    assert_eq!(
        d.step(Statusword(0x0001), 0),
        Err(Cia402Error::UnknownStatusword(1))
    );
}

#[test]
fn pdo_plan_disables_maps_and_enables_in_order() {
    let pdos = finger_pdos(node(7), Mode::CyclicSyncTorque);
    assert_eq!(pdos.len(), 8);
    for p in &pdos {
        let plan = p.plan();
        let comm = ObjectAddr::new(p.comm_index(), 1);
        assert_eq!(plan[0].addr, comm);
        assert_ne!(
            plan[0].data.as_u32() & PDO_INVALID,
            0,
            "first write disables"
        );
        if !p.enabled() {
            assert_eq!(plan.len(), 1);
            continue;
        }
        let count = ObjectAddr::new(p.map_index(), 0);
        let counts: Vec<usize> = plan
            .iter()
            .enumerate()
            .filter(|(_, w)| w.addr == count)
            .map(|(i, _)| i)
            .collect();
        assert_eq!(plan[counts[0]].data.as_u32(), 0);
        assert_eq!(plan[counts[1]].data.as_u32() as usize, p.entries.len());
        assert!(counts[1] == counts[0] + p.entries.len() + 1);
        let last = plan.last().expect("non-empty");
        assert_eq!((last.addr, last.data.as_u32() & PDO_INVALID), (comm, 0));
        let values: Vec<u32> = (0..p.entries.len() as u32)
            .map(|k| 0x0101_0101 * (k + 1))
            .collect();
        let f = p.encode(&values).expect("encodes");
        assert_eq!(f.cob_id(), p.cob_id.raw());
        let masked: Vec<u32> = p
            .entries
            .iter()
            .zip(&values)
            .map(|(e, v)| {
                if e.bits == 32 {
                    *v
                } else {
                    v & ((1 << e.bits) - 1)
                }
            })
            .collect();
        assert_eq!(p.decode(&f).expect("decodes"), masked);
        let short = CanFrame::new(p.cob_id.raw(), &f.payload()[1..]).expect("frame");
        assert!(matches!(
            p.decode(&short),
            Err(PdoError::PayloadLength { .. })
        ));
    }
    let rx: Vec<_> = pdos
        .iter()
        .filter(|p| p.direction == Direction::Rx)
        .collect();
    assert_eq!(
        rx.iter().filter(|p| p.enabled()).count(),
        1,
        "unused RPDOs disabled"
    );
}

#[test]
fn scaling_follows_the_arm_and_gear() {
    // 10 N at a 50 mm arm = 0.5 Nm at the joint; / 50 gear = 10 mNm at the motor;
    // rated 100 mNm -> 100 per mille.
    let s = ScalingSettings {
        rated_torque_mnm: 100.0,
        gear_ratio: 50.0,
        moment_arm_m: 0.05,
        max_torque_permille: 1_000,
        max_speed_rpm: 10_000,
    }
    .validate()
    .expect("valid");
    assert_eq!(s.torque_permille(10.0), 100);
    assert!((s.force_n(100) - 10.0).abs() < 1e-9);
    // 2 pi rad/s at the joint = 60 rpm, * 50 = 3000 rpm at the motor.
    assert_eq!(s.velocity_rpm(core::f64::consts::TAU), 3_000);
    assert!((s.rad_s(3_000) - core::f64::consts::TAU).abs() < 1e-9);
    assert_eq!(s.torque_permille(1e9), 1_000);
    assert_eq!(s.velocity_rpm(-1e9), -10_000);
    assert_eq!(s.torque_permille(f64::NAN), 0);
    // The torque limit (0x6072) is the force's magnitude, saturated, NaN none.
    assert_eq!(s.max_torque_permille(10.0), 100);
    assert_eq!(s.max_torque_permille(-10.0), 100);
    assert_eq!(s.max_torque_permille(0.0), 0);
    assert_eq!(s.max_torque_permille(1e9), 1_000);
    assert_eq!(s.max_torque_permille(-1e9), 1_000);
    assert_eq!(s.max_torque_permille(f64::INFINITY), 1_000);
    assert_eq!(s.max_torque_permille(f64::NAN), 0);
    assert!((s.limit_force_n(100) - 10.0).abs() < 1e-9);
    assert!((s.limit_force_n(u16::MAX) - 6553.5).abs() < 1e-9);
    let bad = ScalingSettings {
        gear_ratio: 0.0,
        rated_torque_mnm: 1.0,
        moment_arm_m: 0.05,
        max_torque_permille: 1_000,
        max_speed_rpm: 1,
    };
    assert!(matches!(
        bad.validate(),
        Err(ScalingError::NotPositive {
            field: "gear_ratio",
            ..
        })
    ));
    let bad = ScalingSettings {
        gear_ratio: 1.0,
        max_torque_permille: 40_000,
        ..bad
    };
    assert_eq!(
        bad.validate(),
        Err(ScalingError::Limit("max_torque_permille"))
    );
}

#[test]
fn sync_and_heartbeat_follow_the_callers_clock() {
    let mut s = SyncProducer::try_new(10_000).expect("period");
    assert!(SyncProducer::try_new(0).is_err());
    assert_eq!(s.poll(5).map(|f| f.cob_id()), Some(0x080));
    assert!(s.poll(10_004).is_none());
    assert!(s.poll(10_005).is_some());
    // A late loop sends one SYNC, not a burst.
    assert!(s.poll(100_000).is_some());
    assert!(s.poll(100_001).is_none());
    let on = CobId::try_new(0x07F).expect("11 bits");
    let mut s = SyncProducer::try_new(10_000).expect("period").on_cob_id(on);
    assert_eq!(
        s.poll(5).map(|f| (f.cob_id(), f.payload().len())),
        Some((0x07F, 0))
    );

    let mut p = HeartbeatProducer::new(node(100), 50_000);
    assert_eq!(
        p.poll(0, NmtState::Operational),
        Some(frame(0x764, &[0x05]))
    );
    assert!(p.poll(49_999, NmtState::Operational).is_none());
    assert_eq!(
        p.poll(50_000, NmtState::PreOperational),
        Some(frame(0x764, &[0x7F]))
    );

    let mut c = HeartbeatConsumer::new();
    c.watch(node(3), 100);
    assert_eq!(c.status(node(3)), Some(HeartbeatStatus::Unseen));
    assert_eq!(c.status(node(4)), None);
    assert_eq!(
        c.on_frame(&frame(0x703, &[0]), 0),
        Some(HeartbeatEvent::BootUp(node(3)))
    );
    assert_eq!(
        c.on_frame(&frame(0x703, &[0x7F]), 10),
        Some(HeartbeatEvent::StateChanged(
            node(3),
            NmtState::PreOperational
        ))
    );
    assert_eq!(c.on_frame(&frame(0x703, &[0x7F]), 20), None);
    let mut lost = Vec::new();
    c.poll(120, |n| lost.push(n));
    assert!(lost.is_empty());
    c.poll(121, |n| lost.push(n));
    c.poll(500, |n| lost.push(n));
    assert_eq!(lost, vec![node(3)], "reported once");
    assert_eq!(c.status(node(3)), Some(HeartbeatStatus::Lost));
}

#[test]
fn startup_settings_are_checked_once() {
    assert_eq!(interpolation_period(50_000), Some((50, -3)));
    assert_eq!(interpolation_period(10_000), Some((10, -3)));
    assert_eq!(interpolation_period(500), Some((5, -4)));
    assert_eq!(interpolation_period(0), None);
    assert_eq!(interpolation_period(1_000_000), None);
    let s = StartupSettings {
        node: node(3),
        master: node(100),
        mode: Mode::CyclicSyncTorque,
        sync_period_us: 50_000,
        sync_cob_id: CobId::try_new(0x07F).expect("11 bits"),
        master_heartbeat_timeout_ms: 150,
        drive_heartbeat_ms: 50,
        abort_connection: 3,
        quick_stop_option: 2,
        sdo_timeout_us: 20_000,
        step_timeout_us: 100_000,
    };
    let steps = s.plan().expect("valid");
    assert_eq!(
        steps.first(),
        Some(&hand_canopen::startup::Step::ResetCommunication)
    );
    assert_eq!(steps.last(), Some(&hand_canopen::startup::Step::Enable));
    let same = StartupSettings {
        master: node(3),
        ..s
    };
    assert_eq!(same.plan(), Err(SettingsError::SameNode(3)));
    // 0x1005 is the first object written; NMT's id or one of the drive's own is refused.
    assert!(steps.iter().any(|st| matches!(st,
        hand_canopen::startup::Step::Write(w) if w.addr == ObjectAddr::new(0x1005, 0)
            && w.data == SdoData::u32(0x07F))));
    for bad in [0x000, 0x083, 0x703] {
        let s = StartupSettings {
            sync_cob_id: CobId::try_new(bad).expect("11 bits"),
            ..s
        };
        assert_eq!(s.plan(), Err(SettingsError::SyncCobId(bad)));
    }
    let short = StartupSettings {
        master_heartbeat_timeout_ms: 50,
        ..s
    };
    assert!(matches!(
        short.plan(),
        Err(SettingsError::WatchdogTooShort { .. })
    ));
    let zero = StartupSettings {
        sdo_timeout_us: 0,
        ..s
    };
    assert_eq!(zero.plan(), Err(SettingsError::Zero("sdo_timeout_us")));
    let odd = StartupSettings {
        sync_period_us: 1_000_001,
        ..s
    };
    assert_eq!(odd.plan(), Err(SettingsError::SyncPeriod(1_000_001)));
}

#[test]
fn frames_convert_at_the_edge() {
    assert!(CanFrame::new(0x800, &[]).is_none());
    assert!(CanFrame::new(0x100, &[0; 9]).is_none());
    let f = NmtCommand::Start.frame(Some(node(1)));
    let back: CanFrame = f.to_frame().expect("standard id");
    assert_eq!(CanFrame::from_frame(&back), Some(f));
    assert_eq!(format!("{f:?}"), "000#0101");
}
