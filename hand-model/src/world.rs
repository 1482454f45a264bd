//! The whole simulated world on one bus: patient, amplifier, five motor controllers and the
//! fault injector, stepped together.
//!
//! Each node has its own bus handle (an endpoint of a [`crate::bus::MemBus`], or its own
//! SocketCAN socket), exactly as separate ECUs would, so every frame crosses the bus.

use hand_dbc::messages::FingerStatus;

use crate::error::SimError;
use crate::faults::FaultPlan;
use crate::finger::{FingerConfig, N_FINGERS};
use crate::nodes::{
    std_id, AmplifierNode, AmplifierNodeConfig, Bus, FaultInjector, FingerNode, NodeStats,
};
use crate::patient::{ClosedLoopUser, Intent, Script};

/// Who decides the patient's intent.
#[derive(Debug, Clone)]
pub enum PatientMode {
    /// A scripted timeline (rest, calibration, gestures).
    Script(Script),
    /// A closed-loop user tracking a target with one finger.
    ClosedLoop(Box<ClosedLoopUser>),
}

/// The simulated world.
#[derive(Debug)]
pub struct World<B: Bus> {
    start_us: u64,
    patient: PatientMode,
    patient_bus: B,
    patient_stats: NodeStats,
    amp: (AmplifierNode, B),
    fingers: Vec<(FingerNode, B)>,
    injector: (FaultInjector, B),
    intent: Intent,
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

impl<B: Bus> World<B> {
    /// Builds the world starting at `start_us`; `open` is called once per node for its bus
    /// handle (patient, amplifier, injector, then each selected finger).
    pub fn try_new<E: std::fmt::Display>(
        mut amp_cfg: AmplifierNodeConfig,
        finger_cfg: FingerConfig,
        patient: PatientMode,
        faults: FaultPlan,
        nodes: NodeSelection,
        start_us: u64,
        mut open: impl FnMut() -> Result<B, E>,
    ) -> Result<Self, SimError> {
        let mut open = || open().map_err(|e| SimError::Transport(e.to_string()));
        amp_cfg.start_us = start_us;
        let mut amp = AmplifierNode::try_new(amp_cfg)?;
        amp.set_faults(faults.clone());
        if !nodes.amplifier {
            amp.set_faults(FaultPlan::new());
        }
        let patient_bus = open()?;
        let amp_bus = open()?;
        let injector_bus = open()?;
        let mut fingers = Vec::new();
        for f in 0..N_FINGERS {
            if nodes.fingers & (1 << f) != 0 {
                let mut node = FingerNode::try_new(f, finger_cfg, start_us)?;
                node.set_faults(faults.clone());
                fingers.push((node, open()?));
            }
        }
        // An unselected amplifier is represented by a silent plan: the node still exists so
        // the world's shape does not depend on the selection, but it is never polled.
        let amp_enabled = nodes.amplifier;
        let mut world = Self {
            start_us,
            patient,
            patient_bus,
            patient_stats: NodeStats::default(),
            amp: (amp, amp_bus),
            fingers,
            injector: (FaultInjector::new(faults), injector_bus),
            intent: Intent::REST,
        };
        if !amp_enabled {
            world.amp.0.set_faults(silence_forever());
        }
        Ok(world)
    }

    /// Advances every node to `now_us`.
    pub fn step(&mut self, now_us: u64) {
        let rel = now_us.saturating_sub(self.start_us);
        while let Some(frame) = self.patient_stats.receive(&mut self.patient_bus) {
            if let PatientMode::ClosedLoop(user) = &mut self.patient {
                let id = std_id(&frame);
                if FingerStatus::instance_of(id) == Some(user.config().finger) {
                    if let Ok(st) = FingerStatus::decode(id, frame.data()) {
                        user.observe(rel, st.force());
                    }
                }
            }
        }
        self.intent = match &mut self.patient {
            PatientMode::Script(s) => s.intent_at(rel),
            PatientMode::ClosedLoop(u) => u.intent_at(rel),
        };
        self.amp.0.set_intent(self.intent);
        self.amp.0.poll(now_us, &mut self.amp.1);
        for (node, bus) in &mut self.fingers {
            node.poll(now_us, bus);
        }
        self.injector.0.poll(now_us, &mut self.injector.1);
    }

    /// The intent the patient had at the last step.
    pub fn intent(&self) -> Intent {
        self.intent
    }

    /// The amplifier node.
    pub fn amplifier(&self) -> &AmplifierNode {
        &self.amp.0
    }

    /// The motor controllers that run.
    pub fn fingers(&self) -> impl Iterator<Item = &FingerNode> {
        self.fingers.iter().map(|(n, _)| n)
    }

    /// The fault injector.
    pub fn injector(&self) -> &FaultInjector {
        &self.injector.0
    }

    /// Frames sent by all nodes so far.
    pub fn frames_sent(&self) -> u64 {
        self.amp.0.stats().tx_frames
            + self.injector.0.stats().tx_frames
            + self
                .fingers
                .iter()
                .map(|(n, _)| n.stats().tx_frames)
                .sum::<u64>()
    }
}

fn silence_forever() -> FaultPlan {
    let mut p = FaultPlan::new();
    // Cannot fail: a valid fault over a non-empty window.
    let _ = p.add(crate::faults::Fault::AmplifierSilence, 0, u64::MAX);
    p
}
