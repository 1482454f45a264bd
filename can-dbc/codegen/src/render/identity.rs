//! Which message a value is: `id`, `name`, `e2e`, and for families `instance` and
//! `instance_of`.

use crate::model::Group;

/// The identity methods of a message type.
pub(super) fn render(g: &Group) -> String {
    let protected = g.first().e2e.is_some();
    if g.is_family() {
        family(protected)
    } else {
        single(protected)
    }
}

fn family(protected: bool) -> String {
    let e2e = if protected {
        "/// E2E profile of this instance.
pub fn e2e(&self) -> E2eProfile { Self::E2E[usize::from(self.instance)] }

"
    } else {
        ""
    };
    format!(
        "/// Instance index (e.g. the finger).
pub fn instance(&self) -> usize {{ usize::from(self.instance) }}

/// CAN id of this instance.
pub fn id(&self) -> u32 {{ Self::IDS[usize::from(self.instance)] }}

/// DBC name of this instance.
pub fn name(&self) -> &'static str {{ Self::NAMES[usize::from(self.instance)] }}

/// The instance a CAN id belongs to, if any.
pub fn instance_of(id: u32) -> Option<usize> {{ Self::IDS.iter().position(|&i| i == id) }}

{e2e}"
    )
}

fn single(protected: bool) -> String {
    let e2e = if protected {
        "/// E2E profile.
pub fn e2e(&self) -> E2eProfile { Self::E2E }

"
    } else {
        ""
    };
    format!(
        "/// CAN id.
pub fn id(&self) -> u32 {{ Self::ID }}

/// DBC name.
pub fn name(&self) -> &'static str {{ Self::NAME }}

{e2e}"
    )
}
