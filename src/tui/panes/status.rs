//! The two status lines: what the last step did (or a prompt or message), and where we are.

use ratatui::buffer::Buffer;
use ratatui::layout::Rect;
use ratatui::style::{Color, Modifier};
use ratatui::text::{Line, Span};
use ratatui::widgets::{Paragraph, Widget};

use crate::tui::app::{App, Ask};
use crate::tui::ui::Theme;

/// The status lines.
pub struct StatusLines<'a> {
    /// The state.
    pub app: &'a App,
    /// Colours.
    pub theme: Theme,
}

impl Widget for StatusLines<'_> {
    fn render(self, area: Rect, buf: &mut Buffer) {
        let app = self.app;
        let first = if let Some(p) = &app.prompt {
            let what = match p.ask {
                Ask::Axis => "axis (x, y, z or DX,DY,DZ)",
                Ask::Threshold => "threshold (empty clears)",
            };
            Line::from(vec![
                Span::styled(format!("{what}> "), self.theme.fg(Color::Cyan)),
                Span::raw(format!("{}█", p.text)),
            ])
        } else if let Some(m) = &app.message {
            Line::from(Span::styled(m.clone(), self.theme.fg(Color::Yellow)))
        } else if let Some(a) = app.analysis.ready() {
            Line::from(Span::styled(
                a.explain(app.method, app.position),
                self.theme.fg(Color::Green),
            ))
        } else {
            Line::from("")
        };
        let method = match app.method {
            slabscope::partition::Method::TopDown => "top-down",
            slabscope::partition::Method::BottomUp => "bottom-up",
            slabscope::partition::Method::Optimal => "optimal",
        };
        let mut parts = vec![Span::styled(
            format!(" {method} "),
            self.theme.selected().add_modifier(Modifier::BOLD),
        )];
        if let Some(a) = app.analysis.ready() {
            let threshold = app
                .threshold
                .map_or_else(String::new, |t| format!("  threshold {t}"));
            parts.push(Span::raw(format!(
                " step {}/{}  {} slabs{threshold} ",
                app.position,
                a.last(app.method),
                a.slab_count(app.method, app.position),
            )));
        }
        for (job, running) in [
            ("views", app.views.running()),
            ("histories", app.analysis.running()),
        ] {
            if running {
                parts.push(Span::styled(
                    format!(" {job}… "),
                    self.theme.fg(Color::Cyan),
                ));
            }
        }
        let hints = if area.width >= 100 {
            " n/p step  +/- slabs  m method  Tab pane  ? help  q quit"
        } else {
            " n/p  +/-  m  ? help  q quit"
        };
        parts.push(Span::styled(hints, self.theme.fg(Color::DarkGray)));
        Paragraph::new(vec![first, Line::from(parts)]).render(area, buf);
    }
}
