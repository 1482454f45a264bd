//! Real-time set-up of the daemon: lock memory (no page fault in the tick) and, if asked, a
//! SCHED_FIFO priority for the control thread. Neither is required to run: when the process is
//! not permitted (no CAP_IPC_LOCK / RLIMIT_MEMLOCK, no RLIMIT_RTPRIO), the daemon says so
//! clearly and goes on, since a working hand with more jitter beats no hand.

use thread_priority::{
    set_thread_priority_and_policy, thread_native_id, RealtimeThreadSchedulePolicy, ThreadPriority,
    ThreadPriorityValue, ThreadSchedulePolicy,
};

/// What the real-time set-up achieved, for the log and `handctl status`.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct RtReport {
    /// Memory is locked.
    pub memory_locked: bool,
    /// The SCHED_FIFO priority in force, if any.
    pub fifo_priority: Option<u8>,
    /// Warnings, one per step that was not permitted.
    pub warnings: Vec<String>,
}

/// Lock all current and future pages into memory.
pub fn lock_memory(report: &mut RtReport) {
    use rustix::mm::{mlockall, MlockAllFlags};
    match mlockall(MlockAllFlags::CURRENT | MlockAllFlags::FUTURE) {
        Ok(()) => report.memory_locked = true,
        Err(e) => report.warnings.push(format!(
            "mlockall failed ({e}): memory is not locked, so page faults may delay ticks; \
             run as root, or give the service LimitMEMLOCK=infinity or CAP_IPC_LOCK"
        )),
    }
}

/// Give the calling thread SCHED_FIFO at `priority` (1..=99).
pub fn set_fifo(priority: u8, report: &mut RtReport) {
    let value = match ThreadPriorityValue::try_from(priority.clamp(1, 99)) {
        Ok(v) => v,
        Err(e) => {
            report.warnings.push(format!(
                "SCHED_FIFO priority {priority} is not valid: {e:?}"
            ));
            return;
        }
    };
    let policy = ThreadSchedulePolicy::Realtime(RealtimeThreadSchedulePolicy::Fifo);
    match set_thread_priority_and_policy(
        thread_native_id(),
        ThreadPriority::Crossplatform(value),
        policy,
    ) {
        Ok(()) => report.fifo_priority = Some(priority),
        Err(e) => report.warnings.push(format!(
            "SCHED_FIFO priority {priority} not permitted ({e:?}): the control thread runs with \
             normal scheduling; give the service LimitRTPRIO={priority} or CAP_SYS_NICE"
        )),
    }
}

/// The machine's CLOCK_MONOTONIC, µs: the one time base of every process on the machine,
/// to line up what the daemon saw with what others saw (the daemon's own clock counts from
/// its start).
pub fn monotonic_us() -> u64 {
    let t = rustix::time::clock_gettime(rustix::time::ClockId::Monotonic);
    t.tv_sec as u64 * 1_000_000 + t.tv_nsec as u64 / 1_000
}

/// What the calling thread used so far: its CPU time and its context switches.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ThreadUsage {
    /// CPU time, user and system, µs.
    pub cpu_us: u64,
    /// Voluntary context switches (it waited).
    pub waited: u64,
    /// Involuntary context switches (another thread took its CPU).
    pub preempted: u64,
}

impl ThreadUsage {
    /// The calling thread's, now (one `getrusage(RUSAGE_THREAD)`; all zero if it fails).
    pub fn now() -> Self {
        use nix::sys::resource::{getrusage, UsageWho};
        let Ok(u) = getrusage(UsageWho::RUSAGE_THREAD) else {
            return Self::default();
        };
        let us = |t: nix::sys::time::TimeVal| {
            (t.tv_sec().max(0) as u64) * 1_000_000 + t.tv_usec().max(0) as u64
        };
        Self {
            cpu_us: us(u.user_time()) + us(u.system_time()),
            waited: u.voluntary_context_switches().max(0) as u64,
            preempted: u.involuntary_context_switches().max(0) as u64,
        }
    }

    /// What was used from `earlier` to this.
    pub fn since(self, earlier: Self) -> Self {
        Self {
            cpu_us: self.cpu_us.saturating_sub(earlier.cpu_us),
            waited: self.waited.saturating_sub(earlier.waited),
            preempted: self.preempted.saturating_sub(earlier.preempted),
        }
    }
}

/// The CPU the calling thread runs on.
pub fn current_cpu() -> u32 {
    rustix::thread::sched_getcpu() as u32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thread_usage_counts_a_wait_and_cpu_time() {
        let before = ThreadUsage::now();
        std::thread::sleep(std::time::Duration::from_millis(2));
        let slept = ThreadUsage::now().since(before);
        assert!(
            slept.waited >= 1,
            "a sleep is a voluntary switch: {slept:?}"
        );
        // Spin until 5 ms of CPU time show (on a loaded machine that takes longer than 5 ms
        // of wall time); a usage that never grew would time out.
        let start = std::time::Instant::now();
        let mut x = 0u64;
        let spun = loop {
            for _ in 0..100_000 {
                x = std::hint::black_box(x.wrapping_add(1));
            }
            let spun = ThreadUsage::now().since(before);
            if spun.cpu_us >= 5_000 || start.elapsed() > std::time::Duration::from_secs(20) {
                break spun;
            }
        };
        assert!(spun.cpu_us >= 5_000, "spinning is CPU time: {spun:?}");
        assert_eq!(ThreadUsage::default().since(spun), ThreadUsage::default());
    }

    #[test]
    fn set_up_reports_success_or_a_clear_warning() {
        let mut r = RtReport::default();
        lock_memory(&mut r);
        assert!(
            r.memory_locked || r.warnings.iter().any(|w| w.contains("mlockall")),
            "{r:?}"
        );
        // Other tests of this process must not run under MCL_FUTURE and its memlock limit.
        rustix::mm::munlockall().unwrap();
        // Runs on its own thread, so the test runner's threads keep their policy.
        let r = std::thread::spawn(|| {
            let mut r = RtReport::default();
            set_fifo(10, &mut r);
            r
        })
        .join()
        .unwrap();
        assert!(
            r.fifo_priority == Some(10) || r.warnings.iter().any(|w| w.contains("LimitRTPRIO")),
            "{r:?}"
        );
    }
}
