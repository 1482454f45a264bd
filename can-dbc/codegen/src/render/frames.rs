//! Conversion to and from CAN frames, and the E2E `Protected` impl.

use crate::model::Group;

/// `to_frame`, `to_can_frame` and `try_from_frame`.
pub(super) fn methods(g: &Group) -> String {
    let decode = if g.is_family() {
        "Self::decode(id, frame.data())"
    } else {
        "if id != Self::ID { return Err(CodecError::WrongId { message: Self::NAME, id }); }
Self::decode(frame.data())"
    };
    format!(
        "/// The message as a [`CanFrame`].
pub fn to_frame(&self) -> CanFrame {{ CanFrame::from_dbc(self.id(), &self.encode()) }}

/// The message as any [`embedded_can::Frame`] (e.g. a SocketCAN frame).
pub fn to_can_frame<F: embedded_can::Frame>(&self) -> Result<F, CodecError> {{
to_can_frame(self.id(), &self.encode())
}}

/// Decodes any [`embedded_can::Frame`]; refuses remote frames, extended ids and other \
         messages' ids.
pub fn try_from_frame<F: embedded_can::Frame>(frame: &F) -> Result<Self, CodecError> {{
let id = standard_data_frame(frame)?;
{decode}
}}

"
    )
}

/// `impl crate::e2e::Protected` for protected messages (nothing otherwise).
pub(super) fn protected_impl(g: &Group) -> String {
    if g.first().e2e.is_none() {
        return String::new();
    }
    let ty = &g.ty;
    format!(
        "impl crate::e2e::Protected for {ty} {{
fn e2e_profile(&self) -> E2eProfile {{ self.e2e() }}
fn to_frame(&self) -> CanFrame {{ {ty}::to_frame(self) }}
}}

"
    )
}
