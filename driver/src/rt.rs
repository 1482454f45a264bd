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

/// The calling thread's CPU time, ns.
pub fn thread_cpu_ns() -> u64 {
    let t = rustix::time::clock_gettime(rustix::time::ClockId::ThreadCPUTime);
    t.tv_sec as u64 * 1_000_000_000 + t.tv_nsec as u64
}

/// The CPU the calling thread runs on.
pub fn current_cpu() -> u32 {
    rustix::thread::sched_getcpu() as u32
}

#[cfg(test)]
mod tests {
    use super::*;

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
