//! The handstack CAN bus: `hand.dbc` is the single source of truth for every frame on the
//! prosthesis's bus, and this crate owns it.
//!
//! - [`messages`]: message types generated from hand.dbc by `hand-dbc-codegen`
//!   (`cargo run -p hand-dbc-codegen --bin hand-dbc-gen`) into the checked-in module
//!   `core/src/messages/generated.rs`, with the [`messages::decode`] dispatcher and
//!   [`messages::Message`].
//! - [`hand`]: the hand's constants from the DBC: [`hand::N_FINGERS`], [`hand::FINGER_NAMES`]
//!   (0 thumb .. 4 pinky), [`hand::finger_index`], the EMG ADC rails [`hand::ADC_MIN`] and
//!   [`hand::ADC_MAX`].
//! - [`CanFrame`]: the concrete classic-CAN frame (implements [`embedded_can::Frame`]).
//! - [`e2e`]: alive counter + CRC-8 SAE J1850 protection and the receiver-side checker.
//! - [`emg`]: reassembly of 12-channel sEMG samples from the three EMG frame groups.
//! - [`emg_front`]: the one EMG front end (E2E, decode, reassembly, rails, µV) that the daemon
//!   and offline session loading share.
//! - [`busload`]: worst-case bus load computed from the DBC.
//! - [`candump`]: can-utils log reading and writing.
//!
//! The codec itself (`messages`, `e2e`, `emg`, `hand`, [`CanFrame`]) lives in the no_std,
//! no-alloc crate `hand-dbc-core` (`can-dbc/core`), which the amplifier node's firmware builds
//! too; this crate re-exports it unchanged, so `hand_dbc::messages::...` and the rest keep
//! their paths, and adds the host-side parts (`emg_front`, `busload`, `candump`).
//!
//! Nothing here knows sockets, threads or clocks: the same code runs in the daemon, the
//! simulator, offline evaluation and replay.
//!
//! ```
//! use hand_dbc::e2e::{E2eChecker, E2eProtector, E2eStatus};
//! use hand_dbc::messages::{self, FingerMode, FingerSetpoint, Message};
//!
//! // Sender: a checked setpoint for finger 1 (index), protected with counter and CRC.
//! let sp = FingerSetpoint::new(1, FingerMode::Active, 4.5, -0.25, 0)?;
//! let mut protector = E2eProtector::new(sp.e2e());
//! let frame = protector.protect_message(&sp)?;
//! assert_eq!(frame.raw_id(), 0x201);
//!
//! // Out-of-range values are refused, never wrapped or saturated.
//! assert!(FingerSetpoint::new(1, FingerMode::Active, 80.0, 0.0, 0).is_err());
//!
//! // Receiver: check E2E, then decode by id.
//! let mut checker = E2eChecker::try_new(FingerSetpoint::E2E[1], 1)?;
//! assert_eq!(checker.check_frame(Some(&frame)), E2eStatus::Ok);
//! match messages::decode_frame(&frame)? {
//!     Message::FingerSetpoint(m) => assert_eq!((m.instance(), m.force()), (1, 4.5)),
//!     other => panic!("unexpected {other:?}"),
//! }
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod busload;
pub mod candump;
pub mod emg_front;

pub use hand_dbc_core::{e2e, emg, hand, messages};
pub use hand_dbc_core::{CanFrame, CodecError, MessageInfo, SignalInfo, MAX_DLC};
