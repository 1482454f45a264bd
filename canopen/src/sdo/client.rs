//! The expedited SDO client: one transfer at a time per drive, a deadline from the caller's
//! `now`, every way a transfer can fail named.

use super::abort::AbortCode;
use super::codec::{SdoData, SdoFrameError, SdoReply, SdoRequest};
use crate::frame::CanFrame;
use crate::ids::{NodeId, ObjectAddr};
use thiserror::Error;

/// How an SDO transfer failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Error)]
pub enum SdoError {
    /// A transfer is already in progress on this client.
    #[error("{node}: SDO client busy with {addr}")]
    Busy {
        /// The drive.
        node: NodeId,
        /// The object of the transfer in progress.
        addr: ObjectAddr,
    },
    /// No reply before the deadline.
    #[error("{node}: SDO {addr} timed out after {timeout_us} us")]
    Timeout {
        /// The drive.
        node: NodeId,
        /// The object.
        addr: ObjectAddr,
        /// The timeout.
        timeout_us: u64,
    },
    /// The server aborted the transfer.
    #[error("{node}: SDO {addr} aborted: {code}")]
    Aborted {
        /// The drive.
        node: NodeId,
        /// The object.
        addr: ObjectAddr,
        /// The abort code, named.
        code: AbortCode,
    },
    /// The reply could not be decoded.
    #[error("{node}: malformed SDO reply for {addr}: {error}")]
    Malformed {
        /// The drive.
        node: NodeId,
        /// The object of the transfer.
        addr: ObjectAddr,
        /// What was wrong.
        error: SdoFrameError,
    },
    /// The reply echoed another index/subindex than requested.
    #[error("{node}: SDO reply for {got}, expected {expected}")]
    WrongObject {
        /// The drive.
        node: NodeId,
        /// The object requested.
        expected: ObjectAddr,
        /// The object in the reply.
        got: ObjectAddr,
    },
    /// A download confirmation to an upload, or data to a download.
    #[error("{node}: SDO reply for {addr} does not match the request (upload/download)")]
    Mismatch {
        /// The drive.
        node: NodeId,
        /// The object.
        addr: ObjectAddr,
    },
}

/// A finished transfer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SdoDone {
    /// An upload's data.
    Uploaded(SdoData),
    /// A download confirmed.
    Downloaded,
}

#[derive(Clone, Copy, Debug)]
struct Pending {
    request: SdoRequest,
    deadline_us: u64,
}

/// An expedited SDO client for one server node.
#[derive(Clone, Debug)]
pub struct SdoClient {
    node: NodeId,
    timeout_us: u64,
    pending: Option<Pending>,
    /// The object of the last transfer given up (cancelled or timed out): its server may still
    /// answer it, and that late reply belongs to no transfer in flight.
    given_up: Option<ObjectAddr>,
}

impl SdoClient {
    /// A client for `node` with a per-transfer timeout.
    pub fn new(node: NodeId, timeout_us: u64) -> Self {
        Self {
            node,
            timeout_us,
            pending: None,
            given_up: None,
        }
    }

    /// Forgets the transfer in flight, if any: its server rebooted. A reply to it that still
    /// comes (sent before the reboot, or to a request the server had queued) is ignored once,
    /// where it does not fit the transfer then in flight.
    pub fn cancel(&mut self) {
        if let Some(p) = self.pending.take() {
            self.given_up = Some(p.request.addr());
        }
    }

    /// The server node.
    pub fn node(&self) -> NodeId {
        self.node
    }

    /// Whether a transfer is in progress.
    pub fn is_busy(&self) -> bool {
        self.pending.is_some()
    }

    /// Starts an upload of `addr`; the frame to send.
    pub fn upload(&mut self, addr: ObjectAddr, now_us: u64) -> Result<CanFrame, SdoError> {
        self.start(SdoRequest::Upload(addr), now_us)
    }

    /// Starts an expedited download of `data` to `addr`; the frame to send.
    pub fn download(
        &mut self,
        addr: ObjectAddr,
        data: SdoData,
        now_us: u64,
    ) -> Result<CanFrame, SdoError> {
        self.start(SdoRequest::Download(addr, data), now_us)
    }

    fn start(&mut self, request: SdoRequest, now_us: u64) -> Result<CanFrame, SdoError> {
        if let Some(p) = self.pending {
            return Err(SdoError::Busy {
                node: self.node,
                addr: p.request.addr(),
            });
        }
        self.pending = Some(Pending {
            request,
            deadline_us: now_us.saturating_add(self.timeout_us),
        });
        Ok(request.frame(self.node))
    }

    /// Offers a received frame. `None` if it is not this server's SDO reply, no transfer is in
    /// progress, or it is the late reply to a transfer given up ([`SdoClient::cancel`], a
    /// timeout) that does not fit the one in flight (ignored once; the transfer goes on);
    /// otherwise the transfer's end.
    pub fn on_frame(&mut self, f: &CanFrame) -> Option<Result<SdoDone, SdoError>> {
        if f.cob_id() != 0x580 + u16::from(self.node.get()) {
            return None;
        }
        let p = self.pending.take()?;
        let result = self.finish(p, f);
        if let Some(late) = self.given_up {
            let stale = match &result {
                Err(SdoError::WrongObject { got, .. }) => *got == late,
                Err(SdoError::Mismatch { addr, .. }) => *addr == late,
                _ => false,
            };
            if stale {
                self.given_up = None;
                self.pending = Some(p);
                return None;
            }
        }
        Some(result)
    }

    /// The end of transfer `p` on reply `f` (this server's).
    fn finish(&self, p: Pending, f: &CanFrame) -> Result<SdoDone, SdoError> {
        let node = self.node;
        let expected = p.request.addr();
        let reply = match SdoReply::decode(f, node) {
            Ok(r) => r,
            Err(error) => {
                return Err(SdoError::Malformed {
                    node,
                    addr: expected,
                    error,
                })
            }
        };
        if reply.addr() != expected {
            return Err(SdoError::WrongObject {
                node,
                expected,
                got: reply.addr(),
            });
        }
        match (p.request, reply) {
            (_, SdoReply::Abort(addr, code)) => Err(SdoError::Aborted { node, addr, code }),
            (SdoRequest::Upload(_), SdoReply::Uploaded(_, d)) => Ok(SdoDone::Uploaded(d)),
            (SdoRequest::Download(..), SdoReply::Downloaded(_)) => Ok(SdoDone::Downloaded),
            _ => Err(SdoError::Mismatch {
                node,
                addr: expected,
            }),
        }
    }

    /// Checks the deadline: on timeout, the error and the abort frame (0x0504_0000) to send.
    pub fn poll(&mut self, now_us: u64) -> Option<(SdoError, CanFrame)> {
        let p = self.pending?;
        if now_us < p.deadline_us {
            return None;
        }
        self.pending = None;
        let addr = p.request.addr();
        self.given_up = Some(addr);
        let abort = SdoRequest::Abort(addr, AbortCode::Timeout).frame(self.node);
        Some((
            SdoError::Timeout {
                node: self.node,
                addr,
                timeout_us: self.timeout_us,
            },
            abort,
        ))
    }
}
