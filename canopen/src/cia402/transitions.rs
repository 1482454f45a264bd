//! The CiA 402 power state transitions the master commands, as data (figure 30's numbers).

use super::controlword::{Command, Controlword};
use super::state::PowerState;

use PowerState::{
    Fault, OperationEnabled, QuickStopActive, ReadyToSwitchOn, SwitchOnDisabled, SwitchedOn,
};

/// One commanded transition: from, command, to, CiA 402 transition number.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Transition {
    /// The state the drive is in.
    pub from: PowerState,
    /// The command.
    pub command: Command,
    /// The state it goes to.
    pub to: PowerState,
    /// The transition's number in CiA 402.
    pub number: u8,
}

const fn t(from: PowerState, command: Command, to: PowerState, number: u8) -> Transition {
    Transition {
        from,
        command,
        to,
        number,
    }
}

/// Every controlword-commanded transition. (0, 1, 13, 14 happen inside the drive.)
pub const TRANSITIONS: [Transition; 15] = [
    t(SwitchOnDisabled, Command::Shutdown, ReadyToSwitchOn, 2),
    t(ReadyToSwitchOn, Command::SwitchOn, SwitchedOn, 3),
    t(SwitchedOn, Command::EnableOperation, OperationEnabled, 4),
    t(OperationEnabled, Command::DisableOperation, SwitchedOn, 5),
    t(SwitchedOn, Command::Shutdown, ReadyToSwitchOn, 6),
    t(
        ReadyToSwitchOn,
        Command::DisableVoltage,
        SwitchOnDisabled,
        7,
    ),
    t(ReadyToSwitchOn, Command::QuickStop, SwitchOnDisabled, 7),
    t(OperationEnabled, Command::Shutdown, ReadyToSwitchOn, 8),
    t(
        OperationEnabled,
        Command::DisableVoltage,
        SwitchOnDisabled,
        9,
    ),
    t(SwitchedOn, Command::DisableVoltage, SwitchOnDisabled, 10),
    t(SwitchedOn, Command::QuickStop, SwitchOnDisabled, 10),
    t(OperationEnabled, Command::QuickStop, QuickStopActive, 11),
    t(
        QuickStopActive,
        Command::DisableVoltage,
        SwitchOnDisabled,
        12,
    ),
    t(Fault, Command::FaultReset, SwitchOnDisabled, 15),
    t(
        QuickStopActive,
        Command::EnableOperation,
        OperationEnabled,
        16,
    ),
];

/// The transition a drive in `from` takes on `cw` (the device side). Fault reset is an edge:
/// `previous` is the controlword before `cw`. `None`: no transition.
pub fn transition_for(
    from: PowerState,
    previous: Controlword,
    cw: Controlword,
) -> Option<&'static Transition> {
    TRANSITIONS.iter().find(|tr| {
        tr.from == from
            && match tr.command {
                Command::FaultReset => cw.fault_reset_bit() && !previous.fault_reset_bit(),
                c => !cw.fault_reset_bit() && c.matches(cw),
            }
    })
}

/// The next command on the way from `from` to Operation enabled (the master side);
/// `None` when there or when the drive moves by itself (Not ready, Fault reaction).
pub fn toward_operation_enabled(from: PowerState) -> Option<Command> {
    match from {
        SwitchOnDisabled => Some(Command::Shutdown),
        ReadyToSwitchOn => Some(Command::SwitchOn),
        SwitchedOn => Some(Command::EnableOperation),
        QuickStopActive => Some(Command::DisableVoltage),
        Fault => Some(Command::FaultReset),
        OperationEnabled | PowerState::NotReadyToSwitchOn | PowerState::FaultReactionActive => None,
    }
}
