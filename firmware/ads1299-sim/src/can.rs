//! A CAN controller that takes every frame: what the node sends, in its order.

/// Takes every frame handed to it, in order (never full, never an error); receives nothing.
#[derive(Debug, Clone)]
pub struct TakeAll<F>(pub Vec<F>);

impl<F> Default for TakeAll<F> {
    fn default() -> Self {
        Self(Vec::new())
    }
}

impl<F: embedded_can::Frame + Clone> embedded_can::nb::Can for TakeAll<F> {
    type Frame = F;
    type Error = embedded_can::ErrorKind;

    fn transmit(&mut self, frame: &F) -> nb::Result<Option<F>, Self::Error> {
        self.0.push(frame.clone());
        Ok(None)
    }

    fn receive(&mut self) -> nb::Result<F, Self::Error> {
        Err(nb::Error::WouldBlock)
    }
}
