//! NMT: the master's commands (COB-ID 0x000), boot-up and the NMT state a heartbeat reports.

use crate::frame::CanFrame;
use crate::ids::NodeId;
use thiserror::Error;

/// An NMT command specifier (CiA 301 7.2.8.3.1).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum NmtCommand {
    /// 0x01: start remote node (-> Operational).
    Start,
    /// 0x02: stop remote node (-> Stopped).
    Stop,
    /// 0x80: enter pre-operational.
    PreOperational,
    /// 0x81: reset node (application and communication).
    ResetNode,
    /// 0x82: reset communication.
    ResetCommunication,
}

/// Every NMT command, for tables and tests.
pub const NMT_COMMANDS: [NmtCommand; 5] = [
    NmtCommand::Start,
    NmtCommand::Stop,
    NmtCommand::PreOperational,
    NmtCommand::ResetNode,
    NmtCommand::ResetCommunication,
];

impl NmtCommand {
    /// The command specifier byte.
    pub fn specifier(self) -> u8 {
        match self {
            Self::Start => 0x01,
            Self::Stop => 0x02,
            Self::PreOperational => 0x80,
            Self::ResetNode => 0x81,
            Self::ResetCommunication => 0x82,
        }
    }

    /// The command for a specifier byte.
    pub fn from_specifier(cs: u8) -> Option<Self> {
        NMT_COMMANDS.into_iter().find(|c| c.specifier() == cs)
    }

    /// The frame: COB-ID 0x000, `[cs, node]`; `None` addresses every node (node 0).
    pub fn frame(self, node: Option<NodeId>) -> CanFrame {
        let mut d = [0u8; 8];
        d[0] = self.specifier();
        d[1] = node.map_or(0, NodeId::get);
        CanFrame::from_parts(0x000, 2, d)
    }
}

/// A decoded NMT command frame: the command and its target (`None` = all nodes).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct NmtMessage {
    /// The command.
    pub command: NmtCommand,
    /// The addressed node, `None` for a broadcast (node 0).
    pub node: Option<NodeId>,
}

/// What can be wrong with an NMT or heartbeat frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Error)]
pub enum NmtError {
    /// Not the COB-ID this decoder reads.
    #[error("COB-ID 0x{0:03X} is not an NMT frame")]
    WrongId(u16),
    /// The frame has the wrong length.
    #[error("NMT frame of {0} bytes (expected {1})")]
    Length(usize, usize),
    /// An unknown command specifier.
    #[error("unknown NMT command specifier 0x{0:02X}")]
    UnknownCommand(u8),
    /// Node id 128..=255 in an NMT command.
    #[error("NMT command addresses node {0}")]
    BadNode(u8),
    /// An unknown NMT state byte in a heartbeat.
    #[error("unknown NMT state 0x{0:02X} in a heartbeat")]
    UnknownState(u8),
}

impl NmtMessage {
    /// Decodes an NMT command frame (as a node sees it).
    pub fn decode(f: &CanFrame) -> Result<Self, NmtError> {
        if f.cob_id() != 0 {
            return Err(NmtError::WrongId(f.cob_id()));
        }
        let p = f.payload();
        if p.len() != 2 {
            return Err(NmtError::Length(p.len(), 2));
        }
        let command = NmtCommand::from_specifier(p[0]).ok_or(NmtError::UnknownCommand(p[0]))?;
        let node = match p[1] {
            0 => None,
            n => Some(NodeId::try_new(n).map_err(|_| NmtError::BadNode(n))?),
        };
        Ok(Self { command, node })
    }

    /// Whether this command is meant for `me`.
    pub fn addresses(&self, me: NodeId) -> bool {
        self.node.is_none_or(|n| n == me)
    }
}

/// The NMT state of a node (CiA 301 7.2.8.2.1), as its heartbeat reports it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum NmtState {
    /// 0x00: boot-up (only in the boot-up message).
    BootUp,
    /// 0x04: stopped.
    Stopped,
    /// 0x05: operational.
    Operational,
    /// 0x7F: pre-operational.
    PreOperational,
}

impl NmtState {
    /// The heartbeat state byte.
    pub fn byte(self) -> u8 {
        match self {
            Self::BootUp => 0x00,
            Self::Stopped => 0x04,
            Self::Operational => 0x05,
            Self::PreOperational => 0x7F,
        }
    }

    /// The state for a heartbeat byte (the toggle bit 7 is masked, as node guarding sets it).
    pub fn from_byte(b: u8) -> Result<Self, NmtError> {
        match b & 0x7F {
            0x00 => Ok(Self::BootUp),
            0x04 => Ok(Self::Stopped),
            0x05 => Ok(Self::Operational),
            0x7F => Ok(Self::PreOperational),
            _ => Err(NmtError::UnknownState(b)),
        }
    }
}

/// A decoded NMT error-control frame (0x700 + node): boot-up or heartbeat.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ErrorControl {
    /// The node that sent it.
    pub node: NodeId,
    /// Its state; [`NmtState::BootUp`] is the boot-up message.
    pub state: NmtState,
}

impl ErrorControl {
    /// The frame a node sends: 0x700 + node, one state byte.
    pub fn frame(self) -> CanFrame {
        let mut d = [0u8; 8];
        d[0] = self.state.byte();
        CanFrame::from_parts(0x700 + u16::from(self.node.get()), 1, d)
    }

    /// Decodes a boot-up or heartbeat frame.
    pub fn decode(f: &CanFrame) -> Result<Self, NmtError> {
        let id = f.cob_id();
        if !(0x701..=0x77F).contains(&id) {
            return Err(NmtError::WrongId(id));
        }
        let node = NodeId::try_new((id - 0x700) as u8).map_err(|e| NmtError::BadNode(e.0))?;
        let p = f.payload();
        if p.len() != 1 {
            return Err(NmtError::Length(p.len(), 1));
        }
        Ok(Self {
            node,
            state: NmtState::from_byte(p[0])?,
        })
    }

    /// Whether this is a boot-up message.
    pub fn is_boot_up(&self) -> bool {
        self.state == NmtState::BootUp
    }
}
