//! A crash or kill during a save never leaves a broken config: a writer process saving the
//! config in a loop is killed with SIGKILL at pseudo-random points, many times, and the file
//! is loaded after each kill. It must always load, with one of the values written.

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::Duration;

use driver::config::Config;

const CHILD_ENV: &str = "HANDD_CONFIG_CRASH_CHILD";

/// The writer: runs only when the parent test starts this binary with `CHILD_ENV` set.
#[test]
fn child_writer() {
    let Some(path) = std::env::var_os(CHILD_ENV) else {
        return; // Not the child: nothing to do (the parent test below does the work).
    };
    let path = Path::new(&path);
    let mut c = Config::default();
    for i in 0u64.. {
        // Alternate between two valid values so a torn write would show as a third.
        c.fingers.index.kf = if i % 2 == 0 { 1.25 } else { 2.5 };
        c.fingers.ring.kalpha = if i % 2 == 0 { 4.0 } else { 8.0 };
        c.save_atomic(path).expect("save");
    }
}

#[test]
fn kill_during_save_never_leaves_a_broken_file() {
    let dir = std::env::temp_dir().join(format!("handd-crash-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("handd.toml");
    Config::default().save_atomic(&path).unwrap();
    let exe = std::env::current_exe().unwrap();
    let mut seed = 0x2545_f491_4f6c_dd1du64;
    let mut loaded_new = 0;
    let kills = 40;
    for round in 0..kills {
        let mut child = Command::new(&exe)
            .args([
                "--exact",
                "child_writer",
                "--test-threads",
                "1",
                "--nocapture",
            ])
            .env(CHILD_ENV, &path)
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        std::thread::sleep(Duration::from_micros(20_000 + seed % 30_000));
        child.kill().unwrap(); // SIGKILL
        child.wait().unwrap();
        let c = Config::load(&path).unwrap_or_else(|e| {
            panic!("round {round}: the config does not load after a kill: {e}")
        });
        let pair = (c.fingers.index.kf, c.fingers.ring.kalpha);
        assert!(
            [(10.0, 3.0), (1.25, 4.0), (2.5, 8.0)].contains(&pair),
            "round {round}: a value that was never written: {pair:?}"
        );
        loaded_new += usize::from(pair != (10.0, 3.0));
    }
    let leftovers = std::fs::read_dir(&dir).unwrap().count();
    println!("{kills} kills, {loaded_new} loads saw a value written by the killed writer; {leftovers} files in the dir");
    assert!(
        loaded_new > kills / 2,
        "the writer got to write: {loaded_new}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
