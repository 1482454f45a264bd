//! The project's binaries as child processes: started with their output in files of the test's
//! scratch directory (shown when a test fails), killed when dropped.

use std::fs::File;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

use super::env::VcanEnv;

/// A running child process, SIGKILLed on drop if still running.
#[derive(Debug)]
pub struct Proc {
    name: String,
    child: Child,
    log: PathBuf,
}

impl Proc {
    /// Starts `bin` (one of the project's binaries, or an absolute path) with `args`; stdout
    /// and stderr go to `dir/<name>.log`.
    pub fn spawn(env: &VcanEnv, bin: &str, name: &str, args: &[String], dir: &Path) -> Self {
        Self::spawn_as(env, bin, name, args, dir, None)
    }

    /// [`Proc::spawn`] as user `uid` and group `gid` (the process drops root's privileges
    /// before it runs, as systemd's `User=` and `Group=` do); None runs as this process.
    pub fn spawn_as(
        env: &VcanEnv,
        bin: &str,
        name: &str,
        args: &[String],
        dir: &Path,
        user: Option<(u32, u32)>,
    ) -> Self {
        let log = dir.join(format!("{name}.log"));
        let out = File::create(&log).expect("log file in the scratch directory");
        let err = out.try_clone().expect("log file handle");
        let path = if bin.starts_with('/') {
            PathBuf::from(bin)
        } else {
            env.bin(bin)
        };
        let mut cmd = Command::new(&path);
        if let Some((uid, gid)) = user {
            use std::os::unix::process::CommandExt;
            cmd.uid(uid).gid(gid);
        }
        let child = cmd
            .args(args)
            .stdin(Stdio::null())
            .stdout(out)
            .stderr(err)
            .spawn()
            .unwrap_or_else(|e| panic!("cannot start {}: {e}", path.display()));
        Self {
            name: name.to_owned(),
            child,
            log,
        }
    }

    /// The process id.
    pub fn pid(&self) -> u32 {
        self.child.id()
    }

    /// Its output file.
    pub fn log_path(&self) -> &Path {
        &self.log
    }

    /// What the process wrote so far.
    pub fn output(&self) -> String {
        std::fs::read_to_string(&self.log).unwrap_or_default()
    }

    /// Whether it is still running.
    pub fn running(&mut self) -> bool {
        matches!(self.child.try_wait(), Ok(None))
    }

    /// SIGTERM (as systemd stops a service), then waits up to `limit` for it to exit with 0.
    pub fn terminate(&mut self, limit: Duration) {
        self.signal(rustix::process::Signal::TERM);
        self.wait_success(limit);
    }

    /// Sends `sig` (e.g. SIGSTOP, SIGCONT) without waiting.
    pub fn signal(&self, sig: rustix::process::Signal) {
        let pid = rustix::process::Pid::from_raw(self.child.id() as i32)
            .expect("a child's pid is positive");
        rustix::process::kill_process(pid, sig)
            .unwrap_or_else(|e| panic!("cannot signal {}: {e}", self.name));
    }

    /// SIGKILL, then reap.
    pub fn kill(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }

    /// Waits up to `limit` for the process to end by itself; its exit status.
    pub fn wait_exit(&mut self, limit: Duration) -> std::process::ExitStatus {
        let end = Instant::now() + limit;
        loop {
            match self.child.try_wait() {
                Ok(Some(st)) => return st,
                Ok(None) if Instant::now() < end => std::thread::sleep(Duration::from_millis(20)),
                Ok(None) => {
                    self.kill();
                    panic!(
                        "{} did not end within {limit:?}; its output:\n{}",
                        self.name,
                        self.output()
                    );
                }
                Err(e) => panic!("waiting for {}: {e}", self.name),
            }
        }
    }

    /// Waits up to `limit` for the process to end by itself and asserts it exited with 0.
    pub fn wait_success(&mut self, limit: Duration) {
        let st = self.wait_exit(limit);
        assert!(
            st.success(),
            "{} ended with {st}; its output:\n{}",
            self.name,
            self.output()
        );
    }
}

impl Drop for Proc {
    fn drop(&mut self) {
        if self.running() {
            self.kill();
        }
    }
}

/// Runs `handctl ARGS` to completion; panics with its output unless it succeeds.
pub fn handctl(env: &VcanEnv, args: &[&str]) -> Output {
    let out = Command::new(env.bin("handctl"))
        .args(args)
        .output()
        .unwrap_or_else(|e| panic!("cannot run handctl: {e}"));
    assert!(
        out.status.success(),
        "handctl {} failed ({}):\n{}{}",
        args.join(" "),
        out.status,
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// The suite's deadline: a tick starting more than this after its deadline is a miss, ms.
/// The daemon's default (5 ms) is for the board; under TCG emulation the guest's timers and
/// both virtual CPUs share this machine's two cores with the emulated world, and the sleeping
/// SCHED_FIFO loop wakes about 2 ms late typically and up to 15 ms late now and then (measured
/// in the closed loop) with nothing else on the bus. Half a tick (the most the config allows)
/// still puts every tick's setpoints out inside its 50 ms period and far inside the
/// controllers' 150 ms brake timeout; `handctl status` shows the measured lateness.
pub const DEADLINE_SLACK_MS: u32 = 25;

/// A handd config file for one test.
#[derive(Debug, Clone)]
pub struct TestConfig {
    /// The config file.
    pub path: PathBuf,
    /// handd's control socket.
    pub socket: PathBuf,
}

impl TestConfig {
    /// Writes `dir/handd.toml` for `model` on the env's interface; `silence_ms` sets both the
    /// EMG and the finger silence timeouts. The state directory (the latch file) is `dir`, so
    /// no test's latches reach another's.
    pub fn write(env: &VcanEnv, dir: &Path, model: &Path, silence_ms: u32) -> Self {
        Self::write_installed(
            env,
            &Layout {
                config: dir.join("handd.toml"),
                state_dir: dir.to_path_buf(),
                socket: dir.join("handctl.sock"),
                group: "root".into(),
            },
            model,
            silence_ms,
        )
    }

    /// Writes `layout.config` for `model` with the layout's state directory (latches, audit
    /// log), control socket and socket group.
    pub fn write_installed(env: &VcanEnv, layout: &Layout, model: &Path, silence_ms: u32) -> Self {
        let text = format!(
            "interface = \"{}\"\nmodel = \"{}\"\ntick_ms = 50\n\
             deadline_slack_ms = {DEADLINE_SLACK_MS}\nmains_hz = 50\nstate_dir = \"{}\"\n\n\
             [timeouts]\nemg_silence_ms = {silence_ms}\nfinger_silence_ms = {silence_ms}\n\
             recovery_ms = 500\n\n[control]\nsocket = \"{}\"\ngroup = \"{}\"\n\
             audit_log = \"{}\"\n",
            env.iface,
            model.display(),
            layout.state_dir.display(),
            layout.socket.display(),
            layout.group,
            layout.state_dir.join("audit.log").display()
        );
        std::fs::write(&layout.config, text).expect("write the config");
        Self {
            path: layout.config.clone(),
            socket: layout.socket.clone(),
        }
    }

    /// Starts handd with this config.
    pub fn start(&self, env: &VcanEnv, dir: &Path) -> Proc {
        self.start_as(env, dir, "handd", None)
    }

    /// Starts handd with this config and `extra` arguments.
    pub fn start_with(&self, env: &VcanEnv, dir: &Path, extra: &[&str]) -> Proc {
        self.launch(env, dir, "handd", None, extra)
    }

    /// Starts handd with this config, its output in `dir/<name>.log`, as `user` (uid, gid;
    /// None: as this process). Waits for its control socket: a socket file left by a killed
    /// handd must be removed first, or this returns before the new one listens.
    pub fn start_as(
        &self,
        env: &VcanEnv,
        dir: &Path,
        name: &str,
        user: Option<(u32, u32)>,
    ) -> Proc {
        self.launch(env, dir, name, user, &[])
    }

    fn launch(
        &self,
        env: &VcanEnv,
        dir: &Path,
        name: &str,
        user: Option<(u32, u32)>,
        extra: &[&str],
    ) -> Proc {
        // SCHED_FIFO for the control loop, as on the board (root in the VM): the simulated
        // world shares the CPU with it, and under emulation a normal-priority loop starves.
        let mut args = vec![
            "--config".to_string(),
            self.path.display().to_string(),
            "--rt-priority".into(),
            HANDD_FIFO.to_string(),
        ];
        args.extend(extra.iter().map(|a| a.to_string()));
        let p = Proc::spawn_as(env, "handd", name, &args, dir, user);
        // handd is up once its control socket exists.
        let end = Instant::now() + Duration::from_secs(20);
        while !self.socket.exists() {
            assert!(
                Instant::now() < end,
                "handd did not open its control socket; its output:\n{}",
                p.output()
            );
            std::thread::sleep(Duration::from_millis(20));
        }
        p
    }

    /// The status straight from the control socket, as `handctl status` asks for it, without
    /// a process: for the drills that poll every 50 ms. Under the emulator, running `handctl`
    /// (the exec and exit of a 6 MB binary) 20 times a second stalled the guest's CPUs up to
    /// 67 ms at a time, and handd's ticks with them (issue 29: README, "The real bus").
    pub fn query_status(&self) -> driver::protocol::Status {
        use driver::protocol::{Reply, Request};
        match driver::control::request(&self.socket, &Request::Status) {
            Ok(Reply::Ok {
                status: Some(s), ..
            }) => s,
            other => panic!("handd's status request: {other:?}"),
        }
    }

    /// `handctl status --json` against this daemon.
    pub fn status(&self, env: &VcanEnv) -> driver::protocol::Status {
        let sock = self.socket.display().to_string();
        let out = handctl(env, &["status", "--json", "--socket", &sock]);
        serde_json::from_slice(&out.stdout).unwrap_or_else(|e| {
            panic!(
                "handctl status --json is not a status ({e}):\n{}",
                String::from_utf8_lossy(&out.stdout)
            )
        })
    }
}

/// Where a handd config puts things.
#[derive(Debug, Clone)]
pub struct Layout {
    /// The config file.
    pub config: PathBuf,
    /// The state directory (latches, audit log, deployed models beside the model).
    pub state_dir: PathBuf,
    /// The control socket.
    pub socket: PathBuf,
    /// The control socket's group.
    pub group: String,
}

/// Starts handsim on the env's interface with `scenario` for `seconds`, plus extra arguments.
pub fn handsim(
    env: &VcanEnv,
    dir: &Path,
    name: &str,
    scenario: &str,
    seconds: f64,
    extra: &[&str],
) -> Proc {
    let mut args = vec![
        "--iface".to_string(),
        env.iface.clone(),
        "--scenario".into(),
        scenario.into(),
        "--duration".into(),
        format!("{seconds}"),
    ];
    args.extend(extra.iter().map(|s| s.to_string()));
    // The simulated nodes are the prosthesis's other microcontrollers: they must not stall
    // behind the test's own threads. A child inherits the scheduling policy of the thread that
    // starts it, so start handsim from a thread on SCHED_FIFO just below handd's.
    let (env, name, dir) = (env.clone(), name.to_owned(), dir.to_path_buf());
    std::thread::spawn(move || {
        let mut rt = driver::rt::RtReport::default();
        driver::rt::set_fifo(HANDSIM_FIFO, &mut rt);
        for w in &rt.warnings {
            eprintln!("handsim starter: {w}");
        }
        Proc::spawn(&env, "handsim", &name, &args, &dir)
    })
    .join()
    .expect("handsim starter thread")
}

/// SCHED_FIFO priority of handsim (handd's control loop runs at [`HANDD_FIFO`]).
pub const HANDSIM_FIFO: u8 = 40;
/// SCHED_FIFO priority of handd's control loop in the suite, as on the board.
pub const HANDD_FIFO: u8 = 50;
