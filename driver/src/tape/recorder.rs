//! The recorder: the engine's end puts entries in a bounded queue without waiting or
//! allocating; a thread (`handd-tape`) writes them to the file.
//!
//! The writer does not wait on the queue: it wakes every [`WRITE_EVERY`], writes what is there
//! and flushes, so the loop never pays for waking it. A full queue (a file system stalled
//! longer than the queue holds) loses entries, never a tick: every entry carries its number,
//! so the writer puts an [`Entry::Lost`] line exactly where entries are missing, and a replay
//! stops there.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{sync_channel, Receiver, SyncSender, TryRecvError};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::Duration;

use super::entry::{Entry, HEADER};

/// Entries the queue holds: about 10 s of a busy bus (3,250 frames/s and 140 tick entries/s),
/// so a writer starved by the real-time threads for seconds loses nothing (about 2.5 MB).
pub const QUEUE_ENTRIES: usize = 32_768;
/// How often the writer empties the queue into the file.
pub const WRITE_EVERY: Duration = Duration::from_millis(20);

/// The engine's end of a tape. Cloning it records the clone's entries too: a replay's engine
/// has none.
#[derive(Debug, Clone)]
pub struct Recorder {
    queue: SyncSender<(u64, Entry)>,
    next: u64,
    lost: u64,
}

impl Recorder {
    /// Queues `e`; it is lost if the queue is full or the writer is gone. Never blocks, never
    /// allocates.
    pub fn put(&mut self, e: Entry) {
        if self.queue.try_send((self.next, e)).is_err() {
            self.lost += 1;
        }
        self.next += 1;
    }

    /// Entries lost since the start.
    pub fn lost(&self) -> u64 {
        self.lost
    }
}

/// A recorder whose entries stay in its queue of `capacity` (no file, no writer): for tests
/// of what the engine's end does.
pub fn unwritten(capacity: usize) -> (Recorder, Receiver<(u64, Entry)>) {
    let (queue, rx) = sync_channel(capacity);
    (
        Recorder {
            queue,
            next: 0,
            lost: 0,
        },
        rx,
    )
}

/// Why a tape could not be started.
#[derive(Debug, thiserror::Error)]
pub enum RecorderError {
    /// The file could not be created.
    #[error("cannot create the tape {path}: {source}")]
    Create {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// The writer thread could not be started.
    #[error("cannot start the tape's writer thread: {0}")]
    Thread(#[source] std::io::Error),
}

/// The writer thread: [`TapeWriter::finish`] waits for it to write everything queued once every
/// [`Recorder`] is dropped.
pub struct TapeWriter {
    thread: JoinHandle<()>,
    failed: Arc<AtomicBool>,
}

impl TapeWriter {
    /// Waits for the writer (every recorder must be dropped first, or this waits for ever).
    /// True when everything reached the file.
    pub fn finish(self) -> bool {
        self.thread.join().is_ok() && !self.failed.load(Ordering::Relaxed)
    }
}

/// Creates the tape at `path` (replacing a file there) and starts its writer.
pub fn start(path: &Path) -> Result<(Recorder, TapeWriter), RecorderError> {
    let file = File::create(path).map_err(|source| RecorderError::Create {
        path: path.to_owned(),
        source,
    })?;
    let (queue, rx) = sync_channel(QUEUE_ENTRIES);
    let failed = Arc::new(AtomicBool::new(false));
    let (failed_w, path_w) = (Arc::clone(&failed), path.to_owned());
    let thread = std::thread::Builder::new()
        .name("handd-tape".into())
        .stack_size(crate::control::THREAD_STACK_BYTES)
        .spawn(move || {
            let mut out = BufWriter::with_capacity(64 * 1024, file);
            if let Err(e) = write_all(&mut out, &rx) {
                failed_w.store(true, Ordering::Relaxed);
                tracing::error!(path = %path_w.display(), error = %e, "tape: writing failed; the tape ends here");
            }
        })
        .map_err(RecorderError::Thread)?;
    let recorder = Recorder {
        queue,
        next: 0,
        lost: 0,
    };
    Ok((recorder, TapeWriter { thread, failed }))
}

fn write_all(out: &mut impl Write, rx: &Receiver<(u64, Entry)>) -> std::io::Result<()> {
    writeln!(out, "{HEADER}")?;
    let mut expected = 0;
    loop {
        let gone = loop {
            match rx.try_recv() {
                Ok((n, e)) => {
                    if n != expected {
                        writeln!(
                            out,
                            "{}",
                            Entry::Lost {
                                entries: n - expected
                            }
                        )?;
                    }
                    expected = n + 1;
                    writeln!(out, "{e}")?;
                }
                Err(TryRecvError::Empty) => break false,
                Err(TryRecvError::Disconnected) => break true,
            }
        };
        out.flush()?;
        if gone {
            return Ok(());
        }
        std::thread::sleep(WRITE_EVERY);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn what_the_recorder_puts_is_in_the_file_in_order_and_a_gap_is_marked_where_it_is() {
        let dir = std::env::temp_dir().join(format!("handstack-tape-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("dir");
        let path = dir.join("tape");
        let (mut rec, writer) = start(&path).expect("start");
        for t in 0..100 {
            rec.put(Entry::Validated { at_us: t });
        }
        // Three entries lost, as a full queue loses them.
        rec.next += 3;
        rec.put(Entry::NewEpoch);
        drop(rec);
        assert!(writer.finish(), "everything written");
        let text = std::fs::read_to_string(&path).expect("tape");
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines[0], HEADER);
        for t in 0..100 {
            assert_eq!(lines[1 + t], format!("V {t}"));
        }
        assert_eq!(&lines[101..], ["X 3", "N"]);
        std::fs::remove_dir_all(&dir).expect("clean up");
    }

    #[test]
    fn a_full_queue_loses_entries_without_blocking() {
        let (queue, rx) = sync_channel(2);
        let mut rec = Recorder {
            queue,
            next: 0,
            lost: 0,
        };
        for _ in 0..5 {
            rec.put(Entry::NewEpoch);
        }
        assert_eq!(rec.lost(), 3);
        let mut out = Vec::new();
        drop(rec);
        write_all(&mut out, &rx).expect("write");
        let text = String::from_utf8(out).expect("utf8");
        assert_eq!(text, format!("{HEADER}\nN\nN\n"));
    }
}
