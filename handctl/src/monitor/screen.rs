//! The whole screen from a state and the technician's view of it; 80x24 and larger. Also
//! renders into ratatui's test backend as text (`--screen`, the tests, the README's capture).

use ratatui::backend::TestBackend;
use ratatui::layout::{Constraint, Layout};
use ratatui::text::Line;
use ratatui::widgets::Paragraph;
use ratatui::{Frame, Terminal};

use super::state::MonitorState;
use super::view::View;
use super::widgets::{ChannelBars, DaemonPanel, FingerPlot, FingerTable};

/// Rows of the channel and finger panels: 12 channels and the block's borders.
const MIDDLE_ROWS: u16 = 14;

/// Draws the monitor.
pub fn draw(frame: &mut Frame<'_>, st: &MonitorState, view: &View) {
    let [title, daemon, middle, plot] = Layout::vertical([
        Constraint::Length(1),
        Constraint::Length(2),
        Constraint::Length(MIDDLE_ROWS),
        Constraint::Min(5),
    ])
    .areas(frame.area());
    let [left, right] =
        Layout::horizontal([Constraint::Percentage(45), Constraint::Percentage(55)]).areas(middle);
    frame.render_widget(Paragraph::new(title_line(st, view)), title);
    frame.render_widget(
        DaemonPanel {
            daemon: &st.daemon,
            baseline: &view.baseline,
        },
        daemon,
    );
    frame.render_widget(
        ChannelBars {
            channels: &st.channels,
        },
        left,
    );
    frame.render_widget(
        FingerTable {
            fingers: &st.fingers,
            selected: view.finger,
        },
        right,
    );
    frame.render_widget(
        FingerPlot {
            history: &st.history,
            finger: view.finger,
        },
        plot,
    );
}

fn title_line(st: &MonitorState, view: &View) -> Line<'static> {
    // Why it ended goes to stderr on exit: the title stays within 80 columns.
    let status = match (&st.ended, view.frozen) {
        (_, true) => " FROZEN",
        (Some(_), false) => " ENDED",
        (None, false) => "",
    };
    Line::from(format!(
        "{} t {:.1} s{status} | <- -> finger  f freeze  r reset  q quit",
        st.source,
        st.elapsed_s()
    ))
}

/// The screen as text, rendered into ratatui's test backend at `cols` x `rows`: one string per
/// row, trailing blanks kept.
pub fn render_text(st: &MonitorState, view: &View, cols: u16, rows: u16) -> Vec<String> {
    let mut term =
        Terminal::new(TestBackend::new(cols, rows)).expect("the test backend cannot fail to start");
    term.draw(|f| draw(f, st, view))
        .expect("the test backend cannot fail to draw");
    let buf = term.backend().buffer();
    (0..rows)
        .map(|y| {
            (0..cols)
                .map(|x| buf[(x, y)].symbol().to_owned())
                .collect::<String>()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_empty_state_fits_80x24_and_says_what_is_unknown() {
        let st = MonitorState::new("bus can0", 12);
        let rows = render_text(&st, &View::default(), 80, 24);
        assert_eq!(rows.len(), 24);
        let all = rows.join("\n");
        assert!(all.contains("no daemon heard"), "{all}");
        assert!(all.contains(">thumb"), "{all}");
        assert!(all.contains("pinky"), "{all}");
        // All 12 channels are on screen.
        assert!(rows.iter().any(|r| r.starts_with("│11    0.0 ")), "{all}");
    }
}
