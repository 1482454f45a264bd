//! The daemon: state, faults in force, the model, tick latency, deadline misses, E2E errors,
//! lost samples, windows beyond the calibration and implausible ones, and bus load, in two
//! lines. Counters are shown since the technician's last
//! reset of the view ([`Baseline`]); the daemon's own totals are not touched.

use ratatui::buffer::Buffer;
use ratatui::layout::Rect;
use ratatui::style::{Color, Modifier, Style};
use ratatui::text::{Line, Span};
use ratatui::widgets::{Paragraph, Widget};

use crate::monitor::state::DaemonView;

/// The counters at the technician's last reset of the view.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Baseline {
    /// Deadline misses then.
    pub deadline_misses: u64,
    /// E2E errors then.
    pub e2e_errors: u64,
    /// Lost samples then.
    pub samples_lost: u64,
    /// Windows beyond the calibration then.
    pub beyond_calibration: u64,
    /// Implausible windows then.
    pub implausible: u64,
}

impl Baseline {
    /// The counters now: later counts show from zero.
    pub fn of(d: &DaemonView) -> Self {
        Self {
            deadline_misses: d.deadline_misses,
            e2e_errors: d.e2e_errors,
            samples_lost: d.samples_lost,
            beyond_calibration: d.beyond_calibration,
            implausible: d.implausible,
        }
    }
}

/// The daemon panel.
pub struct DaemonPanel<'a> {
    /// The daemon's side of the state.
    pub daemon: &'a DaemonView,
    /// Counters subtracted from the shown ones.
    pub baseline: &'a Baseline,
}

fn opt<T: std::fmt::Display>(v: Option<T>) -> String {
    v.map_or_else(|| "--".to_owned(), |v| v.to_string())
}

impl Widget for DaemonPanel<'_> {
    fn render(self, area: Rect, buf: &mut Buffer) {
        let d = self.daemon;
        let b = self.baseline;
        let state = d.state.clone().unwrap_or_else(|| "no daemon heard".into());
        let colour = match state.as_str() {
            "RUNNING" => Color::Green,
            "SAFE" => Color::Red,
            _ => Color::Yellow,
        };
        let faults = if d.faults.is_empty() {
            "none".to_owned()
        } else {
            d.faults.join(",")
        };
        let model = match (&d.model_id, &d.model_detail) {
            (Some(id), Some(x)) => format!("{id} {x}"),
            (Some(id), None) => id.clone(),
            (None, _) => "none".to_owned(),
        };
        let first = Line::from(vec![
            Span::styled(
                state,
                Style::default().fg(colour).add_modifier(Modifier::BOLD),
            ),
            Span::raw(format!("  faults {faults}  model {model}")),
        ]);
        let second = Line::from(format!(
            "latency p50 {} p99 {} us  misses {}  E2E {}  lost {}  beyond cal {}  implausible {}  bus {}  CAN {}",
            opt(d.latency_p50_us),
            opt(d.latency_p99_us),
            d.deadline_misses.saturating_sub(b.deadline_misses),
            d.e2e_errors.saturating_sub(b.e2e_errors),
            d.samples_lost.saturating_sub(b.samples_lost),
            d.beyond_calibration.saturating_sub(b.beyond_calibration),
            d.implausible.saturating_sub(b.implausible),
            d.bus_load
                .map_or_else(|| "--".to_owned(), |l| format!("{:.1}%", l * 100.0)),
            d.can.as_deref().unwrap_or("--"),
        ));
        Paragraph::new(vec![first, second]).render(area, buf);
    }
}
