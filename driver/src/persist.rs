//! Latches that survive a restart of handd: the latched faults (E-stop, bus-off, a
//! technician's `stop`, the calibrating hold, a swapped model waiting for `arm`, ...) and the
//! calibrating hold are kept in `<state_dir>/latches`, so a crash, a panic or a watchdog kill
//! (systemd restarts handd 1 s later) never undoes a stop.
//!
//! ## What is kept and how
//! - Every latched fault except `no_model` (which the start derives from the model file), and
//!   the calibrating hold (`calibrating`, or `deployed` once a model came after it).
//! - The loop never touches the file. Each tick it publishes the latch set into an atomic word
//!   and, when it changed, wakes the writer thread with a `try_send` on a one-slot channel
//!   ([`LatchPublisher::publish`]: no lock, no allocation, no waiting). The writer thread
//!   (`handd-latches`) replaces the file atomically (temporary file, fsync, rename, fsync of
//!   the directory): a crash leaves the old set or the new one, never a mix. A failed write is
//!   logged and retried every second.
//! - `handctl stop` answers only once its latch is on disk ([`LatchStore::wait_written`]), or
//!   says plainly that it could not confirm it. `handctl arm` clears the engine's latches and
//!   the loop publishes the empty set, so the file is cleared as well.
//!
//! ## At start
//! - No file (the first start on a board): nothing latched.
//! - A file that reads: handd starts SAFE with those latches. Each needs `handctl arm` as it
//!   did before the restart; the calibrating hold needs a deploy (or rollback) and then `arm`.
//! - A file that cannot be read or does not parse: handd starts SAFE with `stop_requested`
//!   latched, and the log says why. It never guesses "nothing latched".
//!
//! ## A restart with nothing latched resumes
//! When the file holds no latch, the restarted handd starts as on a first boot: READY after the
//! config, the model and the bus are validated, RUNNING on the first valid window with no fault
//! in force, in fresh setpoint epochs (every finger gets a SAFE_STOP first, so nothing the old
//! process queued can move it), each finger's gains ramping in from rest. From the patient's
//! side: the alternative, a `restarted` latch, turns every crash into a hand that stays dead
//! until a technician comes, which may be days for someone at home, and a prosthesis that
//! cannot open releases nothing it holds. A crash with nothing latched interrupted normal use;
//! the safety a latch gives (a stop undone, a calibration interrupted) is exactly what the file
//! keeps. The fingers' own controllers brake 150 ms after the last setpoint, so the hand is
//! held still for the ~1.3 s the restart takes, and every restart is in the journal.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc::{sync_channel, Receiver, RecvTimeoutError, SyncSender};
use std::sync::{Arc, Condvar, Mutex};
use std::time::Duration;

use crate::engine::Hold;
use crate::safety::{Fault, FaultSet};

/// The file's name inside the state directory.
pub const LATCH_FILE: &str = "latches";

/// How long `handctl stop` waits for its latch to reach the disk.
pub const STOP_SAVE_WAIT: Duration = Duration::from_secs(1);

/// How often the writer retries a failed write.
const RETRY: Duration = Duration::from_secs(1);

/// The file's first line: its format.
const HEADER: &str = "handd-latches 1";

/// What survives a restart.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Latches {
    /// The latched faults kept (never `no_model`).
    pub faults: FaultSet,
    /// The calibrating hold.
    pub hold: Hold,
}

/// The faults kept across a restart: every latched one but `no_model`.
pub fn kept(f: Fault) -> bool {
    f.is_latched() && f != Fault::NoModel
}

impl Latches {
    /// The latches kept of `latched` (faults that are not kept are left out) and `hold`.
    pub fn of(latched: FaultSet, hold: Hold) -> Self {
        let mut faults = FaultSet::default();
        for f in latched.iter().filter(|f| kept(*f)) {
            faults.insert(f);
        }
        Self { faults, hold }
    }

    /// Whether nothing is latched.
    pub fn is_empty(self) -> bool {
        self.faults.is_empty() && self.hold == Hold::Free
    }

    /// One word: fault bits 0-15, hold bits 16-17, bit 31 set (so 0 means "none yet").
    fn code(self) -> u32 {
        let hold = match self.hold {
            Hold::Free => 0,
            Hold::Calibrating => 1,
            Hold::Deployed => 2,
        };
        u32::from(self.faults.0) | (hold << 16) | (1 << 31)
    }

    fn from_code(code: u32) -> Option<Self> {
        if code & (1 << 31) == 0 {
            return None;
        }
        let hold = match (code >> 16) & 3 {
            1 => Hold::Calibrating,
            2 => Hold::Deployed,
            _ => Hold::Free,
        };
        Some(Self {
            faults: FaultSet(code as u16),
            hold,
        })
    }

    /// The file's text.
    pub fn to_text(self) -> String {
        let hold = match self.hold {
            Hold::Free => "free",
            Hold::Calibrating => "calibrating",
            Hold::Deployed => "deployed",
        };
        let faults: Vec<&str> = self.faults.iter().map(Fault::name).collect();
        format!(
            "{HEADER}\n# Written by handd whenever its latches change; read at start. \
             `handctl arm` clears them.\nlatched={}\nhold={hold}\n",
            faults.join(",")
        )
    }

    /// Parses the file's text; every line must be known, each key present once.
    pub fn from_text(text: &str) -> Result<Self, String> {
        let mut lines = text
            .lines()
            .filter(|l| !l.trim().is_empty() && !l.starts_with('#'));
        if lines.next() != Some(HEADER) {
            return Err(format!("its first line is not {HEADER:?}"));
        }
        let (mut faults, mut hold) = (None, None);
        for line in lines {
            let (key, value) = line
                .split_once('=')
                .ok_or_else(|| format!("line {line:?} is not key=value"))?;
            match key {
                "latched" if faults.is_none() => {
                    let mut set = FaultSet::default();
                    for name in value.split(',').filter(|n| !n.is_empty()) {
                        let f = Fault::ALL
                            .into_iter()
                            .find(|f| f.name() == name && kept(*f))
                            .ok_or_else(|| format!("{name:?} is not a latch handd keeps"))?;
                        set.insert(f);
                    }
                    faults = Some(set);
                }
                "hold" if hold.is_none() => {
                    hold = Some(match value {
                        "free" => Hold::Free,
                        "calibrating" => Hold::Calibrating,
                        "deployed" => Hold::Deployed,
                        other => {
                            return Err(format!(
                                "hold={other:?} is not free, calibrating or deployed"
                            ))
                        }
                    });
                }
                _ => return Err(format!("line {line:?}: unknown or repeated key")),
            }
        }
        match (faults, hold) {
            (Some(faults), Some(hold)) => Ok(Self { faults, hold }),
            _ => Err("the latched= or the hold= line is missing".into()),
        }
    }
}

/// Why the latches could not be read or written.
#[derive(Debug, thiserror::Error)]
pub enum PersistError {
    /// The file exists but could not be read.
    #[error("{path}: {source}")]
    Read {
        /// The file.
        path: PathBuf,
        /// The cause.
        #[source]
        source: std::io::Error,
    },
    /// The file does not parse.
    #[error("{path}: {what}")]
    Corrupt {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        what: String,
    },
    /// The file could not be replaced.
    #[error("could not save the latches: {0}")]
    Write(#[from] decoder::fsio::WriteError),
    /// The state directory could not be made.
    #[error("could not make the state directory {path}: {source}")]
    Dir {
        /// The directory.
        path: PathBuf,
        /// The cause.
        #[source]
        source: std::io::Error,
    },
}

/// What the start found in the file.
#[derive(Debug)]
pub enum Restored {
    /// No file: the first start.
    Missing,
    /// The file's latches.
    Read(Latches),
    /// The file is unreadable or corrupt: start with `stop_requested` (see [`Restored::latches`]).
    Unusable(PersistError),
}

impl Restored {
    /// The latches to start with: none, the file's, or `stop_requested` for a file that could
    /// not be used.
    pub fn latches(&self) -> Latches {
        match self {
            Restored::Missing => Latches::default(),
            Restored::Read(l) => *l,
            Restored::Unusable(_) => {
                let mut faults = FaultSet::default();
                faults.insert(Fault::StopRequested);
                Latches {
                    faults,
                    hold: Hold::Free,
                }
            }
        }
    }

    /// What is on disk now (None when nothing usable is).
    pub fn on_disk(&self) -> Option<Latches> {
        match self {
            Restored::Read(l) => Some(*l),
            _ => None,
        }
    }

    /// Logs what the start found.
    pub fn log(&self, path: &Path) {
        match self {
            Restored::Missing => {
                tracing::info!(path = %path.display(), "no latch file: nothing latched (first start)")
            }
            Restored::Read(l) if l.is_empty() => {
                tracing::info!(path = %path.display(), "latch file: nothing latched; resuming")
            }
            Restored::Read(l) => tracing::warn!(
                path = %path.display(),
                latched = %l.faults,
                hold = ?l.hold,
                "latches restored: the hand stays SAFE until `handctl arm` (a deploy first for the calibrating hold)"
            ),
            Restored::Unusable(e) => tracing::error!(
                error = %e,
                "the latch file cannot be used: starting SAFE with stop_requested latched; check the hand, then `handctl arm`"
            ),
        }
    }
}

/// The latch file in `state_dir`.
pub fn latch_path(state_dir: &Path) -> PathBuf {
    state_dir.join(LATCH_FILE)
}

/// Reads the latch file at `path`.
pub fn load(path: &Path) -> Restored {
    match std::fs::read(path) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Restored::Missing,
        Err(source) => Restored::Unusable(PersistError::Read {
            path: path.to_owned(),
            source,
        }),
        Ok(bytes) => {
            let parsed = std::str::from_utf8(&bytes)
                .map_err(|_| "it is not UTF-8 text".to_owned())
                .and_then(Latches::from_text);
            match parsed {
                Ok(l) => Restored::Read(l),
                Err(what) => Restored::Unusable(PersistError::Corrupt {
                    path: path.to_owned(),
                    what,
                }),
            }
        }
    }
}

/// Replaces the latch file at `path` with `l`, atomically (making its directory if needed).
pub fn save(path: &Path, l: Latches) -> Result<(), PersistError> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|source| PersistError::Dir {
            path: dir.to_owned(),
            source,
        })?;
    }
    decoder::fsio::write_atomic(path, l.to_text().as_bytes())?;
    Ok(())
}

struct Shared {
    /// The newest latch set the loop published: its publication number in the high word, its
    /// [`Latches::code`] in the low word (0: none yet).
    pending: AtomicU64,
    /// What the file holds, when known.
    written: Mutex<Written>,
    saved: Condvar,
}

/// What the file holds: its code, and the newest publication it answers. The number, not the
/// code, tells a flush that its set is on disk: a set published, replaced and published again
/// (stop, then arm) has the old code while the write of the set between may still be under way.
#[derive(Clone, Copy)]
struct Written {
    code: Option<u32>,
    publication: u32,
}

fn pack(publication: u32, code: u32) -> u64 {
    (u64::from(publication) << 32) | u64::from(code)
}

fn unpack(word: u64) -> (u32, u32) {
    ((word >> 32) as u32, word as u32)
}

/// The loop's end: publishes the latch set without a lock or an allocation.
pub struct LatchPublisher {
    shared: Arc<Shared>,
    wake: SyncSender<()>,
    last: u32,
    publication: u32,
}

impl LatchPublisher {
    /// Publishes `l`; wakes the writer when it changed. Never blocks.
    pub fn publish(&mut self, l: Latches) {
        let code = l.code();
        if code == self.last {
            return;
        }
        self.last = code;
        self.publication = self.publication.wrapping_add(1);
        self.shared
            .pending
            .store(pack(self.publication, code), Ordering::Release);
        // A full slot means a wake-up is already pending: the writer reads the newest word.
        let _ = self.wake.try_send(());
    }

    /// Waits up to `timeout` for the last published set to be on disk (at shutdown, not in
    /// the tick); true when it is.
    pub fn flush(&self, timeout: Duration) -> bool {
        let _ = self.wake.try_send(());
        let publication = self.publication;
        LatchStore {
            shared: Arc::clone(&self.shared),
            path: PathBuf::new(),
        }
        .wait(|w| w.publication == publication, timeout)
    }
}

/// The control side's view: what the file holds, and a wait for a latch to reach it.
#[derive(Clone)]
pub struct LatchStore {
    shared: Arc<Shared>,
    path: PathBuf,
}

impl LatchStore {
    /// The file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// What the file holds, when known.
    pub fn on_disk(&self) -> Option<Latches> {
        let w = *self
            .shared
            .written
            .lock()
            .unwrap_or_else(|e| e.into_inner());
        w.code.and_then(Latches::from_code)
    }

    fn wait(&self, done: impl Fn(Written) -> bool, timeout: Duration) -> bool {
        let guard = self
            .shared
            .written
            .lock()
            .unwrap_or_else(|e| e.into_inner());
        let (guard, _) = self
            .shared
            .saved
            .wait_timeout_while(guard, timeout, |w| !done(*w))
            .unwrap_or_else(|e| e.into_inner());
        done(*guard)
    }

    /// Waits up to `timeout` until the file holds a set for which `done` is true.
    pub fn wait_written(&self, done: impl Fn(Latches) -> bool, timeout: Duration) -> bool {
        self.wait(
            |w| w.code.and_then(Latches::from_code).is_some_and(&done),
            timeout,
        )
    }
}

/// The writer's end, before it runs: [`LatchWriter::spawn`] starts its thread.
pub struct LatchWriter {
    path: PathBuf,
    shared: Arc<Shared>,
    wake: Receiver<()>,
}

impl LatchWriter {
    /// Starts the writer thread (`handd-latches`); it ends when the publisher is dropped,
    /// after a last write.
    pub fn spawn(self) -> std::io::Result<()> {
        std::thread::Builder::new()
            .name("handd-latches".into())
            // Small, like the control threads: locked memory makes a stack resident in full.
            .stack_size(crate::control::THREAD_STACK_BYTES)
            .spawn(move || writer(&self.path, &self.shared, &self.wake))?;
        Ok(())
    }
}

/// The three ends for the file at `path`, which holds `on_disk` now (None when it is missing
/// or unusable: the first published set is then written): the loop's, the control side's and
/// the writer's (not started).
pub fn latch_channel(
    path: PathBuf,
    on_disk: Option<Latches>,
) -> (LatchPublisher, LatchStore, LatchWriter) {
    let shared = Arc::new(Shared {
        pending: AtomicU64::new(0),
        written: Mutex::new(Written {
            code: on_disk.map(Latches::code),
            publication: 0,
        }),
        saved: Condvar::new(),
    });
    let (wake, rx) = sync_channel(1);
    (
        LatchPublisher {
            shared: Arc::clone(&shared),
            wake,
            last: 0,
            publication: 0,
        },
        LatchStore {
            shared: Arc::clone(&shared),
            path: path.clone(),
        },
        LatchWriter {
            path,
            shared,
            wake: rx,
        },
    )
}

/// [`latch_channel`] with its writer thread started: the loop's and the control side's ends.
pub fn spawn_writer(
    path: PathBuf,
    on_disk: Option<Latches>,
) -> std::io::Result<(LatchPublisher, LatchStore)> {
    let (publisher, store, writer) = latch_channel(path, on_disk);
    writer.spawn()?;
    Ok((publisher, store))
}

fn writer(path: &Path, shared: &Shared, wake: &Receiver<()>) {
    let mut failing = false;
    loop {
        let gone = matches!(
            wake.recv_timeout(RETRY),
            Err(RecvTimeoutError::Disconnected)
        );
        let (publication, code) = unpack(shared.pending.load(Ordering::Acquire));
        let known = shared
            .written
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .code;
        let Some(l) = Latches::from_code(code) else {
            if gone {
                return;
            }
            continue;
        };
        // One writer: when it reads the word, no write of its own is under way, so a file that
        // already holds this set answers this publication without a write.
        let result = if known == Some(code) {
            Ok(())
        } else {
            save(path, l)
        };
        match result {
            Ok(()) => {
                *shared.written.lock().unwrap_or_else(|e| e.into_inner()) = Written {
                    code: Some(code),
                    publication,
                };
                shared.saved.notify_all();
                if failing {
                    tracing::info!(path = %path.display(), "latches saved again");
                }
                if known != Some(code) {
                    tracing::debug!(path = %path.display(), latched = %l.faults, hold = ?l.hold, "latches saved");
                }
                failing = false;
            }
            Err(e) => {
                if !failing {
                    tracing::error!(error = %e, "latches NOT saved: a restart may not keep them; retrying every second");
                }
                failing = true;
            }
        }
        if gone {
            return;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("handd-persist-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).expect("scratch directory");
        d
    }

    fn set(faults: &[Fault]) -> FaultSet {
        let mut s = FaultSet::default();
        for f in faults {
            s.insert(*f);
        }
        s
    }

    #[test]
    fn latches_round_trip_through_the_file() {
        let dir = scratch("round");
        let path = latch_path(&dir);
        assert!(matches!(load(&path), Restored::Missing));
        assert!(load(&path).latches().is_empty(), "no file: nothing latched");
        for l in [
            Latches::default(),
            Latches::of(set(&[Fault::EStop, Fault::StopRequested]), Hold::Free),
            Latches::of(set(&[Fault::Calibrating]), Hold::Calibrating),
            Latches::of(
                set(&[Fault::Calibrating, Fault::ModelSwapped]),
                Hold::Deployed,
            ),
        ] {
            save(&path, l).expect("saved");
            match load(&path) {
                Restored::Read(back) => assert_eq!(back, l),
                other => panic!("{other:?}"),
            }
            assert_eq!(Latches::from_code(l.code()), Some(l));
        }
        // Transient faults and no_model are never kept.
        let l = Latches::of(
            set(&[Fault::EmgSilence, Fault::NoModel, Fault::BusOff]),
            Hold::Free,
        );
        assert_eq!(l.faults, set(&[Fault::BusOff]));
        std::fs::remove_dir_all(&dir).expect("clean up");
    }

    #[test]
    fn a_save_replaces_the_file_atomically_and_leaves_no_temporary() {
        let dir = scratch("atomic");
        let path = latch_path(&dir);
        save(&path, Latches::of(set(&[Fault::EStop]), Hold::Free)).expect("first");
        let ino = |p: &Path| {
            std::os::unix::fs::MetadataExt::ino(&std::fs::metadata(p).expect("metadata"))
        };
        let before = ino(&path);
        save(&path, Latches::default()).expect("second");
        assert_ne!(
            ino(&path),
            before,
            "a new file renamed over the old one, not rewritten in place"
        );
        let names: Vec<_> = std::fs::read_dir(&dir)
            .expect("listing")
            .map(|e| e.expect("entry").file_name())
            .collect();
        assert_eq!(
            names,
            vec![std::ffi::OsString::from(LATCH_FILE)],
            "no temporary left"
        );
        assert!(load(&path).latches().is_empty());
        std::fs::remove_dir_all(&dir).expect("clean up");
    }

    #[test]
    fn a_corrupt_or_unreadable_file_starts_with_stop_requested() {
        let dir = scratch("corrupt");
        let path = latch_path(&dir);
        for text in [
            &b""[..],
            b"handd-latches 1\nlatched=estop\n",
            b"handd-latches 1\nlatched=estop,bogus\nhold=free\n",
            b"handd-latches 1\nlatched=emg_silence\nhold=free\n",
            b"handd-latches 1\nlatched=\nhold=free\nhold=free\n",
            b"handd-latches 2\nlatched=\nhold=free\n",
            b"\xff\xfe",
        ] {
            std::fs::write(&path, text).expect("write");
            let r = load(&path);
            assert!(
                matches!(r, Restored::Unusable(PersistError::Corrupt { .. })),
                "{text:?}: {r:?}"
            );
            assert_eq!(r.latches().faults, set(&[Fault::StopRequested]), "{text:?}");
            assert_eq!(r.on_disk(), None);
        }
        // A directory where the file should be cannot be read.
        std::fs::remove_file(&path).expect("remove");
        std::fs::create_dir(&path).expect("a directory in its place");
        let r = load(&path);
        assert!(
            matches!(r, Restored::Unusable(PersistError::Read { .. })),
            "{r:?}"
        );
        assert_eq!(r.latches().faults, set(&[Fault::StopRequested]));
        std::fs::remove_dir_all(&dir).expect("clean up");
    }

    #[test]
    fn the_writer_saves_what_the_loop_publishes() {
        let dir = scratch("writer");
        let path = latch_path(&dir);
        let (mut publisher, store) = spawn_writer(path.clone(), None).expect("writer");
        let stop = Latches::of(set(&[Fault::StopRequested]), Hold::Free);
        publisher.publish(stop);
        assert!(store.wait_written(|l| l == stop, Duration::from_secs(5)));
        assert_eq!(load(&path).on_disk(), Some(stop));
        publisher.publish(Latches::default());
        assert!(
            publisher.flush(Duration::from_secs(5)),
            "the cleared set reaches the disk"
        );
        assert_eq!(load(&path).on_disk(), Some(Latches::default()));
        assert_eq!(store.on_disk(), Some(Latches::default()));
        drop(publisher);
        std::fs::remove_dir_all(&dir).expect("clean up");
    }

    #[test]
    fn a_flush_waits_for_its_own_publication_not_for_an_equal_older_set() {
        // The file holds the empty set; a stop and an arm are published before the writer
        // runs. The file's code equals the newest set, yet the stop's write may come first, so
        // the flush must wait for the writer (CI saw the stop land after such a flush).
        let dir = scratch("aba");
        let path = latch_path(&dir);
        save(&path, Latches::default()).expect("save");
        let (mut publisher, store, writer) = latch_channel(path.clone(), Some(Latches::default()));
        publisher.publish(Latches::of(set(&[Fault::StopRequested]), Hold::Free));
        publisher.publish(Latches::default());
        assert!(
            !publisher.flush(Duration::from_millis(50)),
            "no writer ran: the flush cannot be confirmed"
        );
        writer.spawn().expect("writer");
        assert!(publisher.flush(Duration::from_secs(5)));
        assert_eq!(load(&path).on_disk(), Some(Latches::default()));
        assert_eq!(store.on_disk(), Some(Latches::default()));
        drop(publisher);
        std::fs::remove_dir_all(&dir).expect("clean up");
    }
}
