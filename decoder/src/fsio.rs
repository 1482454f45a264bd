//! Atomic file replacement, the one implementation behind every file the stack rewrites in
//! place (handd's config, model files, session metadata and sample files): a temporary file in
//! the same directory, written and fsynced, renamed over the target, then the directory
//! fsynced. A crash at any point leaves either the old file or the new one, never a mix, and
//! a failure leaves no temporary file behind.

use std::fs::{self, File};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// A step of an atomic write failed.
#[derive(Debug, thiserror::Error)]
#[error("{op} {path}: {source}")]
pub struct WriteError {
    /// What was being done ("create", "write", "fsync", "rename into", "fsync directory").
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
        ".{}.tmp.{}.{}",
        name.to_string_lossy(),
        std::process::id(),
        SEQ.fetch_add(1, Ordering::Relaxed)
    )))
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
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let tmp = temp_path(&dir, path)?;
    let write = || -> Result<(), WriteError> {
        let mut f = File::create(&tmp).map_err(step("create", &tmp))?;
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
}
