//! The whole simulated world on one bus: patient, amplifier, five motor controllers and the
//! fault injector, stepped together.
//!
//! Each node has its own bus handle (an endpoint of a [`crate::bus::MemBus`], or its own
//! SocketCAN socket), exactly as separate ECUs would, so every frame crosses the bus.

use hand_dbc::messages::{
    CalibrationCue, EmgSamplesG0, EmgSamplesG1, EmgSamplesG2, FingerSetpoint, FingerStatus,
    HandEstop,
};

use crate::error::SimError;
use crate::faults::FaultPlan;
use crate::finger::{FingerConfig, N_FINGERS};
use crate::nodes::{
    std_id, AmplifierNode, AmplifierNodeConfig, Bus, DriveFingerConfig, DriveFingerNode,
    FaultInjector, FingerNode, NodeStats,
};
use crate::patient::{ClosedLoopUser, CuedConfig, CuedPatient, Intent, Script};

/// Who decides the patient's intent.
#[derive(Debug, Clone)]
pub enum PatientMode {
    /// A scripted timeline (rest, calibration, gestures).
    Script(Script),
    /// A closed-loop user tracking a target with one finger.
    ClosedLoop(Box<ClosedLoopUser>),
    /// A patient following the CALIBRATION_CUE frames on the bus (rests without them).
    Cued(Box<CuedPatient>),
}

impl PatientMode {
    /// A cued patient with these settings (checked).
    pub fn cued(cfg: CuedConfig) -> Result<Self, SimError> {
        Ok(PatientMode::Cued(Box::new(CuedPatient::try_new(cfg)?)))
    }
}

/// The simulated world.
#[derive(Debug)]
pub struct World<B: Bus> {
    start_us: u64,
    patient: PatientMode,
    patient_bus: B,
    patient_stats: NodeStats,
    amp: Option<(AmplifierNode, B)>,
    fingers: Vec<(FingerNode, B)>,
    drives: Vec<(DriveFingerNode, B)>,
    injector: (FaultInjector, B),
    intent: Intent,
    /// How often a closed-loop patient feels a drive-moved finger (the native status period),
    /// and when next, µs since the start.
    felt_period_us: u64,
    next_felt_us: u64,
}

/// Which nodes a world runs (for `handsim` beside real hardware, e.g. only the amplifier).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct NodeSelection {
    /// Run the amplifier.
    pub amplifier: bool,
    /// Run the motor controllers of these fingers (bit f = finger f).
    pub fingers: u8,
}

impl Default for NodeSelection {
    fn default() -> Self {
        Self {
            amplifier: true,
            fingers: 0b1_1111,
        }
    }
}

/// Everything about a world except the patient and the transport.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct WorldConfig {
    /// The amplifier (its `start_us` is overridden by `start_us` below).
    pub amplifier: AmplifierNodeConfig,
    /// Every finger's limits and timing.
    pub finger: FingerConfig,
    /// Faults, handed to every node.
    pub faults: FaultPlan,
    /// Which nodes run.
    pub nodes: NodeSelection,
    /// Node time at which the scenario starts (scripts count from here), µs.
    pub start_us: u64,
    /// Fingers moved by a simulated CiA 402 drive instead of a native controller (the native
    /// one does not run for them).
    pub drives: [Option<DriveFingerConfig>; N_FINGERS],
}

/// The standard CAN ids one node reads: what a real node's acceptance filter would pass.
/// Everything else it would only drain unread, so a transport that can filter (SocketCAN in
/// the kernel) need not deliver it: on `vcan0` every frame would otherwise be copied to each
/// of the world's eight sockets.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Listens {
    /// Nothing (the amplifier, the fault injector, a scripted patient).
    Nothing,
    /// These ids only.
    To(&'static [u32]),
    /// Every standard frame but these ids.
    Except(&'static [u32]),
}

impl Listens {
    /// A simulated CiA 402 drive: every frame but the EMG samples (3000 a second, which no
    /// drive reads). Its ids follow its node id and its SYNC follows its 0x1005, so it takes
    /// the rest. On `vcan0` five drives that each copied every EMG frame too kept handsim at
    /// over a third of the VM's CPU.
    pub const DRIVE: Listens =
        Listens::Except(&[EmgSamplesG0::ID, EmgSamplesG1::ID, EmgSamplesG2::ID]);

    /// Whether a frame with standard id `id` is one the node reads.
    pub fn accepts(self, id: u32) -> bool {
        match self {
            Listens::Nothing => false,
            Listens::To(ids) => ids.contains(&id),
            Listens::Except(ids) => !ids.contains(&id),
        }
    }
}

/// What each finger's controller reads: its own FINGER_SETPOINT and HAND_ESTOP.
const FINGER_LISTENS: [[u32; 2]; N_FINGERS] = {
    let mut out = [[0; 2]; N_FINGERS];
    let mut f = 0;
    while f < N_FINGERS {
        out[f] = [FingerSetpoint::IDS[f], HandEstop::ID];
        f += 1;
    }
    out
};

impl PatientMode {
    /// What the patient reads from the bus: the tracked finger's FINGER_STATUS (closed loop),
    /// CALIBRATION_CUE (cued), nothing (scripted).
    pub fn listens(&self) -> Listens {
        match self {
            PatientMode::Script(_) => Listens::Nothing,
            PatientMode::ClosedLoop(u) => {
                Listens::To(std::slice::from_ref(&FingerStatus::IDS[u.config().finger]))
            }
            PatientMode::Cued(_) => Listens::To(&[CalibrationCue::ID]),
        }
    }
}

impl<B: Bus> World<B> {
    /// Builds the world; `open` is called once per node for its own bus handle (patient,
    /// injector, amplifier if selected, then each selected finger in order).
    pub fn try_new<E: std::fmt::Display>(
        cfg: WorldConfig,
        patient: PatientMode,
        mut open: impl FnMut() -> Result<B, E>,
    ) -> Result<Self, SimError> {
        Self::try_new_listening(cfg, patient, |_| open())
    }

    /// As [`World::try_new`], `open` being told what the node reads ([`Listens`]), for a
    /// transport that filters: nodes behave the same, they only never see what they ignore.
    pub fn try_new_listening<E: std::fmt::Display>(
        cfg: WorldConfig,
        patient: PatientMode,
        mut open: impl FnMut(Listens) -> Result<B, E>,
    ) -> Result<Self, SimError> {
        let mut open = |l| open(l).map_err(|e| SimError::Transport(e.to_string()));
        let patient_bus = open(patient.listens())?;
        let injector = (
            FaultInjector::new(cfg.faults.clone()),
            open(Listens::Nothing)?,
        );
        let amp = if cfg.nodes.amplifier {
            let mut amp = AmplifierNode::try_new(AmplifierNodeConfig {
                start_us: cfg.start_us,
                ..cfg.amplifier
            })?;
            amp.set_faults(cfg.faults.clone());
            Some((amp, open(Listens::Nothing)?))
        } else {
            None
        };
        let mut fingers = Vec::new();
        let mut drives = Vec::new();
        for (f, listens) in FINGER_LISTENS.iter().enumerate() {
            if let Some(d) = cfg.drives[f] {
                let mut node = DriveFingerNode::try_new(f, cfg.finger, d, cfg.start_us)?;
                node.set_faults(cfg.faults.clone());
                drives.push((node, open(Listens::DRIVE)?));
            } else if cfg.nodes.fingers & (1 << f) != 0 {
                let mut node = FingerNode::try_new(f, cfg.finger, cfg.start_us)?;
                node.set_faults(cfg.faults.clone());
                fingers.push((node, open(Listens::To(listens))?));
            }
        }
        Ok(Self {
            start_us: cfg.start_us,
            patient,
            patient_bus,
            patient_stats: NodeStats::default(),
            amp,
            fingers,
            drives,
            injector,
            intent: Intent::REST,
            felt_period_us: cfg.finger.status_period_us,
            next_felt_us: 0,
        })
    }

    /// Advances every node to `now_us`.
    pub fn step(&mut self, now_us: u64) {
        let rel = now_us.saturating_sub(self.start_us);
        while let Some(frame) = self.patient_stats.receive(&mut self.patient_bus) {
            match &mut self.patient {
                PatientMode::ClosedLoop(user) => {
                    let id = std_id(&frame);
                    if FingerStatus::instance_of(id) == Some(user.config().finger) {
                        if let Ok(st) = FingerStatus::decode(id, frame.data()) {
                            user.observe(rel, st.force());
                        }
                    }
                }
                PatientMode::Cued(p) => p.observe(rel, &frame),
                PatientMode::Script(_) => {}
            }
        }
        self.intent = match &mut self.patient {
            PatientMode::Script(s) => s.intent_at(rel),
            PatientMode::ClosedLoop(u) => u.intent_at(rel),
            PatientMode::Cued(p) => p.intent_at(rel),
        };
        if let Some((amp, bus)) = &mut self.amp {
            amp.set_intent(self.intent);
            amp.poll(now_us, bus);
        }
        for (node, bus) in &mut self.fingers {
            node.poll(now_us, bus);
        }
        for (node, bus) in &mut self.drives {
            node.poll(now_us, bus);
        }
        self.injector.0.poll(now_us, &mut self.injector.1);
        self.feel_drive_finger(rel);
    }

    /// A closed-loop patient whose finger a CiA 402 drive moves: no FINGER_STATUS comes from a
    /// drive, so the patient feels the finger's force itself, at the native status rate (the
    /// same reading a native controller reports, with the same reaction delay after it).
    fn feel_drive_finger(&mut self, rel_us: u64) {
        let PatientMode::ClosedLoop(user) = &mut self.patient else {
            return;
        };
        if rel_us < self.next_felt_us {
            return;
        }
        let finger = user.config().finger;
        if let Some((node, _)) = self.drives.iter().find(|(n, _)| n.finger() == finger) {
            user.observe(rel_us, node.physics().force_n);
            self.next_felt_us = rel_us + self.felt_period_us;
        }
    }

    /// The intent the patient had at the last step.
    pub fn intent(&self) -> Intent {
        self.intent
    }

    /// The patient (e.g. a cued patient's [`CuedPatient::stats`]).
    pub fn patient(&self) -> &PatientMode {
        &self.patient
    }

    /// The amplifier node, if it runs.
    pub fn amplifier(&self) -> Option<&AmplifierNode> {
        self.amp.as_ref().map(|(a, _)| a)
    }

    /// The motor controllers that run.
    pub fn fingers(&self) -> impl Iterator<Item = &FingerNode> {
        self.fingers.iter().map(|(n, _)| n)
    }

    /// The fingers moved by a CiA 402 drive.
    pub fn drive_fingers(&self) -> impl Iterator<Item = &DriveFingerNode> {
        self.drives.iter().map(|(n, _)| n)
    }

    /// Finger `finger`'s CiA 402 drive, to script its faults (a trip, a power cycle).
    pub fn drive_finger_mut(&mut self, finger: usize) -> Option<&mut DriveFingerNode> {
        self.drives
            .iter_mut()
            .map(|(n, _)| n)
            .find(|n| n.finger() == finger)
    }

    /// The fault injector.
    pub fn injector(&self) -> &FaultInjector {
        &self.injector.0
    }

    /// Frames sent by all nodes so far.
    pub fn frames_sent(&self) -> u64 {
        self.amp.as_ref().map_or(0, |(a, _)| a.stats().tx_frames)
            + self.injector.0.stats().tx_frames
            + self
                .fingers
                .iter()
                .map(|(n, _)| n.stats().tx_frames)
                .sum::<u64>()
            + self
                .drives
                .iter()
                .map(|(n, _)| n.stats().tx_frames)
                .sum::<u64>()
    }
}
