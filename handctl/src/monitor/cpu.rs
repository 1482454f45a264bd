//! The monitor's own CPU use: the kernel's account of this process's user and system time
//! (`/proc/self/stat`, as getrusage reports it, in 10 ms clock ticks) over the wall time of the
//! run.

use std::time::Instant;

/// Clock ticks per second of `/proc/<pid>/stat` (USER_HZ, 100 on every Linux ABI).
const USER_HZ: f64 = 100.0;

/// CPU time of this process (all threads, user + system), s; 0 where `/proc` cannot be read.
fn process_cpu_s() -> f64 {
    let Ok(stat) = std::fs::read_to_string("/proc/self/stat") else {
        return 0.0;
    };
    // Fields after the command name (which may hold spaces, so split after its ')'): state is
    // field 3, utime field 14, stime field 15.
    let Some((_, rest)) = stat.rsplit_once(')') else {
        return 0.0;
    };
    let f: Vec<&str> = rest.split_whitespace().collect();
    let tick = |i: usize| f.get(i).and_then(|v| v.parse::<u64>().ok()).unwrap_or(0);
    (tick(11) + tick(12)) as f64 / USER_HZ
}

/// Started at the beginning of a run.
#[derive(Debug, Clone, Copy)]
pub struct CpuMeter {
    wall: Instant,
    cpu_s: f64,
}

impl CpuMeter {
    /// Starts measuring now.
    pub fn start() -> Self {
        Self {
            wall: Instant::now(),
            cpu_s: process_cpu_s(),
        }
    }

    /// (CPU seconds, wall seconds) since the start.
    pub fn used(&self) -> (f64, f64) {
        (
            process_cpu_s() - self.cpu_s,
            self.wall.elapsed().as_secs_f64(),
        )
    }

    /// "monitor used 1.2% of a core over 10.0 s at 10 Hz"; without a refresh rate (a log
    /// read as fast as possible) the CPU time alone.
    pub fn summary(&self, refresh_hz: Option<f64>) -> String {
        let (cpu, wall) = self.used();
        match refresh_hz {
            Some(hz) => format!(
                "monitor used {:.1}% of a core over {wall:.1} s at {hz:.0} Hz ({cpu:.2} s CPU)",
                100.0 * cpu / wall.max(1e-9)
            ),
            None => format!(
                "monitor used {cpu:.2} s CPU in {wall:.2} s (a log read as fast as possible)"
            ),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn busy_work_shows_as_cpu_time() {
        let m = CpuMeter::start();
        let mut x = 0u64;
        let start = Instant::now();
        while start.elapsed().as_millis() < 100 {
            x = x.wrapping_mul(6364136223846793005).wrapping_add(1);
        }
        std::hint::black_box(x);
        let (cpu, wall) = m.used();
        assert!(cpu > 0.0 && wall > 0.0, "cpu {cpu} wall {wall}");
        assert!(m.summary(Some(10.0)).contains("of a core"));
    }
}
