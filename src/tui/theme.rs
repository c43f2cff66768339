//! Colours, or none when `NO_COLOR` is set: the one place the TUI's styles come from.

use ratatui::style::{Color, Modifier, Style};
use ratatui::widgets::{Block, Borders};

/// The TUI's styles.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Theme {
    /// Whether to use colours.
    pub color: bool,
}

impl Theme {
    /// From the environment: no colours when `NO_COLOR` is set and not empty.
    pub fn from_env() -> Self {
        Self {
            color: std::env::var_os("NO_COLOR").is_none_or(|v| v.is_empty()),
        }
    }

    /// `style` with foreground `c`, or plain without colours.
    pub fn fg(self, c: Color) -> Style {
        if self.color {
            Style::default().fg(c)
        } else {
            Style::default()
        }
    }

    /// The style of something selected: reversed (and bold with colours).
    pub fn selected(self) -> Style {
        let reversed = Style::default().add_modifier(Modifier::REVERSED);
        if self.color {
            reversed.add_modifier(Modifier::BOLD)
        } else {
            reversed
        }
    }

    /// A pane's frame, brighter when focused.
    pub fn block(self, title: String, focused: bool) -> Block<'static> {
        let style = if focused {
            self.fg(Color::Cyan).add_modifier(Modifier::BOLD)
        } else {
            self.fg(Color::DarkGray)
        };
        Block::default()
            .borders(Borders::ALL)
            .border_style(style)
            .title(title)
    }
}
