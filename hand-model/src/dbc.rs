//! TEMPORARY stand-in until hand-dbc exports CanFrame and the messages.
#![allow(missing_docs)]

use embedded_can::{Frame, Id};

pub const EMG_LSB_UV: f64 = 2.5;

#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct CanFrame {
    id: Id,
    dlc: u8,
    data: [u8; 8],
}

impl Frame for CanFrame {
    fn new(id: impl Into<Id>, data: &[u8]) -> Option<Self> {
        if data.len() > 8 {
            return None;
        }
        let mut d = [0; 8];
        d[..data.len()].copy_from_slice(data);
        Some(Self {
            id: id.into(),
            dlc: data.len() as u8,
            data: d,
        })
    }
    fn new_remote(_id: impl Into<Id>, _dlc: usize) -> Option<Self> {
        None
    }
    fn is_extended(&self) -> bool {
        matches!(self.id, Id::Extended(_))
    }
    fn is_remote_frame(&self) -> bool {
        false
    }
    fn id(&self) -> Id {
        self.id
    }
    fn dlc(&self) -> usize {
        self.dlc as usize
    }
    fn data(&self) -> &[u8] {
        &self.data[..self.dlc as usize]
    }
}
