//! Atomic file replacement, the one implementation behind every file the stack rewrites in
//! place (handd's config, model files, session metadata and sample files): a temporary file in
//! the same directory, written and fsynced, renamed over the target, then the directory
//! fsynced. A crash at any point leaves either the old file or the new one, never a mix, and
//! a failure leaves no temporary file behind.
//!
//! A writer killed mid-save still leaves its temporary (`.<name>.tmp.<pid>.<seq>`):
//! [`remove_stale_temps`] removes those whose writer is gone, and [`temp_file_pid`] recognises
//! them, so the name pattern lives here only.

use std::ffi::OsStr;
use std::fs::{self, File};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// A step of an atomic write failed.
#[derive(Debug, thiserror::Error)]
#[error("{op} {path}: {source}")]
pub struct WriteError {
    /// What was being done ("create", "write", "fsync", "rename into", "fsync directory";
    /// "list" and "remove" when cleaning up after killed writers).
    pub op: &'static str,
    /// The file concerned (the temporary file, the target or its directory).
    pub path: PathBuf,
    /// What the OS said.
    #[source]
    pub source: std::io::Error,
}

fn step<'a>(op: &'static str, path: &'a Path) -> impl FnOnce(std::io::Error) -> WriteError + 'a {
    move |source| WriteError {
        op,
        path: path.to_path_buf(),
        source,
    }
}

/// What every temporary name of an atomic write to a file named `name` starts with; the
/// writer's PID and a per-process sequence number follow, separated by a dot.
fn temp_prefix(name: &OsStr) -> String {
    format!(".{}.tmp.", name.to_string_lossy())
}

/// The directory `path` is in ("." for a bare file name).
fn dir_of(path: &Path) -> PathBuf {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// The temporary file beside `path`: hidden, and unique per process and call, so concurrent
/// writers never share one.
fn temp_path(dir: &Path, path: &Path) -> Result<PathBuf, WriteError> {
    static SEQ: AtomicU64 = AtomicU64::new(0);
    let name = path.file_name().ok_or_else(|| WriteError {
        op: "name",
        path: path.to_path_buf(),
        source: std::io::Error::new(std::io::ErrorKind::InvalidInput, "no file name"),
    })?;
    Ok(dir.join(format!(
        "{}{}.{}",
        temp_prefix(name),
        std::process::id(),
        SEQ.fetch_add(1, Ordering::Relaxed)
    )))
}

/// A non-empty run of ASCII digits, as a number.
fn digits<T: std::str::FromStr>(s: &str) -> Option<T> {
    let all_digits = !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
    all_digits.then(|| s.parse().ok()).flatten()
}

/// If `file_name` is the temporary of an atomic write to a file named `target_name`, the PID of
/// the process that wrote it.
pub fn temp_file_pid(target_name: &OsStr, file_name: &OsStr) -> Option<u32> {
    let rest = file_name
        .to_str()?
        .strip_prefix(&temp_prefix(target_name))?;
    let (pid, seq) = rest.split_once('.')?;
    digits::<u64>(seq)?;
    digits(pid)
}

/// Whether process `pid` exists. Where `/proc` is not mounted every process counts as alive,
/// so that nothing is removed on a guess.
pub fn process_alive(pid: u32) -> bool {
    let proc = Path::new("/proc");
    !proc.join("self").exists() || proc.join(pid.to_string()).exists()
}

/// A temporary file of an interrupted atomic write, removed by [`remove_stale_temps`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct StaleTemp {
    /// The temporary file.
    pub path: PathBuf,
    /// The PID of its writer, no longer a live process.
    pub pid: u32,
}

/// Removes the temporaries that atomic writes to `path` left behind when their writer was
/// killed mid-save: those whose writer PID is no live process ([`process_alive`]); a live
/// writer's temporary is left alone. Returns what was removed. A missing directory has none.
pub fn remove_stale_temps(path: &Path) -> Result<Vec<StaleTemp>, WriteError> {
    let Some(name) = path.file_name() else {
        return Ok(Vec::new());
    };
    let dir = dir_of(path);
    let entries = match fs::read_dir(&dir) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Vec::new()),
        r => r.map_err(step("list", &dir))?,
    };
    let mut removed = Vec::new();
    for entry in entries {
        let entry = entry.map_err(step("list", &dir))?;
        let Some(pid) = temp_file_pid(name, &entry.file_name()) else {
            continue;
        };
        if process_alive(pid) {
            continue;
        }
        let tmp = entry.path();
        match fs::remove_file(&tmp) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
                return Err(step("remove", &tmp)(e));
            }
            _ => removed.push(StaleTemp { path: tmp, pid }),
        }
    }
    Ok(removed)
}

/// Replaces `path` with `bytes` atomically (see the module doc).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), WriteError> {
    write_atomic_with(path, |f| f.write_all(bytes))
}

/// Replaces `path` atomically with what `fill` writes into the temporary file; an error from
/// `fill` (reported as the "write" step) leaves the old file as it was.
pub fn write_atomic_with(
    path: &Path,
    fill: impl FnOnce(&mut File) -> std::io::Result<()>,
) -> Result<(), WriteError> {
    let dir = dir_of(path);
    let tmp = temp_path(&dir, path)?;
    let write = || -> Result<(), WriteError> {
        let mut f = File::create(&tmp).map_err(step("create", &tmp))?;
        // The file replaced keeps its permissions: a config installed 0640 stays 0640 after a
        // rewrite (the temporary was created by the process's umask, 0644 under systemd).
        if let Ok(old) = fs::metadata(path) {
            f.set_permissions(old.permissions())
                .map_err(step("set the permissions of", &tmp))?;
        }
        fill(&mut f).map_err(step("write", &tmp))?;
        f.sync_all().map_err(step("fsync", &tmp))?;
        drop(f);
        fs::rename(&tmp, path).map_err(step("rename into", path))?;
        File::open(&dir)
            .and_then(|d| d.sync_all())
            .map_err(step("fsync directory", &dir))
    };
    let result = write();
    if result.is_err() {
        // Best effort: never leave a stray temporary behind; the original error matters more.
        let _ = fs::remove_file(&tmp);
    }
    result
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("fsio-{name}-{}", std::process::id()));
        let _ = fs::remove_dir_all(&d);
        fs::create_dir_all(&d).expect("scratch directory");
        d
    }

    fn names(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> = fs::read_dir(dir)
            .expect("list")
            .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    #[test]
    fn a_rewrite_keeps_the_permissions_of_the_file_it_replaces() {
        use std::os::unix::fs::PermissionsExt;
        let d = scratch("mode");
        let p = d.join("handd.toml");
        fs::write(&p, "a").expect("write");
        fs::set_permissions(&p, fs::Permissions::from_mode(0o640)).expect("chmod");
        write_atomic(&p, b"b").expect("rewrite");
        let mode = fs::metadata(&p).expect("stat").permissions().mode() & 0o7777;
        assert_eq!(mode, 0o640, "the rewrite changed mode 0640 to {mode:o}");
        assert_eq!(fs::read(&p).expect("read"), b"b");
    }

    #[test]
    fn success_replaces_the_file_and_leaves_no_temporary() {
        let dir = scratch("ok");
        let path = dir.join("model.hsm");
        write_atomic(&path, b"old").expect("first write");
        write_atomic(&path, b"new contents").expect("second write");
        assert_eq!(fs::read(&path).expect("read"), b"new contents");
        assert_eq!(names(&dir), vec!["model.hsm".to_string()]);
        fs::remove_dir_all(&dir).expect("clean up");
    }

    #[test]
    fn a_failed_write_leaves_the_old_file_intact() {
        let dir = scratch("fail");
        let path = dir.join("config.toml");
        write_atomic(&path, b"old").expect("first write");
        let e = write_atomic_with(&path, |f| {
            f.write_all(b"half of the new")?;
            Err(std::io::Error::other("disk full"))
        })
        .expect_err("the write fails");
        assert_eq!(e.op, "write", "{e}");
        assert_eq!(fs::read(&path).expect("read"), b"old");
        assert_eq!(
            names(&dir),
            vec!["config.toml".to_string()],
            "temporary left"
        );

        // A rename that fails (the target is a non-empty directory) leaves no temporary.
        let blocked = dir.join("session.toml");
        fs::create_dir_all(blocked.join("occupied")).expect("blocker");
        let e = write_atomic(&blocked, b"new").expect_err("rename over a directory");
        assert_eq!(e.op, "rename into", "{e}");
        assert!(blocked.join("occupied").is_dir());
        assert_eq!(names(&dir), vec!["config.toml", "session.toml"]);
        fs::remove_dir_all(&dir).expect("clean up");
    }

    /// A PID above Linux's PID_MAX_LIMIT (2^22): no process can have it.
    const IMPOSSIBLE_PID: u32 = (1 << 22) + 1;

    #[test]
    fn temporaries_are_recognised_by_their_target_and_writer() {
        let dir = scratch("names");
        let path = dir.join("handd.toml");
        let tmp = temp_path(&dir, &path).expect("temporary name");
        let name = OsStr::new("handd.toml");
        let tmp_name = tmp.file_name().expect("file name");
        assert_eq!(temp_file_pid(name, tmp_name), Some(std::process::id()));
        for other in [
            "handd.toml",
            ".handd.toml.tmp.12",
            ".handd.toml.tmp.x.1",
            ".handd.toml.tmp.12.",
            ".handd.toml.tmp.+12.1",
            ".other.toml.tmp.12.1",
        ] {
            assert_eq!(temp_file_pid(name, OsStr::new(other)), None, "{other}");
        }
        fs::remove_dir_all(&dir).expect("clean up");
    }

    #[test]
    fn only_temporaries_of_dead_writers_are_removed() {
        let dir = scratch("stale");
        let path = dir.join("handd.toml");
        write_atomic(&path, b"config").expect("the config");
        let stale = format!(".handd.toml.tmp.{IMPOSSIBLE_PID}.0");
        let live = format!(".handd.toml.tmp.{}.7", std::process::id());
        let other = format!(".model.hsm.tmp.{IMPOSSIBLE_PID}.0");
        for name in [&stale, &live, &other] {
            fs::write(dir.join(name), b"half a save").expect("a temporary");
        }
        assert!(
            !process_alive(IMPOSSIBLE_PID),
            "no process has PID 2^22 + 1"
        );
        assert!(process_alive(std::process::id()), "this test is alive");

        let removed = remove_stale_temps(&path).expect("clean up after killed writers");
        let expected = StaleTemp {
            path: dir.join(&stale),
            pid: IMPOSSIBLE_PID,
        };
        assert_eq!(removed, vec![expected], "only the dead writer's temporary");
        let mut left = vec![live, other, "handd.toml".to_string()];
        left.sort();
        assert_eq!(
            names(&dir),
            left,
            "the live writer's and another target's stay"
        );
        fs::remove_dir_all(&dir).expect("clean up");
    }

    #[test]
    fn a_missing_directory_has_no_stale_temporaries() {
        let path = std::env::temp_dir()
            .join("fsio-no-such-dir-4c1f")
            .join("handd.toml");
        let removed = remove_stale_temps(&path).expect("nothing to list is no error");
        assert!(removed.is_empty(), "{removed:?}");
    }
}
