//! Issue 16: the control socket survives hostile or broken clients, and issue 13's live
//! subscription never delays a tick. Each test runs the real loop on the system clock (an idle
//! in-memory bus: no EMG, so the daemon sits in SAFE, but every tick runs and sends its
//! frames) with the real control server and handler on a real Unix socket.
//!
//! A tick is counted as a deadline miss here when it starts more than 40 ms late: far beyond
//! scheduling noise on a loaded machine, far below what waiting on a client would cost (the
//! request deadline is 1 s).

mod common;

use std::io::{BufRead, BufReader, Read, Write};
use std::os::unix::net::UnixStream;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{mpsc, Arc};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use driver::config::Config;
use driver::control::{self, ControlServer, LiveFeed, LiveModel, MAX_CONNECTIONS, MAX_SUBSCRIBERS};
use driver::daemon::{Runner, Snapshot};
use driver::engine::{Engine, EngineSettings};
use driver::live::{Live, ModelInfo};
use driver::protocol::{Reply, Request};
use driver::service::{ControlHandler, COMMAND_QUEUE};
use driver::transport::{Timestamped, Transport, TransportError};
use hand_clock::SystemClock;
use hand_dbc::CanFrame;

/// A bus on which nobody else talks: every frame sent is taken.
struct IdleBus;

impl Transport for IdleBus {
    fn try_recv(&mut self) -> Result<Option<Timestamped>, TransportError> {
        Ok(None)
    }
    fn send(&mut self, _frame: &CanFrame) -> Result<(), TransportError> {
        Ok(())
    }
    fn drop_queued(&mut self) {}
    fn reopen(&mut self) -> Result<(), TransportError> {
        Ok(())
    }
}

const SLACK_US: u64 = 40_000;

/// The daemon: loop thread, control server, config on disk.
struct Daemon {
    dir: PathBuf,
    socket: PathBuf,
    config_path: PathBuf,
    stop: Arc<AtomicBool>,
    loop_thread: Option<JoinHandle<Snapshot>>,
}

impl Daemon {
    fn start(name: &str) -> Self {
        let dir = std::env::temp_dir().join(format!("handd-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("scratch directory");
        let config_path = dir.join("handd.toml");
        let mut config = Config::default();
        config.control.socket = dir.join("ctl.sock");
        config.control.group = None;
        config.control.audit_log = dir.join("audit.log");
        config.save_atomic(&config_path).expect("config saved");

        let clock = SystemClock::new();
        let chain = decoder::dsp::ChainConfig::default()
            .validate()
            .expect("chain");
        let settings = EngineSettings {
            deadline_slack_us: SLACK_US,
            ..EngineSettings::default()
        };
        let predictor = common::random_predictor(7);
        let mut engine = Engine::new(&chain, predictor, settings, 0);
        engine.validated(0);
        let (tx, rx) = mpsc::sync_channel(COMMAND_QUEUE);
        let mut runner = Runner::new(engine, IdleBus, clock, 50_000).with_commands(rx);
        let snapshot = runner.snapshot();
        let feed = LiveFeed {
            snapshot: runner.snapshot(),
            model: Arc::new(std::sync::Mutex::new(LiveModel {
                info: ModelInfo {
                    id: "0000beef".into(),
                    path: "model.hsm".into(),
                    kind: "ResDD".into(),
                },
                rest_rms_uv: None,
            })),
            tick_us: 50_000,
        };
        let mut handler = ControlHandler::new(config.clone(), config_path.clone(), snapshot, tx);
        let server = ControlServer::bind(&config.control.socket, None)
            .expect("bound")
            .with_live(feed);
        std::thread::spawn(move || server.serve(move |req, peer| handler.handle(req, peer)));
        let stop = Arc::new(AtomicBool::new(false));
        let s = Arc::clone(&stop);
        let loop_thread = std::thread::spawn(move || {
            runner.run_realtime(&s, |_| {});
            let snap = *runner.snapshot().lock().expect("snapshot");
            snap
        });
        Self {
            dir,
            socket: config.control.socket,
            config_path,
            stop,
            loop_thread: Some(loop_thread),
        }
    }

    fn connect(&self) -> UnixStream {
        UnixStream::connect(&self.socket).expect("connect")
    }

    /// Stops the loop; its last snapshot.
    fn finish(mut self) -> Snapshot {
        self.stop.store(true, Ordering::Relaxed);
        let snap = self
            .loop_thread
            .take()
            .expect("running")
            .join()
            .expect("the loop did not panic");
        let _ = std::fs::remove_dir_all(&self.dir);
        snap
    }
}

/// The one reply line on `s`, within `wait`.
fn reply_on(s: &UnixStream, wait: Duration) -> Reply {
    s.set_read_timeout(Some(wait)).expect("timeout");
    let mut line = String::new();
    BufReader::new(s)
        .read_line(&mut line)
        .expect("a reply line");
    serde_json::from_str(line.trim()).unwrap_or_else(|e| panic!("{e}: {line:?}"))
}

fn refusal(r: Reply) -> String {
    match r {
        Reply::Refused { reason } => reason,
        other => panic!("expected a refusal, got {other:?}"),
    }
}

/// Ask `status` and time it.
fn timed_status(d: &Daemon) -> (Duration, Reply) {
    let t = Instant::now();
    let r = control::request(&d.socket, &Request::Status).expect("status answered");
    (t.elapsed(), r)
}

fn assert_ticks_on_time(snap: &Snapshot, min_ticks: u64) {
    assert!(
        snap.counters.ticks >= min_ticks,
        "the loop ran {} ticks, expected at least {min_ticks}",
        snap.counters.ticks
    );
    assert_eq!(
        snap.counters.deadline_misses, 0,
        "ticks started over {SLACK_US} us late (lateness {:?})",
        snap.lateness
    );
}

#[test]
fn silent_clients_do_not_delay_status_or_the_tick() {
    let d = Daemon::start("silent");
    std::thread::sleep(Duration::from_millis(200));
    let silent: Vec<UnixStream> = (0..100).map(|_| d.connect()).collect();
    let (took, reply) = timed_status(&d);
    assert!(
        matches!(
            reply,
            Reply::Ok {
                status: Some(_),
                ..
            }
        ),
        "{reply:?}"
    );
    assert!(
        took < Duration::from_secs(1),
        "status took {took:?} with 100 silent clients"
    );
    // A silent client is told why it is dropped, after the request deadline.
    let reason = refusal(reply_on(&silent[0], Duration::from_secs(3)));
    assert!(reason.contains("no request within 1000 ms"), "{reason}");
    // 100 technicians at once are all answered.
    let askers: Vec<_> = (0..100)
        .map(|_| {
            let p = d.socket.clone();
            std::thread::spawn(move || control::request(&p, &Request::Status))
        })
        .collect();
    for a in askers {
        let r = a.join().expect("asker").expect("answered");
        assert!(matches!(r, Reply::Ok { .. }), "{r:?}");
    }
    drop(silent);
    let snap = d.finish();
    assert_ticks_on_time(&snap, 20);
    println!(
        "status with 100 silent clients took {took:?}; lateness {:?}",
        snap.lateness
    );
}

#[test]
fn oversize_malformed_and_incomplete_requests_are_refused_with_a_reason() {
    let d = Daemon::start("malformed");
    // 10 MB on one line: refused after MAX_REQUEST_BYTES + 1 bytes, never buffered.
    let big = d.connect();
    let writer_side = big.try_clone().expect("clone");
    let writer = std::thread::spawn(move || {
        let chunk = vec![b'x'; 1 << 20];
        let mut w = writer_side;
        let mut sent = 0usize;
        for _ in 0..10 {
            match w.write_all(&chunk) {
                Ok(()) => sent += chunk.len(),
                Err(_) => break,
            }
        }
        sent
    });
    let reason = refusal(reply_on(&big, Duration::from_secs(3)));
    assert!(reason.contains("longer than 4096 bytes"), "{reason}");
    let sent = writer.join().expect("writer");
    assert!(sent < 10 << 20, "the daemon took all 10 MB ({sent} bytes)");
    big.shutdown(std::net::Shutdown::Both).ok();

    let cases: [(&[u8], &str); 5] = [
        (b"{\"cmd\":\"status\"\n", "malformed request"),
        (b"not json at all\n", "malformed request"),
        (b"{\"cmd\":\"st\xffatus\"}\n", "not UTF-8"),
        (b"{\"cmd\":\"explode\"}\n", "explode"),
        (b"{\"cmd\":\"status\",\"extra\":1}\n", "extra"),
    ];
    for (bytes, why) in cases {
        let mut s = d.connect();
        s.write_all(bytes).expect("sent");
        let reason = refusal(reply_on(&s, Duration::from_secs(3)));
        assert!(reason.contains(why), "{bytes:?}: {reason}");
    }
    // Half a line, then silence.
    let mut s = d.connect();
    s.write_all(b"{\"cmd\":").expect("sent");
    let reason = refusal(reply_on(&s, Duration::from_secs(3)));
    assert!(reason.contains("incomplete request: 7 bytes"), "{reason}");

    let snap = d.finish();
    assert_ticks_on_time(&snap, 5);
}

#[test]
fn a_flood_of_commands_waits_in_the_bounded_queue_not_in_the_tick() {
    let d = Daemon::start("commands");
    let senders: Vec<_> = (0..20)
        .map(|_| {
            let p = d.socket.clone();
            std::thread::spawn(move || {
                (0..10)
                    .map(|_| control::request(&p, &Request::Stop))
                    .filter(|r| matches!(r, Ok(Reply::Ok { .. })))
                    .count()
            })
        })
        .collect();
    let done: usize = senders.into_iter().map(|s| s.join().expect("sender")).sum();
    assert_eq!(done, 200, "every stop answered");
    std::thread::sleep(Duration::from_millis(200));
    let snap = d.finish();
    assert!(snap.faults.contains(driver::Fault::StopRequested));
    assert_ticks_on_time(&snap, 5);
}

#[test]
fn a_tune_with_one_bad_value_changes_nothing() {
    let d = Daemon::start("halfbad");
    // A tune with one good and one bad value changes nothing, on disk or in the loop.
    let before = std::fs::read(&d.config_path).expect("config");
    let r = control::request(
        &d.socket,
        &Request::Tune {
            finger: "index".into(),
            kf: Some(5.0),
            kalpha: Some(1e9),
        },
    )
    .expect("answered");
    let reason = refusal(r);
    assert!(reason.contains("kalpha"), "{reason}");
    assert_eq!(std::fs::read(&d.config_path).expect("config"), before);
    std::thread::sleep(Duration::from_millis(150));
    let Reply::Ok {
        status: Some(status),
        ..
    } = control::request(&d.socket, &Request::Status).expect("status")
    else {
        panic!("no status")
    };
    let default = Config::default();
    assert_eq!(
        status.fingers[1].kf, default.fingers.index.kf,
        "kf unchanged"
    );
    let snap = d.finish();
    assert_ticks_on_time(&snap, 2);
}

#[test]
fn connections_beyond_the_cap_are_refused_at_once_and_the_slots_come_back() {
    let d = Daemon::start("cap");
    let held: Vec<UnixStream> = (0..MAX_CONNECTIONS).map(|_| d.connect()).collect();
    // The accept thread admits in order: give it time to take all of them.
    std::thread::sleep(Duration::from_millis(200));
    let extra = d.connect();
    let t = Instant::now();
    let reason = refusal(reply_on(&extra, Duration::from_secs(3)));
    assert!(
        reason.contains("busy") && reason.contains("128"),
        "{reason}"
    );
    assert!(
        t.elapsed() < Duration::from_millis(900),
        "refused after {:?}",
        t.elapsed()
    );
    drop(held);
    // Closed connections free their slots as soon as their threads see the end.
    let mut answered = false;
    for _ in 0..20 {
        std::thread::sleep(Duration::from_millis(50));
        if let Ok(Reply::Ok { .. }) = control::request(&d.socket, &Request::Status) {
            answered = true;
            break;
        }
    }
    assert!(answered, "status refused after the connections closed");
    let snap = d.finish();
    assert_ticks_on_time(&snap, 5);
}

#[test]
fn a_user_outside_the_group_is_refused() {
    if rustix::process::geteuid().as_raw() != 0 {
        println!("not root: the peer-credential refusal is covered by the policy unit test");
        return;
    }
    let d = Daemon::start("outsider");
    // Open the file mode so that only the peer-credential check stands in the way.
    use std::os::unix::fs::PermissionsExt;
    std::fs::set_permissions(&d.socket, std::fs::Permissions::from_mode(0o666)).expect("chmod");
    std::fs::set_permissions(&d.dir, std::fs::Permissions::from_mode(0o755)).expect("chmod");
    use std::os::unix::process::CommandExt;
    let script = "import socket,sys\n\
        s=socket.socket(socket.AF_UNIX)\n\
        s.connect(sys.argv[1])\n\
        try: s.sendall(b'{\"cmd\":\"stop\"}\\n')\n\
        except BrokenPipeError: pass\n\
        print(s.makefile().readline())";
    let out = std::process::Command::new("python3")
        .args(["-c", script, d.socket.to_str().expect("utf-8 path")])
        .uid(65534)
        .gid(65534)
        .output()
        .expect("python3 runs");
    let said = String::from_utf8_lossy(&out.stdout);
    assert!(
        said.contains("refused") && said.contains("not in handd's control group"),
        "{said} {}",
        String::from_utf8_lossy(&out.stderr)
    );
    std::thread::sleep(Duration::from_millis(150));
    let snap = d.finish();
    assert_ne!(snap.state, driver::DaemonState::Boot, "the loop ran");
    assert!(
        !snap.faults.contains(driver::Fault::StopRequested),
        "the outsider's stop was applied"
    );
}

/// Reads lines from a subscription socket until `until`; the Live lines read.
fn read_lines(s: UnixStream, until: Instant) -> Vec<Live> {
    s.set_read_timeout(Some(Duration::from_secs(2)))
        .expect("timeout");
    let mut r = BufReader::new(s);
    let mut out = Vec::new();
    let mut line = String::new();
    while Instant::now() < until {
        line.clear();
        if r.read_line(&mut line).expect("a line") == 0 {
            break;
        }
        out.push(serde_json::from_str(line.trim()).expect("a Live line"));
    }
    out
}

fn subscribe_raw(d: &Daemon, every_ms: u64) -> (UnixStream, Reply) {
    let mut s = d.connect();
    writeln!(s, "{{\"cmd\":\"subscribe\",\"every_ms\":{every_ms}}}").expect("sent");
    // The acknowledgement, read byte by byte so no Live line is taken with it.
    s.set_read_timeout(Some(Duration::from_secs(3)))
        .expect("timeout");
    let mut line = Vec::new();
    let mut b = [0u8; 1];
    while line.last() != Some(&b'\n') {
        s.read_exact(&mut b).expect("the acknowledgement");
        line.push(b[0]);
    }
    let reply = serde_json::from_slice(&line).expect("a reply");
    (s, reply)
}

/// With `open` subscriptions open, fills up to the cap and checks one more is refused.
fn subscribe_over_the_cap(d: &Daemon, open: usize) {
    let (mut extra, mut refused) = (Vec::new(), None);
    for _ in open..=MAX_SUBSCRIBERS {
        let (s, reply) = subscribe_raw(d, 1000);
        match reply {
            Reply::Ok { .. } => extra.push(s),
            Reply::Refused { reason } => refused = Some(reason),
        }
    }
    let refused = refused.expect("one subscriber over the cap is refused");
    assert!(refused.contains("busy"), "{refused}");
}

/// A reading subscriber's lines over 4 s at one per tick.
fn check_reader(i: usize, lines: &[Live]) {
    // 4 s at one line per 50 ms tick is 80 lines; the publisher polls every half tick.
    assert!(lines.len() >= 40, "reader {i} got {} lines", lines.len());
    assert!(
        lines.windows(2).all(|w| w[1].tick > w[0].tick),
        "ticks go forward"
    );
    let last = lines.last().expect("a line");
    assert_eq!(last.fingers.len(), 5);
    assert_eq!(last.channels.len(), 12);
    assert_eq!(last.model.id, "0000beef");
    assert!(
        last.counters.frames_tx > 0 && last.bus_load > 0.0,
        "{last:?}"
    );
}

#[test]
fn stuck_subscribers_are_dropped_readers_keep_receiving_and_no_tick_is_late() {
    let d = Daemon::start("subscribers");
    let reason = refusal(control::subscribe(&d.socket, Some(10)).map_or_else(
        |e| Reply::Refused {
            reason: e.to_string(),
        },
        |_| panic!("10 ms accepted"),
    ));
    assert!(reason.contains("50 (one tick) to 60000"), "{reason}");

    let mut stuck = Vec::new();
    let mut readers = Vec::new();
    for i in 0..20 {
        let (s, reply) = subscribe_raw(&d, 50);
        let Reply::Ok { message, .. } = reply else {
            panic!("subscriber {i} refused: {reply:?}")
        };
        assert_eq!(message, "subscribed: one line every 50 ms");
        if i % 2 == 0 {
            stuck.push(s);
        } else {
            readers.push(s);
        }
    }
    let until = Instant::now() + Duration::from_secs(4);
    let reading: Vec<_> = readers
        .into_iter()
        .map(|s| std::thread::spawn(move || read_lines(s, until)))
        .collect();
    subscribe_over_the_cap(&d, 20);

    for (i, r) in reading.into_iter().enumerate() {
        check_reader(i, &r.join().expect("reader"));
    }
    let mut queued = 0;
    // Each stuck subscriber was dropped: its socket ends (EOF) after the lines it holds.
    for (i, mut s) in stuck.into_iter().enumerate() {
        s.set_read_timeout(Some(Duration::from_secs(2)))
            .expect("timeout");
        let mut rest = Vec::new();
        let r = s.read_to_end(&mut rest);
        assert!(r.is_ok(), "stuck subscriber {i} was not dropped: {r:?}");
        assert!(rest.len() < 64 * 1024, "{} bytes were queued", rest.len());
        queued = queued.max(rest.len());
    }
    println!("a stuck subscriber held at most {queued} bytes when dropped");
    let snap = d.finish();
    assert_ticks_on_time(&snap, 60);
    println!(
        "20 subscribers over 4 s: lateness {:?}, publish skips {}",
        snap.lateness, snap.publish_skips
    );
}
