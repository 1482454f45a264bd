//! Whether the machine itself ran while handd was late.
//!
//! One meter thread per CPU, pinned to it at SCHED_FIFO 99 (above handd's 50 and everything
//! else the suite starts), sleeps [`STEP`] again and again and notes every wake-up more than
//! [`GAP_MIN`] past its time. Such a gap is time in which that CPU ran nothing of the guest's at
//! the highest priority there is: under the emulator, the host did not run that virtual CPU
//! (its thread descheduled on a loaded host, or waiting for qemu's lock). On a board it would be
//! the kernel with preemption off, which handd could not have beaten either.
//!
//! A late tick of handd's ([`LateTick`]: the deadline on CLOCK_MONOTONIC, the CPU it ran on) is
//! charged to handd for the part of its lateness that no gap on its CPU covers; a tick whose
//! uncovered lateness is beyond the slack is handd's miss. The meter never excuses a tick it
//! did not see: more misses than the status keeps, or a meter without SCHED_FIFO, charge every
//! miss to handd.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::Duration;

use driver::protocol::{LateTick, Status};

/// How long each meter sleeps at a time.
pub const STEP: Duration = Duration::from_millis(2);
/// A wake-up later than this past its time is a gap, µs.
pub const GAP_MIN_US: u64 = 2_000;
/// The SCHED_FIFO priority of the meters.
pub const PRIORITY: u8 = 99;

/// A stretch in which one CPU ran nothing of the guest's, CLOCK_MONOTONIC µs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Gap {
    /// The CPU.
    pub cpu: u32,
    /// When its meter was due.
    pub from_us: u64,
    /// When it ran.
    pub to_us: u64,
}

/// The meters, running.
pub struct StallMeter {
    stop: Arc<AtomicBool>,
    threads: Vec<JoinHandle<Result<Vec<Gap>, String>>>,
}

/// What the meters saw.
#[derive(Debug, Clone, Default)]
pub struct Stalls {
    /// Every gap, per CPU in time order.
    pub gaps: Vec<Gap>,
    /// Why the meters cannot vouch for the machine (none: they can).
    pub unusable: Option<String>,
    /// CPUs metered.
    pub cpus: usize,
}

fn meter(cpu: usize, stop: Arc<AtomicBool>) -> Result<Vec<Gap>, String> {
    let mut set = rustix::thread::CpuSet::new();
    set.set(cpu);
    rustix::thread::sched_setaffinity(None, &set).map_err(|e| format!("CPU {cpu}: {e}"))?;
    let mut report = driver::rt::RtReport::default();
    driver::rt::set_fifo(PRIORITY, &mut report);
    if report.fifo_priority.is_none() {
        return Err(report.warnings.join("; "));
    }
    let mut gaps = Vec::with_capacity(4_096);
    let step_us = STEP.as_micros() as u64;
    while !stop.load(Ordering::Relaxed) {
        let before = driver::rt::monotonic_us();
        std::thread::sleep(STEP);
        let after = driver::rt::monotonic_us();
        let due = before + step_us;
        if after > due + GAP_MIN_US && gaps.len() < gaps.capacity() {
            gaps.push(Gap {
                cpu: cpu as u32,
                from_us: due,
                to_us: after,
            });
        }
    }
    Ok(gaps)
}

impl StallMeter {
    /// One meter per CPU this process may run on.
    pub fn start() -> Self {
        let stop = Arc::new(AtomicBool::new(false));
        let allowed = rustix::thread::sched_getaffinity(None).expect("sched_getaffinity");
        let threads = (0..rustix::thread::CpuSet::MAX_CPU)
            .filter(|&c| allowed.is_set(c))
            .map(|cpu| {
                let stop = stop.clone();
                std::thread::spawn(move || meter(cpu, stop))
            })
            .collect();
        Self { stop, threads }
    }

    /// Stops the meters; what they saw.
    pub fn stop(self) -> Stalls {
        self.stop.store(true, Ordering::Relaxed);
        let mut s = Stalls {
            cpus: self.threads.len(),
            ..Stalls::default()
        };
        for t in self.threads {
            match t.join().expect("a meter thread panicked") {
                Ok(g) => s.gaps.extend(g),
                Err(e) => s.unusable = Some(e),
            }
        }
        s
    }
}

/// handd's late ticks between two statuses, judged against the meters.
#[derive(Debug, Clone, Default)]
pub struct Judged {
    /// Deadline misses between the two statuses.
    pub misses: u64,
    /// Each late tick the status kept, with the part of its lateness no gap covers, µs.
    pub ticks: Vec<(LateTick, u64)>,
    /// Misses charged to handd.
    pub handd: u64,
    /// The slack, µs.
    pub slack_us: u64,
    /// What the meters saw, for the printout.
    pub stalls: Stalls,
}

impl Stalls {
    /// The part of `late`'s lateness that no gap on its CPU covers, µs.
    pub fn uncovered_us(&self, late: &LateTick) -> u64 {
        let (from, to) = (
            late.deadline_mono_us,
            late.deadline_mono_us + late.lateness_us(),
        );
        let covered: u64 = self
            .gaps
            .iter()
            .filter(|g| g.cpu == late.cpu)
            .map(|g| to.min(g.to_us).saturating_sub(from.max(g.from_us)))
            .sum();
        late.lateness_us().saturating_sub(covered)
    }

    /// The misses between `before` and `after` that are handd's own.
    pub fn judge(self, before: &Status, after: &Status, slack_us: u64) -> Judged {
        let misses = after.deadline_misses - before.deadline_misses;
        let kept = after.late_ticks.len() as u64;
        let ticks: Vec<(LateTick, u64)> = after.late_ticks[(kept - misses.min(kept)) as usize..]
            .iter()
            .map(|t| (*t, self.uncovered_us(t)))
            .collect();
        let handd = if self.unusable.is_some() || misses > kept {
            misses
        } else {
            ticks.iter().filter(|(_, u)| *u > slack_us).count() as u64
        };
        Judged {
            misses,
            ticks,
            handd,
            slack_us,
            stalls: self,
        }
    }
}

impl std::fmt::Display for Judged {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let longest = self.stalls.gaps.iter().map(|g| g.to_us - g.from_us).max();
        write!(
            f,
            "{} deadline misses, {} of them handd's (beyond the {} us slack once the time its \
             CPU did not run is taken out); the {} CPU meters saw {} gaps over {} us, the \
             longest {} us",
            self.misses,
            self.handd,
            self.slack_us,
            self.stalls.cpus,
            self.stalls.gaps.len(),
            GAP_MIN_US,
            longest.unwrap_or(0)
        )?;
        if let Some(why) = &self.stalls.unusable {
            write!(f, " (the meters cannot vouch for the machine: {why})")?;
        }
        for (t, uncovered) in &self.ticks {
            write!(
                f,
                "\n  late tick at CLOCK_MONOTONIC {} us on CPU {}: {} us late (woke {} us, read \
                 {} us, {} frames), {} us of it while CPU {} ran nothing",
                t.deadline_mono_us,
                t.cpu,
                t.lateness_us(),
                t.wake_us,
                t.read_us,
                t.frames,
                t.lateness_us() - uncovered,
                t.cpu
            )?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn late(at: u64, wake: u64, cpu: u32) -> LateTick {
        LateTick {
            deadline_mono_us: at,
            wake_us: wake,
            read_us: 1_000,
            frames: 40,
            cpu,
        }
    }

    fn status(misses: u64, late_ticks: Vec<LateTick>) -> Status {
        Status {
            deadline_misses: misses,
            late_ticks,
            ..Status::default()
        }
    }

    fn stalls(gaps: &[(u32, u64, u64)]) -> Stalls {
        Stalls {
            gaps: gaps
                .iter()
                .map(|&(cpu, from_us, to_us)| Gap {
                    cpu,
                    from_us,
                    to_us,
                })
                .collect(),
            unusable: None,
            cpus: 2,
        }
    }

    #[test]
    fn only_a_gap_on_the_ticks_own_cpu_excuses_its_lateness() {
        // 31 ms late on CPU 1; CPU 1 ran nothing for 20 ms of it: 11 ms is handd's, within
        // the 25 ms slack. The same gap on CPU 0 excuses nothing.
        let t = late(1_000_000, 30_000, 1);
        let before = status(3, vec![]);
        let after = status(4, vec![late(10, 30_000, 0), t]);
        let j = stalls(&[(1, 1_005_000, 1_025_000)]).judge(&before, &after, 25_000);
        assert_eq!((j.misses, j.handd), (1, 0), "{j}");
        assert_eq!(j.ticks, vec![(t, 11_000)]);
        let j = stalls(&[(0, 1_005_000, 1_025_000)]).judge(&before, &after, 25_000);
        assert_eq!(j.handd, 1, "{j}");
        // A gap that covers only 5 ms leaves 26 ms: handd's.
        let j = stalls(&[(1, 1_026_000, 1_040_000)]).judge(&before, &after, 25_000);
        assert_eq!(j.handd, 1, "{j}");
    }

    #[test]
    fn misses_the_meters_cannot_see_are_handds() {
        let after = status(9, (0..8).map(|i| late(i * 50_000, 30_000, 0)).collect());
        // Nine misses, eight kept: all charged, however the gaps fall.
        let j = stalls(&[(0, 0, 10_000_000)]).judge(&Status::default(), &after, 25_000);
        assert_eq!(j.handd, 9, "{j}");
        // Meters without SCHED_FIFO vouch for nothing.
        let mut s = stalls(&[(0, 0, 10_000_000)]);
        s.unusable = Some("not permitted".into());
        let j = s.judge(&status(8, vec![]), &after, 25_000);
        assert_eq!(j.handd, 1, "{j}");
        assert!(j.to_string().contains("cannot vouch"), "{j}");
    }
}
