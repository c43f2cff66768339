//! The help overlay: every key.

use ratatui::buffer::Buffer;
use ratatui::layout::{Constraint, Rect};
use ratatui::style::{Color, Modifier};
use ratatui::widgets::{Clear, Row, Table, Widget};

use crate::tui::keymap::HELP;
use crate::tui::theme::Theme;

/// The help overlay, centred over the screen.
pub struct Help {
    /// Colours.
    pub theme: Theme,
}

impl Widget for &Help {
    fn render(self, area: Rect, buf: &mut Buffer) {
        let height = (HELP.len() as u16 + 2).min(area.height);
        let width = 56.min(area.width);
        let popup = Rect {
            x: area.x + (area.width - width) / 2,
            y: area.y + (area.height - height) / 2,
            width,
            height,
        };
        Clear.render(popup, buf);
        let rows = HELP
            .iter()
            .map(|(k, v)| Row::new([k.to_string(), v.to_string()]));
        Table::new(rows, [Constraint::Length(13), Constraint::Min(0)])
            .block(self.theme.block(" Keys (Esc or ? closes) ".into(), true))
            .style(self.theme.fg(Color::Reset).add_modifier(Modifier::empty()))
            .render(popup, buf);
    }
}
