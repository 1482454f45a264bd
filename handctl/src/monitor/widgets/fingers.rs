//! Per finger: conditioned label, commanded force and velocity, the controller's reported
//! position and force, and whether it is active, holding or disabled; the selected finger
//! (the plot's) marked with `>`. Below, each CiA 402 finger's drive: its node, its CiA 402
//! power state and how old its last TPDO1 is, or why it is stopped (the EMCY code), `!!` when
//! stopped.

use ratatui::buffer::Buffer;
use ratatui::layout::Rect;
use ratatui::style::{Color, Modifier, Style};
use ratatui::text::Line;
use ratatui::widgets::{Block, Borders, Paragraph, Widget};

use hand_dbc::hand::FINGER_NAMES;

use driver::protocol::DriveLine;

use crate::monitor::state::FingerView;

/// The finger table.
pub struct FingerTable<'a> {
    /// The fingers, 0 thumb .. 4 pinky.
    pub fingers: &'a [FingerView],
    /// The selected finger.
    pub selected: usize,
    /// The CiA 402 fingers' drives (empty: every finger native).
    pub drives: &'a [DriveLine],
}

/// A drive's state in a few words: `Operation enabled 12ms` (its CiA 402 power state and the
/// age of its TPDO1), `starting`, `STOPPED EMCY 0x2310`, `STOPPED (arm)`.
pub fn drive_cell(d: &DriveLine) -> String {
    if let Some(e) = &d.emcy {
        let code = e.split_whitespace().next().unwrap_or("");
        return format!("STOPPED EMCY {code}");
    }
    if d.faulted {
        return "STOPPED (arm)".into();
    }
    match (&d.power_state, d.feedback_age_ms) {
        (Some(p), Some(a)) => format!("{p} {a}ms"),
        (Some(p), None) => p.clone(),
        (None, _) if d.nmt == "starting" => "starting".into(),
        (None, _) => format!("{} no TPDO1", d.nmt),
    }
}

/// The header row.
pub const HEADER: &str = " finger label   F N  v r/s   pos rep N st ";

impl FingerTable<'_> {
    /// The text of one finger's row.
    pub fn row(f: usize, v: &FingerView, selected: bool) -> String {
        let label = v
            .label
            .map_or_else(|| "   --".to_owned(), |l| format!("{l:>+5.2}"));
        let st = if v.disabled {
            "OFF"
        } else if v.active {
            "ACT"
        } else {
            "hld"
        };
        format!(
            "{}{:<6} {label} {:>+5.1} {:>+6.2} {:>5.2} {:>+5.1} {st}",
            if selected { '>' } else { ' ' },
            FINGER_NAMES.get(f).copied().unwrap_or("?"),
            v.force_n,
            v.velocity_rad_s,
            v.position_rad,
            v.reported_force_n,
        )
    }
}

impl Widget for FingerTable<'_> {
    fn render(self, area: Rect, buf: &mut Buffer) {
        let mut lines = vec![Line::styled(
            HEADER,
            Style::default().add_modifier(Modifier::BOLD),
        )];
        for (f, v) in self.fingers.iter().enumerate() {
            let text = Self::row(f, v, f == self.selected);
            let style = if f == self.selected {
                Style::default().add_modifier(Modifier::REVERSED)
            } else {
                Style::default()
            };
            lines.push(Line::styled(text, style));
        }
        if !self.drives.is_empty() {
            lines.push(Line::styled(
                " CiA 402 drives",
                Style::default().add_modifier(Modifier::BOLD),
            ));
        }
        for d in self.drives {
            let text = format!(
                "{}{:<6} n{:<3} {}",
                if d.faulted { "!!" } else { "  " },
                d.finger,
                d.node,
                drive_cell(d)
            );
            let style = if d.faulted {
                Style::default().fg(Color::Red).add_modifier(Modifier::BOLD)
            } else {
                Style::default()
            };
            lines.push(Line::styled(text, style));
        }
        Paragraph::new(lines)
            .block(Block::default().borders(Borders::ALL).title("fingers"))
            .render(area, buf);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_row_lines_up_with_the_header() {
        let v = FingerView {
            label: Some(-0.45),
            force_n: 12.3,
            velocity_rad_s: -1.25,
            position_rad: 0.8,
            reported_force_n: 11.9,
            disabled: false,
            active: true,
        };
        let row = FingerTable::row(1, &v, true);
        assert_eq!(row, ">index  -0.45 +12.3  -1.25  0.80 +11.9 ACT");
        assert_eq!(row.len(), HEADER.len());
        let none = FingerTable::row(4, &FingerView::default(), false);
        assert!(none.starts_with(" pinky     --"), "{none}");
        assert!(none.ends_with("hld"), "{none}");
    }
}
