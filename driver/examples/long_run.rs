//! The long run (issues 15 and 16): the real daemon loop (`Runner` + `Engine`, 50 ms ticks on
//! the system clock, `Runner::run_realtime` as handd runs it) on its own thread, against the
//! simulated amplifier, hand and patient on the in-memory bus, stepped every millisecond on
//! the main thread. Every second it samples the process's resident memory (VmRSS), the daemon
//! thread's own CPU time (CLOCK_THREAD_CPUTIME_ID, read by that thread after each tick, so the
//! simulated world's CPU is not counted) and every counter. Run by `scripts/long-run`.
//!
//! ```text
//! long_run train DIR            # record a simulated calibration in DIR, train ResDD, save DIR/model.hsm
//! long_run run MODEL [MINUTES]  # the long run (default 10 minutes); prints a Markdown report
//! ```

use std::path::Path;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use cpu_time::ThreadTime;
use decoder::model::TrainedModel;
use decoder::session::Session;
use driver::daemon::Snapshot;
use driver::demo::{closed_loop, record_calibration, train_on_session, ClosedLoop, DemoOptions};
use driver::rt::{lock_memory, RtReport};
use hand_clock::{Clock, SystemClock};

type Error = Box<dyn std::error::Error>;

/// One sample of the run, taken every second.
#[derive(Clone, Copy)]
struct Sample {
    t_s: f64,
    rss_kb: u64,
    daemon_cpu_ns: u64,
    snap: Snapshot,
}

/// What the daemon thread hands back when it stops.
struct DaemonEnd {
    overflows: u64,
    cpu_ns: u64,
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

/// Runs the loop for `minutes`; returns the samples and the daemon thread's end state.
fn run(model: &TrainedModel, minutes: f64) -> Result<(Vec<Sample>, DaemonEnd), Error> {
    let clock = SystemClock::new();
    let ClosedLoop {
        mut world, runner, ..
    } = closed_loop(model, 1, clock)?;
    let snapshot = runner.snapshot();
    let stop = Arc::new(AtomicBool::new(false));
    let cpu_ns = Arc::new(AtomicU64::new(0));
    let daemon = {
        let (stop, cpu_ns) = (Arc::clone(&stop), Arc::clone(&cpu_ns));
        let mut runner = runner;
        std::thread::Builder::new()
            .name("handd-loop".into())
            .spawn(move || {
                runner.run_realtime(&stop, |_| {
                    let t = ThreadTime::now().as_duration().as_nanos() as u64;
                    cpu_ns.store(t, Ordering::Relaxed);
                });
                DaemonEnd {
                    overflows: runner.transport().overflows(),
                    cpu_ns: ThreadTime::now().as_duration().as_nanos() as u64,
                }
            })?
    };
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
    let end = daemon.join().map_err(|_| "the daemon thread panicked")?;
    samples.push(Sample {
        t_s: begun.elapsed().as_secs_f64(),
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
         | nothing lost at all | {} | yes |\n\n",
        last.t_s, c.ticks, last.snap.state, last.snap.faults, end.overflows, c.samples_lost, c.bad_frames,
        c.e2e_errors, c.estops, c.deadline_misses, first.t_s, mb(first.rss_kb), mb(warm.rss_kb),
        mb(last.rss_kb), mb(hi - lo), hi - lo, last.snap.latency.p50_us,
        last.snap.latency.p99_us, last.snap.latency.max_us, last.snap.compute.p50_us,
        last.snap.compute.p99_us, last.snap.compute.max_us, last.snap.lateness.p50_us,
        last.snap.lateness.p99_us, last.snap.lateness.max_us,
        if lost == 0 { "yes" } else { "NO" },
    );
    out += &table(samples);
    out
}

fn main() -> Result<(), Error> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match args.iter().map(String::as_str).collect::<Vec<_>>()[..] {
        ["train", dir] => train_model(Path::new(dir)),
        ["run", model] | ["run", model, _] => {
            let minutes: f64 = args.get(2).map_or(Ok(10.0), |m| m.parse())?;
            if !(minutes > 0.0 && minutes.is_finite()) {
                return Err(format!("minutes must be > 0, got {minutes}").into());
            }
            let model = TrainedModel::load(model, None)?;
            // As handd does before its loop: lock memory (no page fault in a tick); normal
            // scheduling, since handd's SCHED_FIFO is opt-in (--rt-priority).
            let mut rt = RtReport::default();
            lock_memory(&mut rt);
            eprintln!("memory locked: {} {:?}", rt.memory_locked, rt.warnings);
            let (samples, end) = run(&model, minutes)?;
            print!("{}", report(&samples, &end));
            Ok(())
        }
        _ => Err("usage: long_run train DIR | long_run run MODEL [MINUTES]".into()),
    }
}
