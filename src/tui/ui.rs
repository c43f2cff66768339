//! The screen layout and drawing: a pure function of the app's state.

use ratatui::Frame;
use ratatui::layout::{Alignment, Constraint, Direction, Layout, Rect};
use ratatui::style::{Color, Modifier, Style};
use ratatui::widgets::{Block, Borders, Paragraph, Wrap};

use super::app::{App, Pane};
use super::panes;

/// The smallest terminal the layout works in.
pub const MIN_SIZE: (u16, u16) = (60, 18);

/// Colours, or none when `NO_COLOR` is set.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
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

/// Where each pane goes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Areas {
    /// Viewpoints.
    pub views: Rect,
    /// Slabs.
    pub slabs: Rect,
    /// Curves.
    pub curves: Rect,
    /// Preview.
    pub preview: Rect,
    /// The two status lines.
    pub status: Rect,
}

/// The layout of a screen of size `area`, or `None` when it is too small.
pub fn areas(area: Rect) -> Option<Areas> {
    if area.width < MIN_SIZE.0 || area.height < MIN_SIZE.1 {
        return None;
    }
    let [body, status] = Layout::vertical([Constraint::Min(0), Constraint::Length(2)]).areas(area);
    let [top, bottom] =
        Layout::vertical([Constraint::Percentage(56), Constraint::Percentage(44)]).areas(body);
    let left = if area.width >= 140 { 34 } else { 42 };
    let [views, preview] = Layout::horizontal([
        Constraint::Percentage(left),
        Constraint::Percentage(100 - left),
    ])
    .areas(top);
    let [slabs, curves] = Layout::new(
        Direction::Horizontal,
        [
            Constraint::Percentage(left),
            Constraint::Percentage(100 - left),
        ],
    )
    .areas(bottom);
    Some(Areas {
        views,
        slabs,
        curves,
        preview,
        status,
    })
}

/// The cells the preview image fills, for a screen of size `area`.
pub fn preview_cells(area: Rect) -> Option<(u16, u16)> {
    let a = areas(area)?;
    let inner = Block::default().borders(Borders::ALL).inner(a.preview);
    Some((inner.width, inner.height))
}

/// Draws the whole screen.
pub fn draw(frame: &mut Frame, app: &App, theme: Theme) {
    let area = frame.area();
    let Some(a) = areas(area) else {
        let text = format!(
            "The terminal is {}x{}: slabscope needs at least {}x{}. Enlarge it, or press q to quit.",
            area.width, area.height, MIN_SIZE.0, MIN_SIZE.1
        );
        frame.render_widget(
            Paragraph::new(text)
                .wrap(Wrap { trim: true })
                .alignment(Alignment::Center),
            area,
        );
        return;
    };
    frame.render_widget(
        panes::views::ViewsPane {
            app,
            theme,
            focused: app.focus == Pane::Views,
        },
        a.views,
    );
    frame.render_widget(
        panes::slabs::SlabsPane {
            app,
            theme,
            focused: app.focus == Pane::Slabs,
        },
        a.slabs,
    );
    frame.render_widget(
        panes::curves::CurvesPane {
            app,
            theme,
            focused: app.focus == Pane::Curves,
        },
        a.curves,
    );
    frame.render_widget(
        panes::preview::PreviewPane {
            app,
            theme,
            focused: app.focus == Pane::Preview,
        },
        a.preview,
    );
    frame.render_widget(panes::status::StatusLines { app, theme }, a.status);
    if app.help {
        frame.render_widget(panes::help::Help { theme }, area);
    }
}
