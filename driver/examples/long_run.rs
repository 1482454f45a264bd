//! The long run (issues 15 and 16): the real daemon loop (`Runner` + `Engine`, 50 ms ticks on
//! the system clock, `Runner::run_realtime` as handd runs it) on its own thread, against the
//! simulated amplifier, hand and patient on the in-memory bus, stepped every millisecond on
//! the main thread. Every second it samples the process's resident memory (VmRSS), the daemon
//! thread's own CPU time (CLOCK_THREAD_CPUTIME_ID, read by that thread after each tick, so the
//! simulated world's CPU is not counted) and every counter. Run by `scripts/long-run`.
//!
//! ```text
//! long_run train DIR            # record a simulated calibration in DIR, train ResDD, save DIR/model.hsm
//! long_run sleeper MINUTES [RT_PRIORITY]  # (started by `run`) the bare sleeper
//! long_run run MODEL [MINUTES] [RT_PRIORITY]
//!                               # the long run (default 10 minutes); prints a Markdown report
//! ```
//!
//! With `RT_PRIORITY` (1-99) the loop thread runs under SCHED_FIFO at that priority, as
//! handd does with `--rt-priority` (the shipped systemd unit passes 50); without it, normal
//! scheduling.

use std::path::Path;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use cpu_time::ThreadTime;
use decoder::model::TrainedModel;
use decoder::session::Session;
use driver::daemon::{Runner, Snapshot};
use driver::demo::{closed_loop, record_calibration, train_on_session, ClosedLoop, DemoOptions};
use driver::mem_transport::MemTransport;
use driver::rt::{lock_memory, set_fifo, RtReport};
use hand_clock::{Clock, SystemClock};

type Error = Box<dyn std::error::Error>;

/// One sample of the run, taken every second.
#[derive(Clone, Copy)]
struct Sample {
    t_s: f64,
    /// Wall time of the sample, µs since the Unix epoch (the bare sleeper's time base).
    wall_us: u64,
    rss_kb: u64,
    daemon_cpu_ns: u64,
    snap: Snapshot,
}

/// What the daemon thread hands back when it stops.
struct DaemonEnd {
    overflows: u64,
    cpu_ns: u64,
    bare: BareSleeper,
}

/// What a process that does nothing but sleep to a 1 ms grid of deadlines (with the loop's
/// scheduling) saw over the same run: the machine's own stalls, the floor under any loop's
/// deadline misses. A process of its own, so that its memory is not in the loop's RSS. After a
/// late wake-up it skips the deadlines already past, so one stall is one late wake-up.
struct BareSleeper {
    wakeups: u64,
    p99_us: u64,
    max_us: u64,
    /// Wall time (µs since the Unix epoch) and lateness of every wake-up more than
    /// [`STALL_US`] late: the machine's stalls.
    stalls: Vec<(u64, u64)>,
}

/// The deadline slack of the default configuration, µs.
const SLACK_US: u64 = 5_000;
/// The bare sleeper's period: fine enough to see every stall longer than the slack.
const SLEEPER_PERIOD: Duration = Duration::from_millis(1);
/// A stall that can make a tick start more than the slack late: the sleeper sees it at most
/// one period short (it may have woken just before it began).
const STALL_US: u64 = SLACK_US - 1_000;

/// Wall time, µs since the Unix epoch: the one time base of this process and the sleeper's.
fn wall_us() -> u64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_micros() as u64)
}

/// `long_run sleeper MINUTES [RT_PRIORITY]`: sleeps to a 1 ms grid for `minutes`, then prints
/// `wakeups p99_us max_us`, then one `stall WALL_US LATENESS_US` line per stall.
fn bare_sleeper(minutes: f64, rt_priority: Option<u8>) {
    if let Some(p) = rt_priority {
        set_fifo(p, &mut RtReport::default());
    }
    // Lateness histogram in µs (the last bin holds everything longer).
    const BINS: usize = 100_001;
    let mut hist = vec![0u64; BINS];
    let (mut wakeups, mut max_us) = (0u64, 0u64);
    let mut stalls = Vec::new();
    let begun = Instant::now();
    let end = begun + Duration::from_secs_f64(minutes * 60.0);
    let mut deadline = begun + SLEEPER_PERIOD;
    while deadline < end {
        let now = Instant::now();
        if deadline > now {
            std::thread::sleep(deadline - now);
        }
        let woke = Instant::now();
        let late = woke.saturating_duration_since(deadline).as_micros() as u64;
        hist[(late as usize).min(BINS - 1)] += 1;
        wakeups += 1;
        max_us = max_us.max(late);
        if late > STALL_US {
            stalls.push((wall_us(), late));
        }
        while deadline <= woke {
            deadline += SLEEPER_PERIOD;
        }
    }
    let want = (wakeups * 99).div_ceil(100);
    let mut seen = 0;
    let p99_us = hist
        .iter()
        .position(|&c| {
            seen += c;
            seen >= want
        })
        .unwrap_or(0);
    println!("{wakeups} {p99_us} {max_us}");
    for (t, late) in stalls {
        println!("stall {t} {late}");
    }
}

/// Starts the bare sleeper as a child process of this binary.
fn start_sleeper(minutes: f64, rt_priority: Option<u8>) -> Result<std::process::Child, Error> {
    let mut cmd = std::process::Command::new(std::env::current_exe()?);
    cmd.arg("sleeper").arg(minutes.to_string());
    if let Some(p) = rt_priority {
        cmd.arg(p.to_string());
    }
    Ok(cmd.stdout(std::process::Stdio::piped()).spawn()?)
}

/// The bare sleeper's figures, once it has finished.
fn finish_sleeper(child: std::process::Child) -> Result<BareSleeper, Error> {
    let out = child.wait_with_output()?;
    let text = String::from_utf8_lossy(&out.stdout);
    let bad = || format!("the bare sleeper printed {text:?}");
    let mut lines = text.lines();
    let head: Vec<u64> = lines
        .next()
        .ok_or_else(bad)?
        .split_whitespace()
        .map(str::parse)
        .collect::<Result<_, _>>()
        .map_err(|_| bad())?;
    let [wakeups, p99_us, max_us] = head[..] else {
        return Err(bad().into());
    };
    let stalls = lines
        .map(|l| match l.split_whitespace().collect::<Vec<_>>()[..] {
            ["stall", t, late] => Ok((t.parse()?, late.parse()?)),
            _ => Err(bad().into()),
        })
        .collect::<Result<Vec<(u64, u64)>, Error>>()?;
    Ok(BareSleeper {
        wakeups,
        p99_us,
        max_us,
        stalls,
    })
}

/// The loop's deadline misses set against the machine's stalls: (one-second samples in which
/// the loop missed a deadline, how many of them the bare sleeper saw a stall in, the loop's
/// misses in those).
fn misses_against_stalls(samples: &[Sample], stalls: &[(u64, u64)]) -> (usize, usize, u64) {
    let (mut seconds, mut explained, mut explained_misses) = (0, 0, 0);
    for w in samples.windows(2) {
        let misses = w[1].snap.counters.deadline_misses - w[0].snap.counters.deadline_misses;
        if misses == 0 {
            continue;
        }
        seconds += 1;
        // A tick is judged when it starts, up to a tick after its deadline: the stall that made
        // it late can lie up to 100 ms before the sample that counted it.
        let (from, to) = (w[0].wall_us.saturating_sub(100_000), w[1].wall_us);
        if stalls.iter().any(|&(t, _)| (from..=to).contains(&t)) {
            explained += 1;
            explained_misses += misses;
        }
    }
    (seconds, explained, explained_misses)
}

/// The process's resident set, kB (VmRSS of /proc/self/status).
fn rss_kb() -> u64 {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    status
        .lines()
        .find_map(|l| l.strip_prefix("VmRSS:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse().ok())
        .unwrap_or(0)
}

/// Records a simulated calibration session in `dir`, trains ResDD on it, saves `dir/model.hsm`.
fn train_model(dir: &Path) -> Result<(), Error> {
    let session_dir = dir.join("session");
    record_calibration(&session_dir, 1)?;
    let session = Session::open(&session_dir)?;
    let model = train_on_session(&session, &DemoOptions::default(), &mut |_| {})?;
    let path = dir.join("model.hsm");
    model.save(&path)?;
    println!(
        "trained ResDD on {}: {}",
        session_dir.display(),
        path.display()
    );
    Ok(())
}

/// The daemon loop on its own thread (SCHED_FIFO at `rt_priority` if given) until `stop`;
/// it keeps its CPU time in `cpu_ns` after every tick and returns (receive-queue overflows,
/// CPU time at the end).
fn spawn_loop(
    mut runner: Runner<MemTransport<SystemClock>, SystemClock>,
    stop: Arc<AtomicBool>,
    cpu_ns: Arc<AtomicU64>,
    rt_priority: Option<u8>,
) -> std::io::Result<std::thread::JoinHandle<(u64, u64)>> {
    std::thread::Builder::new()
        .name("handd-loop".into())
        // handd runs its loop on the main thread, whose stack is resident only as far as it is
        // touched; here the loop has a thread with the stack of handd's other threads (all of
        // it resident, since memory is locked).
        .stack_size(driver::control::THREAD_STACK_BYTES)
        .spawn(move || {
            if let Some(p) = rt_priority {
                let mut rt = RtReport::default();
                set_fifo(p, &mut rt);
                eprintln!(
                    "loop thread SCHED_FIFO {:?} {:?}",
                    rt.fifo_priority, rt.warnings
                );
            }
            runner.run_realtime(&stop, |_| {
                let t = ThreadTime::now().as_duration().as_nanos() as u64;
                cpu_ns.store(t, Ordering::Relaxed);
            });
            (
                runner.transport().overflows(),
                ThreadTime::now().as_duration().as_nanos() as u64,
            )
        })
}

/// Runs the loop for `minutes`; returns the samples and the daemon thread's end state.
fn run(
    model: &TrainedModel,
    minutes: f64,
    rt_priority: Option<u8>,
) -> Result<(Vec<Sample>, DaemonEnd), Error> {
    let clock = SystemClock::new();
    let ClosedLoop {
        mut world, runner, ..
    } = closed_loop(model, 1, clock)?;
    let snapshot = runner.snapshot();
    let stop = Arc::new(AtomicBool::new(false));
    let cpu_ns = Arc::new(AtomicU64::new(0));
    let daemon = spawn_loop(runner, Arc::clone(&stop), Arc::clone(&cpu_ns), rt_priority)?;
    let sleeper = start_sleeper(minutes, rt_priority)?;
    let read = || *snapshot.lock().unwrap_or_else(|e| e.into_inner());
    let begun = Instant::now();
    let end = Duration::from_secs_f64(minutes * 60.0);
    let mut samples = Vec::with_capacity((minutes * 60.0) as usize + 2);
    let mut next_sample = Duration::ZERO;
    while begun.elapsed() < end {
        let now = clock.now_us();
        world.step(now);
        if begun.elapsed() >= next_sample {
            samples.push(Sample {
                t_s: begun.elapsed().as_secs_f64(),
                wall_us: wall_us(),
                rss_kb: rss_kb(),
                daemon_cpu_ns: cpu_ns.load(Ordering::Relaxed),
                snap: read(),
            });
            next_sample += Duration::from_secs(1);
        }
        let next_ms = (clock.now_us() / 1000 + 1) * 1000;
        std::thread::sleep(Duration::from_micros(
            next_ms.saturating_sub(clock.now_us()),
        ));
    }
    stop.store(true, Ordering::Relaxed);
    let bare = finish_sleeper(sleeper)?;
    let (overflows, cpu_ns) = daemon.join().map_err(|_| "the daemon thread panicked")?;
    let end = DaemonEnd {
        overflows,
        cpu_ns,
        bare,
    };
    samples.push(Sample {
        t_s: begun.elapsed().as_secs_f64(),
        wall_us: wall_us(),
        rss_kb: rss_kb(),
        daemon_cpu_ns: end.cpu_ns,
        snap: read(),
    });
    Ok((samples, end))
}

fn mb(kb: u64) -> f64 {
    kb as f64 / 1024.0
}

/// One row of the per-minute table.
fn row(s: &Sample, prev: &Sample) -> String {
    let c = &s.snap.counters;
    let cpu = (s.daemon_cpu_ns - prev.daemon_cpu_ns) as f64 / ((s.t_s - prev.t_s) * 1e9) * 100.0;
    format!(
        "| {:.0} | {:.2} | {:.3} | {} ({}) | {} | {} | {} | {} | {} | {} | {} |",
        s.t_s,
        mb(s.rss_kb),
        cpu,
        s.snap.state,
        s.snap.faults,
        c.ticks,
        c.deadline_misses,
        c.samples_lost,
        c.bad_frames,
        c.e2e_errors,
        s.snap.latency.p99_us,
        s.snap.lateness.max_us,
    )
}

/// The per-minute table (and the last sample).
fn table(samples: &[Sample]) -> String {
    let mut out = String::from(
        "| t (s) | RSS (MB) | daemon CPU (% of a core, since the last row) | state (faults) | ticks | \
         deadline misses | samples lost | bad frames | E2E errors | latency p99 (µs) | \
         lateness max (µs) |\n|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    let mut prev = &samples[0];
    for (i, s) in samples.iter().enumerate().skip(1) {
        if (s.t_s as u64).is_multiple_of(60) || i == samples.len() - 1 {
            out += &row(s, prev);
            out.push('\n');
            prev = s;
        }
    }
    out
}

/// The Markdown report: the summary against the goals, then the table.
fn report(samples: &[Sample], end: &DaemonEnd) -> String {
    let (first, last) = (&samples[0], &samples[samples.len() - 1]);
    let warm = samples.iter().find(|s| s.t_s >= 60.0).unwrap_or(first);
    let (lo, hi) = samples
        .iter()
        .filter(|s| s.t_s >= warm.t_s)
        .fold((u64::MAX, 0), |(lo, hi), s| {
            (lo.min(s.rss_kb), hi.max(s.rss_kb))
        });
    let c = &last.snap.counters;
    let (seconds, explained, explained_misses) = misses_against_stalls(samples, &end.bare.stalls);
    let cpu = last.daemon_cpu_ns as f64 / (last.t_s * 1e9) * 100.0;
    let lost = end.overflows + c.samples_lost + c.bad_frames + c.e2e_errors;
    let mut out = format!(
        "| figure | measured | goal |\n|---|---|---|\n\
         | run length | {:.1} s, {} ticks (20 Hz), final state {}, faults {} | |\n\
         | frames lost on the bus (daemon's receive queue overflows) | {} | 0 |\n\
         | EMG samples lost / bad frames / E2E errors / e-stops | {} / {} / {} / {} | 0 |\n\
         | deadline misses (5 ms slack) | {} | 0 |\n\
         | daemon thread CPU, whole run | {cpu:.3} % of a core | ≤ 1 % |\n\
         | process RSS at start (t = {:.0} s) / after 1 min / end | {:.2} / {:.2} / {:.2} MB | ≤ 10 MB |\n\
         | RSS range from 1 min to the end | {:.3} MB ({} kB) | flat within 1 MB |\n\
         | latency p50 / p99 / max | {} / {} / {} µs | |\n\
         | compute per tick p50 / p99 / max | {} / {} / {} µs | |\n\
         | tick lateness p50 / p99 / max | {} / {} / {} µs | |\n\
         | the machine alone: a bare process sleeping to a 1 ms grid, the loop's scheduling, same run: stalls over 4 ms (wake-ups that late; a stall over 4 ms can hold a tick over the 5 ms slack) / lateness p99 / max | {} in {} wake-ups / {} / {} µs | |\n\
         | the loop's misses during the machine's stalls: seconds with a miss that hold a stall of the bare process (misses in them) | {} of {} ({} of {}) | |\n\
         | nothing lost at all | {} | yes |\n\n",
        last.t_s, c.ticks, last.snap.state, last.snap.faults, end.overflows, c.samples_lost, c.bad_frames,
        c.e2e_errors, c.estops, c.deadline_misses, first.t_s, mb(first.rss_kb), mb(warm.rss_kb),
        mb(last.rss_kb), mb(hi - lo), hi - lo, last.snap.latency.p50_us,
        last.snap.latency.p99_us, last.snap.latency.max_us, last.snap.compute.p50_us,
        last.snap.compute.p99_us, last.snap.compute.max_us, last.snap.lateness.p50_us,
        last.snap.lateness.p99_us, last.snap.lateness.max_us, end.bare.stalls.len(),
        end.bare.wakeups, end.bare.p99_us, end.bare.max_us, explained, seconds, explained_misses,
        c.deadline_misses,
        if lost == 0 { "yes" } else { "NO" },
    );
    out += &table(samples);
    out
}

fn main() -> Result<(), Error> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match args.iter().map(String::as_str).collect::<Vec<_>>()[..] {
        ["train", dir] => train_model(Path::new(dir)),
        ["run", model] | ["run", model, _] | ["run", model, _, _] => {
            let minutes: f64 = args.get(2).map_or(Ok(10.0), |m| m.parse())?;
            if !(minutes > 0.0 && minutes.is_finite()) {
                return Err(format!("minutes must be > 0, got {minutes}").into());
            }
            let rt_priority = match args.get(3) {
                None => None,
                Some(p) => match p.parse::<u8>() {
                    Ok(p @ 1..=99) => Some(p),
                    _ => return Err(format!("RT_PRIORITY must be 1..=99, got {p}").into()),
                },
            };
            let model = TrainedModel::load(model, None)?;
            // As handd does before its loop: lock memory (no page fault in a tick); SCHED_FIFO
            // for the loop thread only if asked (handd's --rt-priority).
            let mut rt = RtReport::default();
            lock_memory(&mut rt);
            eprintln!("memory locked: {} {:?}", rt.memory_locked, rt.warnings);
            let (samples, end) = run(&model, minutes, rt_priority)?;
            print!("{}", report(&samples, &end));
            Ok(())
        }
        ["sleeper", minutes] | ["sleeper", minutes, _] => {
            let rt_priority = args.get(2).map(|p| p.parse::<u8>()).transpose()?;
            bare_sleeper(minutes.parse()?, rt_priority);
            Ok(())
        }
        _ => Err("usage: long_run train DIR | long_run run MODEL [MINUTES] [RT_PRIORITY]".into()),
    }
}
