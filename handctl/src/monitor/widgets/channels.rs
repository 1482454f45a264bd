//! Per EMG channel: the amplitude as a bar on a log scale, the calibration's rest level marked
//! on it, the value in µV and the lead-off, saturation and noisy flags.

use ratatui::buffer::Buffer;
use ratatui::layout::Rect;
use ratatui::style::{Color, Style};
use ratatui::text::{Line, Span};
use ratatui::widgets::{Block, Borders, Paragraph, Widget};

use crate::monitor::state::ChannelView;

/// The bar's left end, µV (below: empty bar).
pub const BAR_MIN_UV: f64 = 1.0;
/// The bar's right end, µV (three decades: rest to a strong contraction).
pub const BAR_MAX_UV: f64 = 1000.0;

/// The bar of `width` cells for `rms_uv` on the log scale, with `│` at the rest level (`┃`
/// where the bar covers it): what the technician compares at a glance.
pub fn bar_cells(rms_uv: f64, rest_uv: Option<f64>, width: usize) -> String {
    let pos = |uv: f64| {
        let x = (uv.max(BAR_MIN_UV) / BAR_MIN_UV).log10() / (BAR_MAX_UV / BAR_MIN_UV).log10();
        (x.clamp(0.0, 1.0) * width as f64).round() as usize
    };
    let filled = if rms_uv.is_finite() { pos(rms_uv) } else { 0 };
    let mark = rest_uv
        .filter(|r| r.is_finite())
        .map(|r| pos(r).min(width.saturating_sub(1)));
    (0..width)
        .map(|i| match (i < filled, Some(i) == mark) {
            (true, true) => '┃',
            (false, true) => '│',
            (true, false) => '█',
            (false, false) => '·',
        })
        .collect()
}

/// The channel bars (see the module docs); one row per channel inside a bordered block.
pub struct ChannelBars<'a> {
    /// The channels.
    pub channels: &'a [ChannelView],
}

impl ChannelBars<'_> {
    /// The text of one channel's row, `width` cells wide.
    pub fn row(c: usize, v: &ChannelView, width: usize) -> Line<'static> {
        // "11  123.4 " + bar + " LSN"
        let bar_w = width.saturating_sub(14).max(4);
        let flag = |on: bool, ch: char| if on { ch } else { ' ' };
        let flags: String = [
            flag(v.lead_off, 'L'),
            flag(v.saturated, 'S'),
            flag(v.noisy, 'N'),
        ]
        .iter()
        .collect();
        let alarm = v.lead_off || v.saturated || v.noisy;
        Line::from(vec![
            Span::raw(format!("{c:>2} {:>6.1} ", v.rms_uv)),
            Span::styled(
                bar_cells(v.rms_uv, v.rest_uv, bar_w),
                Style::default().fg(Color::Green),
            ),
            Span::styled(
                format!(" {flags}"),
                Style::default().fg(if alarm { Color::Red } else { Color::Reset }),
            ),
        ])
    }
}

impl Widget for ChannelBars<'_> {
    fn render(self, area: Rect, buf: &mut Buffer) {
        let rest = if self.channels.iter().all(|c| c.rest_uv.is_some()) {
            "│rest"
        } else {
            "rest ?"
        };
        let block = Block::default()
            .borders(Borders::ALL)
            .title(format!("EMG µV 1-1000 log {rest} L/S/N"));
        let width = block.inner(area).width as usize;
        let lines: Vec<Line<'_>> = self
            .channels
            .iter()
            .enumerate()
            .map(|(c, v)| Self::row(c, v, width))
            .collect();
        Paragraph::new(lines).block(block).render(area, buf);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_bar_is_logarithmic_and_marks_the_rest_level() {
        assert_eq!(bar_cells(0.5, None, 12), "············");
        assert_eq!(bar_cells(1000.0, None, 12), "████████████");
        // 10 µV is one decade of three: a third of the bar.
        assert_eq!(bar_cells(10.0, None, 12), "████········");
        assert_eq!(bar_cells(100.0, Some(10.0), 12), "████┃███····");
        assert_eq!(bar_cells(5.0, Some(100.0), 12), "███·····│···");
        assert_eq!(bar_cells(f64::NAN, Some(1e9), 4), "···│");
    }
}
