//! A fixed-size FIFO of frames: what the sampler produced and the CAN controller has not
//! taken yet. No heap; a full queue refuses (the node then drops the whole sample).

use hand_dbc_core::CanFrame;

/// Up to `N` frames, oldest first.
#[derive(Debug, Clone)]
pub struct TxQueue<const N: usize> {
    slots: [Option<CanFrame>; N],
    head: usize,
    len: usize,
}

impl<const N: usize> Default for TxQueue<N> {
    fn default() -> Self {
        Self {
            slots: [None; N],
            head: 0,
            len: 0,
        }
    }
}

impl<const N: usize> TxQueue<N> {
    /// Frames queued.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether nothing is queued.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Room left.
    pub fn free(&self) -> usize {
        N - self.len
    }

    /// Appends a frame; `false` (and nothing changes) when full.
    pub fn push_back(&mut self, frame: CanFrame) -> bool {
        if self.len == N {
            return false;
        }
        self.slots[(self.head + self.len) % N] = Some(frame);
        self.len += 1;
        true
    }

    /// Puts a frame back at the front (a frame the controller handed back); `false` when full.
    pub fn push_front(&mut self, frame: CanFrame) -> bool {
        if self.len == N {
            return false;
        }
        self.head = (self.head + N - 1) % N;
        self.slots[self.head] = Some(frame);
        self.len += 1;
        true
    }

    /// The oldest frame, left in place.
    pub fn front(&self) -> Option<&CanFrame> {
        if self.len == 0 {
            return None;
        }
        self.slots[self.head].as_ref()
    }

    /// Removes and returns the oldest frame.
    pub fn pop_front(&mut self) -> Option<CanFrame> {
        if self.len == 0 {
            return None;
        }
        let f = self.slots[self.head].take();
        self.head = (self.head + 1) % N;
        self.len -= 1;
        f
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use embedded_can::StandardId;

    fn frame(id: u16) -> CanFrame {
        CanFrame::new(StandardId::new(id).expect("11 bit"), &[id as u8]).expect("frame")
    }

    #[test]
    fn fifo_wraps_and_refuses_when_full() {
        let mut q = TxQueue::<3>::default();
        assert!(q.push_back(frame(1)) && q.push_back(frame(2)) && q.push_back(frame(3)));
        assert!(!q.push_back(frame(4)) && q.free() == 0);
        assert!(q.pop_front() == Some(frame(1)));
        assert!(q.push_back(frame(4)));
        assert!(q.pop_front() == Some(frame(2)));
        assert!(q.push_front(frame(9)));
        let order: Vec<_> = std::iter::from_fn(|| q.pop_front()).collect();
        assert!(order == [frame(9), frame(3), frame(4)]);
        assert!(q.is_empty() && q.front().is_none());
    }
}
