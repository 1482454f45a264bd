//! Faults on demand: what can go wrong on the bus, switched on for a time window.
//!
//! A [`FaultPlan`] is a list of [`Fault`]s, each active in `[from_us, until_us)`. Every node
//! holds a copy and asks it, per frame, whether to misbehave; lookups walk a short list and
//! never allocate. Periodic faults use `every: n` (the n-th, 2n-th, ... frame) rather than a
//! probability, so a test can predict exactly what appears on the bus.

use std::str::FromStr;

use crate::error::SimError;
use crate::finger::N_FINGERS;

/// Which stream a bad-CRC fault corrupts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CrcTarget {
    /// EMG_SAMPLES_G0..G2.
    Emg,
    /// EMG_STATUS.
    EmgStatus,
    /// FINGER_STATUS of one finger.
    FingerStatus(usize),
}

/// One kind of misbehaviour.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Fault {
    /// The amplifier drops every `every`-th EMG frame.
    DropEmgFrames {
        /// Period in frames (>= 1; 1 drops them all).
        every: u32,
    },
    /// The amplifier sends every `every`-th EMG frame twice.
    RepeatEmgFrames {
        /// Period in frames (>= 1).
        every: u32,
    },
    /// Every `every`-th sample's three frames are held back and sent after the next sample's.
    ReorderEmgFrames {
        /// Period in samples (>= 2).
        every: u32,
    },
    /// The sample counter jumps forward by `by` once, when the fault starts.
    CounterJump {
        /// Extra counter steps (1..=255).
        by: u8,
    },
    /// Every `every`-th frame of `target` carries a wrong CRC.
    BadCrc {
        /// The corrupted stream.
        target: CrcTarget,
        /// Period in frames (>= 1).
        every: u32,
    },
    /// Electrodes of these channels (bit c = channel c) lose contact: EMG_STATUS reports them
    /// and their samples show clipped mains pick-up.
    LeadOff {
        /// Channel mask (12 bits).
        channels: u16,
    },
    /// These channels are driven into the rail: their samples clip and EMG_STATUS reports it.
    Saturation {
        /// Channel mask (12 bits).
        channels: u16,
    },
    /// The amplifier sends nothing (neither samples nor status).
    AmplifierSilence,
    /// An E-stop (HAND_ESTOP, STOP from TOOL) is sent at the start and every 10 ms while the
    /// fault is active (hand.dbc's repetition rate).
    EStop,
    /// A motor controller stops reporting FINGER_STATUS (it still obeys setpoints).
    MotorSilent {
        /// The silent finger.
        finger: usize,
    },
    /// A motor controller receives no setpoints (its receive path broke; the bus and the
    /// other controllers are fine): it brakes by itself after its setpoint timeout and reports
    /// it, while the other fingers go on.
    SetpointLoss {
        /// The finger whose controller hears nothing.
        finger: usize,
    },
    /// `count` frames with an id hand.dbc does not define, sent at once when the fault starts.
    UnknownIdBurst {
        /// 11-bit id not in hand.dbc.
        id: u16,
        /// Frames in the burst (1..=10000).
        count: u32,
    },
    /// 8-byte frames on id 0x001 (above every hand.dbc id in priority) at 1 Mbit/s worth of
    /// worst-case-stuffed frames (7,407 frames/s): on a real bus it starves everyone else.
    BusFlood,
    /// Beyond the calibration (issue 25): the patient contracts `pct` percent of the
    /// calibration's full effort (a stronger grip than the one recorded), every muscle alike.
    OverEffort {
        /// Percent of the calibrated full effort (101..=500).
        pct: u16,
    },
    /// An electrode of `channel` is knocked or pops when the fault starts: a step on that
    /// channel that decays back (see [`crate::emg::POP_UV`]).
    ElectrodePop {
        /// The channel (0..12).
        channel: u8,
    },
    /// Finger `finger`'s CiA 402 drive trips when the fault starts (EMCY 0x2310, continuous
    /// over-current, then Fault); it stays in Fault until handd's fault reset.
    DriveTrip {
        /// The finger moved by the drive (`handsim --cia402`).
        finger: usize,
    },
    /// Finger `finger`'s CiA 402 drive is power-cycled when the fault starts: its
    /// configuration is gone and it sends its boot-up message again.
    DrivePowerCycle {
        /// The finger moved by the drive.
        finger: usize,
    },
    /// The electrode band slipped around the forearm by `tenths` tenths of an electrode
    /// spacing (positive: channel c moves toward c + 1) while the fault is on.
    ElectrodeShift {
        /// Tenths of a spacing, -10..=10 and not 0.
        tenths: i8,
    },
}

/// Ids an unknown-id burst must avoid: hand.dbc's, and 0x000/0x001 (the flood's).
const RESERVED_IDS: [u16; 19] = [
    0x080, 0x100, 0x101, 0x102, 0x180, 0x200, 0x201, 0x202, 0x203, 0x204, 0x280, 0x281, 0x282,
    0x283, 0x284, 0x300, 0x301, 0x001, 0x000,
];

impl Fault {
    /// Checks the fault's parameters.
    pub fn validate(&self) -> Result<(), SimError> {
        let bad = |what: String| Err(SimError::BadScript(what));
        match *self {
            Fault::DropEmgFrames { every }
            | Fault::RepeatEmgFrames { every }
            | Fault::BadCrc { every, .. }
                if every == 0 =>
            {
                bad(format!("{self:?}: every must be >= 1"))
            }
            Fault::ReorderEmgFrames { every } if every < 2 => {
                bad(format!("{self:?}: every must be >= 2"))
            }
            Fault::CounterJump { by: 0 } => bad("counter jump by 0 is no jump".into()),
            Fault::BadCrc {
                target: CrcTarget::FingerStatus(f),
                ..
            }
            | Fault::MotorSilent { finger: f }
            | Fault::SetpointLoss { finger: f }
            | Fault::DriveTrip { finger: f }
            | Fault::DrivePowerCycle { finger: f }
                if f >= N_FINGERS =>
            {
                Err(SimError::BadFinger(f))
            }
            Fault::LeadOff { channels } | Fault::Saturation { channels }
                if channels == 0 || channels > 0xFFF =>
            {
                bad(format!("{self:?}: channel mask must be 1..=0xFFF"))
            }
            Fault::OverEffort { pct } if !(101..=500).contains(&pct) => bad(format!(
                "{self:?}: percent of full effort must be 101..=500"
            )),
            Fault::ElectrodePop { channel } if usize::from(channel) >= crate::emg::N_CHANNELS => {
                bad(format!("{self:?}: channel must be 0..=11"))
            }
            Fault::ElectrodeShift { tenths } if tenths == 0 || !(-10..=10).contains(&tenths) => {
                bad(format!(
                    "{self:?}: shift must be -10..=10 tenths of a spacing, not 0"
                ))
            }
            Fault::UnknownIdBurst { id, count } => {
                if id > 0x7FF || RESERVED_IDS.contains(&id) {
                    bad(format!("{self:?}: id must be an 11-bit id not used by hand.dbc (nor the flood's 0x001)"))
                } else if count == 0 || count > 10_000 {
                    bad(format!("{self:?}: count must be 1..=10000"))
                } else {
                    Ok(())
                }
            }
            _ => Ok(()),
        }
    }

    /// Names accepted by [`FromStr`], with their parameter syntax.
    pub const SYNTAX: &'static str =
        "drop-emg[:N] repeat-emg[:N] reorder-emg[:N] counter-jump[:BY] \
bad-crc-emg[:N] bad-crc-status[:N] bad-crc-finger:F[:N] lead-off[:MASK] saturation[:MASK] \
amp-silence estop motor-silent:F setpoint-loss:F unknown-ids[:ID[:COUNT]] flood \
over-effort[:PCT] electrode-pop[:CH] electrode-shift[:TENTHS] drive-trip:F drive-power-cycle:F";
}

fn num<T: FromStr>(s: Option<&str>, default: T, what: &str) -> Result<T, SimError> {
    match s {
        None => Ok(default),
        Some(v) => {
            let parsed = match v.strip_prefix("0x") {
                Some(hex) => u64::from_str_radix(hex, 16)
                    .ok()
                    .and_then(|x| x.to_string().parse().ok()),
                None => v.parse().ok(),
            };
            parsed.ok_or_else(|| SimError::BadScript(format!("{what}: cannot parse {v:?}")))
        }
    }
}

/// Parses the command-line form, e.g. `drop-emg:10`, `bad-crc-finger:2`, `lead-off:0x003`.
impl FromStr for Fault {
    type Err = SimError;

    fn from_str(s: &str) -> Result<Self, SimError> {
        let mut parts = s.split(':');
        let name = parts.next().unwrap_or_default();
        let (a, b) = (parts.next(), parts.next());
        let f = match name {
            "drop-emg" => Fault::DropEmgFrames {
                every: num(a, 10, s)?,
            },
            "repeat-emg" => Fault::RepeatEmgFrames {
                every: num(a, 10, s)?,
            },
            "reorder-emg" => Fault::ReorderEmgFrames {
                every: num(a, 10, s)?,
            },
            "counter-jump" => Fault::CounterJump { by: num(a, 5, s)? },
            "bad-crc-emg" => Fault::BadCrc {
                target: CrcTarget::Emg,
                every: num(a, 10, s)?,
            },
            "bad-crc-status" => Fault::BadCrc {
                target: CrcTarget::EmgStatus,
                every: num(a, 1, s)?,
            },
            "bad-crc-finger" => Fault::BadCrc {
                target: CrcTarget::FingerStatus(num(a, usize::MAX, s)?),
                every: num(b, 1, s)?,
            },
            "lead-off" => Fault::LeadOff {
                channels: num(a, 0x001, s)?,
            },
            "saturation" => Fault::Saturation {
                channels: num(a, 0x001, s)?,
            },
            "amp-silence" => Fault::AmplifierSilence,
            "estop" => Fault::EStop,
            "motor-silent" => Fault::MotorSilent {
                finger: num(a, usize::MAX, s)?,
            },
            "setpoint-loss" => Fault::SetpointLoss {
                finger: num(a, usize::MAX, s)?,
            },
            "unknown-ids" => Fault::UnknownIdBurst {
                id: num(a, 0x7A0, s)?,
                count: num(b, 100, s)?,
            },
            "flood" => Fault::BusFlood,
            "drive-trip" => Fault::DriveTrip {
                finger: num(a, usize::MAX, s)?,
            },
            "drive-power-cycle" => Fault::DrivePowerCycle {
                finger: num(a, usize::MAX, s)?,
            },
            "over-effort" => Fault::OverEffort {
                pct: num(a, 250, s)?,
            },
            "electrode-pop" => Fault::ElectrodePop {
                channel: num(a, 0, s)?,
            },
            "electrode-shift" => Fault::ElectrodeShift {
                tenths: num(a, 5, s)?,
            },
            _ => {
                return Err(SimError::BadScript(format!(
                    "unknown fault {s:?}; known: {}",
                    Fault::SYNTAX
                )))
            }
        };
        f.validate()?;
        Ok(f)
    }
}

/// A fault and its time window `[from_us, until_us)`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ScheduledFault {
    /// The fault.
    pub fault: Fault,
    /// Start, µs (node time).
    pub from_us: u64,
    /// End (exclusive), µs.
    pub until_us: u64,
}

impl ScheduledFault {
    /// True while the fault is on.
    pub fn active(&self, now_us: u64) -> bool {
        (self.from_us..self.until_us).contains(&now_us)
    }
}

/// Most faults in one plan (one-shot faults are remembered in a 64-bit mask).
pub const MAX_FAULTS: usize = 64;

/// The faults of a run.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct FaultPlan {
    faults: Vec<ScheduledFault>,
}

impl FaultPlan {
    /// No faults.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds `fault` for `[from_us, until_us)`.
    pub fn add(
        &mut self,
        fault: Fault,
        from_us: u64,
        until_us: u64,
    ) -> Result<&mut Self, SimError> {
        fault.validate()?;
        if until_us <= from_us {
            return Err(SimError::BadScript(format!(
                "{fault:?}: window [{from_us}, {until_us}) is empty"
            )));
        }
        if self.faults.len() == MAX_FAULTS {
            return Err(SimError::BadScript(format!(
                "at most {MAX_FAULTS} faults per plan"
            )));
        }
        self.faults.push(ScheduledFault {
            fault,
            from_us,
            until_us,
        });
        Ok(self)
    }

    /// Adds `fault` from `from_us` on, for good.
    pub fn add_from(&mut self, fault: Fault, from_us: u64) -> Result<&mut Self, SimError> {
        self.add(fault, from_us, u64::MAX)
    }

    /// The scheduled faults, with their index (used for one-shot bookkeeping).
    pub fn iter(&self) -> impl Iterator<Item = (usize, &ScheduledFault)> {
        self.faults.iter().enumerate()
    }

    /// The faults active at `now_us`.
    pub fn active(&self, now_us: u64) -> impl Iterator<Item = (usize, Fault)> + '_ {
        self.faults
            .iter()
            .enumerate()
            .filter(move |(_, s)| s.active(now_us))
            .map(|(i, s)| (i, s.fault))
    }

    /// True if no fault is scheduled.
    pub fn is_empty(&self) -> bool {
        self.faults.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_the_command_line_forms() {
        assert_eq!(
            "drop-emg:7".parse::<Fault>(),
            Ok(Fault::DropEmgFrames { every: 7 })
        );
        assert_eq!(
            "lead-off:0x003".parse::<Fault>(),
            Ok(Fault::LeadOff { channels: 3 })
        );
        assert_eq!(
            "bad-crc-finger:2".parse::<Fault>(),
            Ok(Fault::BadCrc {
                target: CrcTarget::FingerStatus(2),
                every: 1
            })
        );
        assert!(
            "motor-silent".parse::<Fault>().is_err(),
            "finger is required"
        );
        assert!(
            "unknown-ids:0x100".parse::<Fault>().is_err(),
            "a DBC id is not unknown"
        );
        assert!("warp-drive".parse::<Fault>().is_err());
    }

    #[test]
    fn the_beyond_calibration_forms_parse_and_are_bounded() {
        assert_eq!(
            "over-effort".parse::<Fault>(),
            Ok(Fault::OverEffort { pct: 250 })
        );
        assert_eq!(
            "electrode-pop:7".parse::<Fault>(),
            Ok(Fault::ElectrodePop { channel: 7 })
        );
        assert_eq!(
            "electrode-shift:-5".parse::<Fault>(),
            Ok(Fault::ElectrodeShift { tenths: -5 })
        );
        for bad in [
            "over-effort:100",
            "over-effort:501",
            "electrode-pop:12",
            "electrode-shift:0",
            "electrode-shift:11",
        ] {
            assert!(bad.parse::<Fault>().is_err(), "{bad} was accepted");
        }
    }

    #[test]
    fn windows_are_half_open_and_validated() {
        let mut p = FaultPlan::new();
        p.add(Fault::EStop, 10, 20).expect("valid");
        assert_eq!(p.active(9).count(), 0);
        assert_eq!(p.active(10).count(), 1);
        assert_eq!(p.active(20).count(), 0);
        assert!(p.add(Fault::EStop, 5, 5).is_err());
        assert!(p.add(Fault::DropEmgFrames { every: 0 }, 0, 1).is_err());
    }
}
