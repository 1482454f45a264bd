//! `--plain`: one line per second of source time instead of the screen, for logs and for a
//! terminal that is not a TTY.

use hand_dbc::hand::FINGER_NAMES;

use super::cpu::CpuMeter;
use super::state::MonitorState;
use super::widgets::drive_cell;

/// Prints a line whenever a second of source time has passed.
#[derive(Debug, Clone, Default)]
pub struct PlainPrinter {
    next_us: Option<u64>,
}

impl PlainPrinter {
    /// The line for `st` if a second has passed since the last one.
    pub fn due(&mut self, st: &MonitorState) -> bool {
        if st.t_us == 0 {
            return false;
        }
        let next = *self.next_us.get_or_insert(st.t_us);
        if st.t_us < next {
            return false;
        }
        self.next_us = Some(next + 1_000_000 * ((st.t_us - next) / 1_000_000 + 1));
        true
    }
}

fn join(v: impl Iterator<Item = String>) -> String {
    v.collect::<Vec<_>>().join(" ")
}

/// One line: time, daemon, per channel RMS (µV, flags appended), per finger label, commanded
/// and reported force, and the monitor's CPU use.
pub fn line(st: &MonitorState, cpu: &CpuMeter) -> String {
    let d = &st.daemon;
    let o = |v: Option<u64>| v.map_or_else(|| "--".to_owned(), |v| v.to_string());
    let rms = join(st.channels.iter().map(|c| {
        let mut s = format!("{:.1}", c.rms_uv);
        for (on, f) in [(c.lead_off, 'L'), (c.saturated, 'S'), (c.noisy, 'N')] {
            if on {
                s.push(f);
            }
        }
        s
    }));
    let fingers = join(st.fingers.iter().enumerate().map(|(f, v)| {
        format!(
            "{}:{}/{:+.1}/{:+.1}{}",
            &FINGER_NAMES[f][..2],
            v.label
                .map_or_else(|| "--".to_owned(), |l| format!("{l:+.2}")),
            v.force_n,
            v.reported_force_n,
            if v.disabled { "!" } else { "" }
        )
    }));
    let drives = if st.drives.is_empty() {
        String::new()
    } else {
        let each: Vec<String> = st
            .drives
            .iter()
            .map(|d| format!("{} n{} {}", d.finger, d.node, drive_cell(d)))
            .collect();
        format!(" | drives {}", each.join(", "))
    };
    let (c, w) = cpu.used();
    format!(
        "t {:.1} s {} faults {} model {} | latency p50 {} p99 {} us misses {} e2e {} lost {} beyond {} implausible {} bus {} CAN {} | rms uV {rms} | label/F/reported {fingers}{drives} | cpu {:.1}%",
        st.elapsed_s(),
        d.state.as_deref().unwrap_or("--"),
        if d.faults.is_empty() { "none".to_owned() } else { d.faults.join(",") },
        d.model_id.as_deref().unwrap_or("--"),
        o(d.latency_p50_us),
        o(d.latency_p99_us),
        d.deadline_misses,
        d.e2e_errors,
        d.samples_lost,
        d.beyond_calibration,
        d.implausible,
        d.bus_load.map_or_else(|| "--".to_owned(), |l| format!("{:.1}%", l * 100.0)),
        d.can.as_deref().unwrap_or("--"),
        100.0 * c / w.max(1e-9),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_line_per_second_of_source_time() {
        let mut p = PlainPrinter::default();
        let mut st = MonitorState::new("t", 2);
        let mut printed = 0;
        for k in 1..=35u64 {
            st.t_us = 1_000_000 + k * 100_000;
            printed += usize::from(p.due(&st));
        }
        assert_eq!(printed, 4, "at 1.1, 2.1, 3.1 and 4.1 s");
        st.channels[1].lead_off = true;
        let l = line(&st, &CpuMeter::start());
        assert!(l.contains("rms uV 0.0 0.0L"), "{l}");
        assert!(l.contains("in:--/+0.0/+0.0"), "{l}");
    }
}
