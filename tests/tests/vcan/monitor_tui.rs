//! `handctl monitor` in a pseudo-terminal (80x24) beside the closed loop: from the daemon's
//! subscription its screen shows RUNNING and the index finger's label changing sign over a
//! sine period; with `--iface` and no daemon it shows the amplifier's channels. The screen is
//! the terminal as a VT100 shows it (the `vt100` crate parsing what the monitor writes).

use std::fs::File;
use std::io::{Read, Write};
use std::process::{Child, Command, Stdio};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use rustix::pty::{grantpt, openpt, ptsname, unlockpt, OpenptFlags};
use rustix::termios::{tcsetwinsize, Winsize};

use super::Rig;
use handstack_tests::vcan::procs::handsim;
use handstack_tests::vcan::VcanEnv;

fn nz(v: u16) -> std::num::NonZeroU16 {
    std::num::NonZeroU16::new(v).expect("a screen size above 0")
}

/// handctl monitor on an 80x24 pseudo-terminal, its screen parsed as it goes.
struct PtyMonitor {
    child: Child,
    master: File,
    screen: Arc<Mutex<vt100::Parser>>,
}

impl PtyMonitor {
    fn start(env: &VcanEnv, args: &[&str]) -> Self {
        let master = openpt(OpenptFlags::RDWR | OpenptFlags::NOCTTY).expect("openpt");
        grantpt(&master).expect("grantpt");
        unlockpt(&master).expect("unlockpt");
        let name = ptsname(&master, Vec::new()).expect("ptsname");
        let size = Winsize {
            ws_row: 24,
            ws_col: 80,
            ws_xpixel: 0,
            ws_ypixel: 0,
        };
        tcsetwinsize(&master, size).expect("window size");
        let slave = File::options()
            .read(true)
            .write(true)
            .open(name.to_str().expect("a UTF-8 pty name"))
            .expect("open the pty's slave");
        let io = |f: &File| Stdio::from(f.try_clone().expect("dup the slave"));
        let child = Command::new(env.bin("handctl"))
            .arg("monitor")
            .args(args)
            .stdin(io(&slave))
            .stdout(io(&slave))
            .stderr(io(&slave))
            .spawn()
            .expect("handctl monitor starts");
        drop(slave);
        let master = File::from(master);
        let screen = Arc::new(Mutex::new(vt100::Parser::new(nz(24), nz(80), 0)));
        let (mut reader, parser) = (master.try_clone().expect("dup master"), screen.clone());
        std::thread::spawn(move || {
            let mut buf = [0u8; 4096];
            // EIO once the monitor has exited and the slave is closed.
            while let Ok(n @ 1..) = reader.read(&mut buf) {
                parser.lock().expect("parser").process(&buf[..n]);
            }
        });
        Self {
            child,
            master,
            screen,
        }
    }

    fn contents(&self) -> String {
        self.screen.lock().expect("parser").screen().contents()
    }

    /// Presses q and waits for the monitor to leave; returns its last screen.
    fn quit(mut self) -> String {
        let _ = self.master.write_all(b"q");
        let end = Instant::now() + Duration::from_secs(5);
        while Instant::now() < end {
            if self.child.try_wait().expect("wait").is_some() {
                std::thread::sleep(Duration::from_millis(200));
                return self.contents();
            }
            std::thread::sleep(Duration::from_millis(50));
        }
        let _ = self.child.kill();
        panic!(
            "the monitor did not quit on q; its screen:\n{}",
            self.contents()
        );
    }
}

/// The label on the selected (index) finger's row: `>index  +0.45 ...`.
fn index_label(screen: &str) -> Option<f64> {
    let row = screen.lines().find(|l| l.contains(">index"))?;
    let after = &row[row.find(">index")? + ">index".len()..];
    after.split_whitespace().next()?.parse().ok()
}

#[test]
fn m1_monitor_shows_running_and_the_index_label_changing_sign() {
    let rig = Rig::start("monitor-tui", 100);
    let mut sim = rig.sim("sine", 14.0, &[]);
    std::thread::sleep(Duration::from_secs(2));
    let socket = rig.cfg.socket.display().to_string();
    let mon = PtyMonitor::start(&rig.env, &["--socket", &socket]);
    let (mut running, mut lo, mut hi) = (false, f64::INFINITY, f64::NEG_INFINITY);
    let end = Instant::now() + Duration::from_secs(9);
    while Instant::now() < end {
        std::thread::sleep(Duration::from_millis(100));
        let s = mon.contents();
        running |= s.contains("RUNNING");
        if let Some(l) = index_label(&s) {
            lo = lo.min(l);
            hi = hi.max(l);
        }
    }
    let last = mon.quit();
    sim.wait_success(Duration::from_secs(30));
    assert!(running, "the screen never showed RUNNING:\n{last}");
    assert!(
        lo <= -0.1 && hi >= 0.1,
        "over two sine periods the index label should take both signs: {lo}..{hi}\n{last}"
    );
    assert!(last.contains("of a core"), "the CPU use on exit:\n{last}");
}

#[test]
fn m2_monitor_on_the_bus_without_the_daemon_shows_the_channels() {
    let env = VcanEnv::get();
    let dir = env.scratch("monitor-iface");
    let mut sim = handsim(&env, &dir, "handsim", "sine", 6.0, &[]);
    std::thread::sleep(Duration::from_millis(500));
    let mon = PtyMonitor::start(&env, &["--iface", &env.iface]);
    std::thread::sleep(Duration::from_secs(3));
    let s = mon.contents();
    let last = mon.quit();
    sim.wait_success(Duration::from_secs(30));
    assert!(s.contains("no daemon heard"), "{s}");
    let live: Vec<f64> = (0..12)
        .filter_map(|c| {
            let row = s.lines().find(|l| {
                l.trim_start_matches('│')
                    .trim_start()
                    .starts_with(&format!("{c} "))
            })?;
            row.trim_start_matches('│')
                .split_whitespace()
                .nth(1)?
                .parse()
                .ok()
        })
        .collect();
    assert_eq!(
        live.len(),
        12,
        "12 channel rows:\n{s}\n(last screen)\n{last}"
    );
    assert!(
        live.iter().all(|&v| v > 0.0),
        "every channel of the amplifier shows an amplitude: {live:?}\n{s}"
    );
}
