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
            drives: &st.drives,
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
        assert!(
            !all.contains("CiA 402"),
            "no drive, no drive section: {all}"
        );
    }

    /// Issue 26 item 9: the finger panel lists every CiA 402 drive at 80x24: its node, power
    /// state and feedback age, or the EMCY that stopped it, flagged; the plain line too.
    #[test]
    fn five_drives_fit_the_finger_panel_at_80x24() {
        use driver::protocol::DriveLine;
        use hand_canopen::master::{DriveFault, DriveStatus, Feedback};
        use hand_canopen::{Emcy, NodeId, PowerState, Statusword};
        let running = |at_us| DriveStatus::Running {
            enabled: true,
            identity: Default::default(),
            feedback: Some(Feedback {
                statusword: Statusword::of(PowerState::OperationEnabled),
                torque_permille: 0,
                velocity_rpm: 0,
                at_us,
            }),
        };
        let trip = Emcy {
            node: NodeId::try_new(9).unwrap(),
            code: 0x2310,
            register: 0x03,
            vendor: [0; 5],
        };
        let now = 5_000_000;
        let mut st = MonitorState::new("daemon", 12);
        st.drives = vec![
            DriveLine::of("thumb", 5, &running(now - 12_000), now),
            DriveLine::of("index", 6, &running(now - 3_000), now),
            DriveLine::of(
                "middle",
                7,
                &DriveStatus::Faulted(DriveFault::Rebooted),
                now,
            ),
            DriveLine::of(
                "ring",
                8,
                &DriveStatus::Starting(hand_canopen::startup::Step::ResetCommunication),
                now,
            ),
            DriveLine::of(
                "pinky",
                9,
                &DriveStatus::Faulted(DriveFault::Emcy(trip)),
                now,
            ),
        ];
        let rows = render_text(&st, &View::default(), 80, 24);
        let all = rows.join("\n");
        for want in [
            "CiA 402 drives",
            "  thumb  n5   Operation enabled 12ms",
            "  index  n6   Operation enabled 3ms",
            "!!middle n7   STOPPED (arm)",
            "  ring   n8   starting",
            "!!pinky  n9   STOPPED EMCY 0x2310",
        ] {
            assert!(all.contains(want), "{want:?} missing:\n{all}");
        }
        let l = super::super::plain::line(&st, &super::super::cpu::CpuMeter::start());
        assert!(
            l.contains("| drives thumb n5 Operation enabled 12ms, index n6 Operation enabled 3ms"),
            "{l}"
        );
    }
}
