//! The monitor's own CPU use: the process's CPU time (all threads, user + system;
//! `clock_gettime(CLOCK_PROCESS_CPUTIME_ID)` through `cpu-time`) over the wall time of the run.

use std::time::Instant;

use cpu_time::ProcessTime;

/// Started at the beginning of a run.
#[derive(Debug, Clone, Copy)]
pub struct CpuMeter {
    wall: Instant,
    cpu: ProcessTime,
}

impl CpuMeter {
    /// Starts measuring now.
    pub fn start() -> Self {
        Self {
            wall: Instant::now(),
            cpu: ProcessTime::now(),
        }
    }

    /// (CPU seconds, wall seconds) since the start.
    pub fn used(&self) -> (f64, f64) {
        (
            self.cpu.elapsed().as_secs_f64(),
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
