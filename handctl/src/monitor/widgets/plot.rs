//! The selected finger's label against its reported force, scrolling: label on [-1, 1], force
//! divided by a full scale (the larger of 10 N and the largest force in the history) so both
//! share the axis; the scale is in the title.

use ratatui::buffer::Buffer;
use ratatui::layout::Rect;
use ratatui::style::{Color, Style};
use ratatui::symbols::Marker;
use ratatui::widgets::{Axis, Block, Borders, Chart, Dataset, GraphType, Widget};

use hand_dbc::hand::FINGER_NAMES;

use crate::monitor::state::History;

/// Smallest force full scale of the plot, N.
const MIN_FORCE_SCALE_N: f64 = 10.0;

/// The plot.
pub struct FingerPlot<'a> {
    /// The history.
    pub history: &'a History,
    /// Which finger.
    pub finger: usize,
}

impl Widget for FingerPlot<'_> {
    fn render(self, area: Rect, buf: &mut Buffer) {
        let pts: Vec<(f64, f64, f64)> = self.history.finger(self.finger).collect();
        let scale = pts
            .iter()
            .map(|p| p.2.abs())
            .fold(MIN_FORCE_SCALE_N, f64::max);
        let label: Vec<(f64, f64)> = pts
            .iter()
            .filter(|p| p.1.is_finite())
            .map(|p| (p.0, p.1.clamp(-1.0, 1.0)))
            .collect();
        let force: Vec<(f64, f64)> = pts.iter().map(|p| (p.0, p.2 / scale)).collect();
        let t1 = pts.last().map_or(1.0, |p| p.0);
        let t0 = pts.first().map_or(0.0, |p| p.0).min(t1 - 1.0);
        let name = FINGER_NAMES.get(self.finger).copied().unwrap_or("?");
        let title = format!("{name}: label (green) vs reported force / {scale:.0} N (yellow)");
        let datasets = vec![
            Dataset::default()
                .marker(Marker::Braille)
                .graph_type(GraphType::Line)
                .style(Style::default().fg(Color::Green))
                .data(&label),
            Dataset::default()
                .marker(Marker::Braille)
                .graph_type(GraphType::Line)
                .style(Style::default().fg(Color::Yellow))
                .data(&force),
        ];
        Chart::new(datasets)
            .block(Block::default().borders(Borders::ALL).title(title))
            .x_axis(Axis::default().bounds([t0, t1]))
            .y_axis(Axis::default().bounds([-1.0, 1.0]))
            .render(area, buf);
    }
}
