//! The terminal UI loop: events from the source as they come, the screen redrawn at 10 Hz,
//! keys read in between.

use std::sync::mpsc::Receiver;
use std::time::{Duration, Instant};

use ratatui::crossterm::event::{self, Event as TermEvent, KeyCode, KeyEventKind};

use super::feed::{Event, Monitor};
use super::screen::draw;
use super::view::{Action, View};
use crate::error::CliError;

/// The redraw period (10 Hz).
pub const REFRESH: Duration = Duration::from_millis(100);

fn action(code: KeyCode) -> Option<Action> {
    match code {
        KeyCode::Right | KeyCode::Down | KeyCode::Tab | KeyCode::Char('n') => {
            Some(Action::NextFinger)
        }
        KeyCode::Left | KeyCode::Up | KeyCode::BackTab | KeyCode::Char('p') => {
            Some(Action::PrevFinger)
        }
        KeyCode::Char(c @ '1'..='5') => Some(Action::Finger(c as usize - '1' as usize)),
        KeyCode::Char('f') | KeyCode::Char(' ') => Some(Action::Freeze),
        KeyCode::Char('r') => Some(Action::Reset),
        KeyCode::Char('q') | KeyCode::Esc => Some(Action::Quit),
        _ => None,
    }
}

fn term_err(e: std::io::Error) -> CliError {
    CliError::Usage(format!("terminal: {e}"))
}

/// Runs the screen until the technician quits (or `seconds` of source time have passed).
pub fn run(
    m: &mut Monitor,
    view: &mut View,
    rx: &Receiver<Event>,
    seconds: Option<f64>,
) -> Result<(), CliError> {
    let mut term = ratatui::try_init().map_err(term_err)?;
    let result = (|| {
        let mut next_draw = Instant::now();
        loop {
            while let Ok(e) = rx.try_recv() {
                m.apply(e);
            }
            if seconds.is_some_and(|s| m.elapsed_s() >= s) {
                return Ok(());
            }
            let now = Instant::now();
            if now >= next_draw {
                term.draw(|f| draw(f, view.shown(&m.state), view))
                    .map_err(term_err)?;
                next_draw = now + REFRESH;
            }
            let wait = next_draw.saturating_duration_since(Instant::now());
            if event::poll(wait.min(Duration::from_millis(20))).map_err(term_err)? {
                if let TermEvent::Key(k) = event::read().map_err(term_err)? {
                    let act = (k.kind == KeyEventKind::Press).then(|| action(k.code));
                    if let Some(Some(a)) = act {
                        if !view.apply(a, &m.state) {
                            return Ok(());
                        }
                        next_draw = Instant::now();
                    }
                }
            }
        }
    })();
    ratatui::restore();
    result
}
