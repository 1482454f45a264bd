//! A bus monitor: a raw CAN socket in its own thread, every frame kept with its kernel receive
//! time (µs since the Unix epoch, the same base as `handctl record`'s log).

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, UNIX_EPOCH};

use hand_dbc::CanFrame;
use socketcan::{CanFilter, CanSocket, EmbeddedFrame, Socket, SocketOptions};

/// One frame the monitor saw.
#[derive(Debug, Clone)]
pub struct Seen {
    /// Kernel receive time, µs since the Unix epoch.
    pub time_us: u64,
    /// The data frame (None for an error frame).
    pub frame: Option<CanFrame>,
    /// When the monitor's read returned it, µs since the epoch (the wall clock, as
    /// [`now_us`]): a kernel stamp far from it tells a frame read late from one stamped late.
    pub read_us: u64,
    /// The monitor's socket it came from: 0 the first, one more at every reopen (the monitor
    /// reopens when the interface went down).
    pub socket: u32,
}

/// A running monitor.
#[derive(Debug)]
pub struct Monitor {
    seen: Arc<Mutex<Vec<Seen>>>,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

/// Kernel receive time of a socketcan timestamp, µs since the epoch.
pub fn epoch_us(t: std::time::SystemTime) -> u64 {
    t.duration_since(UNIX_EPOCH)
        .map(|d| d.as_micros() as u64)
        .unwrap_or(0)
}

/// The wall clock now, µs since the epoch (the base of kernel timestamps).
pub fn now_us() -> u64 {
    epoch_us(std::time::SystemTime::now())
}

impl Monitor {
    /// Starts watching `iface`. The monitor keeps reading across `ip link set down/up`.
    pub fn start(iface: &str) -> Self {
        let seen = Arc::new(Mutex::new(Vec::with_capacity(1 << 16)));
        let stop = Arc::new(AtomicBool::new(false));
        let sock = open(iface);
        let (s2, st2, name) = (Arc::clone(&seen), Arc::clone(&stop), iface.to_owned());
        let thread = std::thread::spawn(move || {
            let mut sock = Some(sock);
            let mut generation = 0;
            while !st2.load(Ordering::Relaxed) {
                let Some(s) = &sock else {
                    std::thread::sleep(Duration::from_millis(5));
                    sock = try_open(&name);
                    generation += u32::from(sock.is_some());
                    continue;
                };
                match s.read_frame_with_timestamp() {
                    Ok((f, ts)) => {
                        let read_us = now_us();
                        let frame = match f {
                            socketcan::CanFrame::Data(d) => CanFrame::new(d.id(), d.data()),
                            socketcan::CanFrame::Remote(r) => CanFrame::new_remote(r.id(), r.dlc()),
                            socketcan::CanFrame::Error(_) => None,
                        };
                        let mut v = s2.lock().unwrap_or_else(|e| e.into_inner());
                        v.push(Seen {
                            time_us: epoch_us(ts),
                            frame,
                            read_us,
                            socket: generation,
                        });
                    }
                    Err(e)
                        if matches!(
                            e.kind(),
                            std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                        ) => {}
                    // The interface went down: reopen when it is back.
                    Err(_) => sock = None,
                }
            }
        });
        Self {
            seen,
            stop,
            thread: Some(thread),
        }
    }

    /// A copy of everything seen so far.
    pub fn snapshot(&self) -> Vec<Seen> {
        self.seen.lock().unwrap_or_else(|e| e.into_inner()).clone()
    }

    /// Stops the thread and returns everything seen.
    pub fn finish(mut self) -> Vec<Seen> {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            t.join().expect("monitor thread");
        }
        self.snapshot()
    }
}

impl Drop for Monitor {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

fn try_open(iface: &str) -> Option<CanSocket> {
    let s = CanSocket::open(iface).ok()?;
    s.set_recv_timestamp(true).ok()?;
    s.set_error_filter_accept_all().ok()?;
    s.set_read_timeout(Duration::from_millis(20)).ok()?;
    Some(s)
}

fn open(iface: &str) -> CanSocket {
    try_open(iface).unwrap_or_else(|| panic!("monitor: cannot open a CAN socket on {iface:?}"))
}

/// A socket for writing test frames (floods, error frames) on `iface`.
pub fn writer(iface: &str) -> CanSocket {
    CanSocket::open(iface).unwrap_or_else(|e| panic!("cannot open {iface:?} for writing: {e}"))
}

/// A socket for a test's own reads on `iface` that queues only the standard data frames with
/// the ids in `ids`, with a read timeout of `timeout`.
///
/// A socket that takes every frame holds about 300 in its receive queue: the amplifier's 3000
/// frames/s fill that in 100 ms, and the guest's vCPUs stop for that long now and then (or the
/// test spawns a process meanwhile), after which the kernel drops every new frame, among them
/// the one a drill waits for (stop 38 failed on that). Filtered to one finger's 20 setpoints/s,
/// the same queue holds 15 s.
pub fn reader_of(iface: &str, ids: &[u32], timeout: Duration) -> CanSocket {
    // A standard id, neither extended nor a remote frame: the id bits, EFF and RTR compared.
    const MASK: u32 = 0x7FF | 0x8000_0000 | 0x4000_0000;
    let s = CanSocket::open(iface).unwrap_or_else(|e| panic!("cannot open {iface:?} to read: {e}"));
    let filters: Vec<CanFilter> = ids.iter().map(|&id| CanFilter::new(id, MASK)).collect();
    s.set_filters(&filters)
        .unwrap_or_else(|e| panic!("cannot filter the reader on {iface:?}: {e}"));
    s.set_read_timeout(timeout)
        .unwrap_or_else(|e| panic!("cannot set the reader's timeout on {iface:?}: {e}"));
    s
}
