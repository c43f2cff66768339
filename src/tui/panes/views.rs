//! The viewpoints pane: every axis with its entropy rate, lowest first, and a sphere map.

use ratatui::buffer::Buffer;
use ratatui::layout::{Constraint, Layout, Rect};
use ratatui::style::{Color, Modifier};
use ratatui::text::{Line, Span};
use ratatui::widgets::{Paragraph, Widget};

use super::sphere::SphereMap;
use super::{axis_text, placeholder};
use crate::tui::app::{App, Load};
use crate::tui::ui::Theme;

/// The viewpoints pane.
pub struct ViewsPane<'a> {
    /// The state.
    pub app: &'a App,
    /// Colours.
    pub theme: Theme,
    /// Whether it has the focus.
    pub focused: bool,
}

impl Widget for ViewsPane<'_> {
    fn render(self, area: Rect, buf: &mut Buffer) {
        let title = match self.app.views.ready() {
            Some(v) if area.width >= 44 => {
                format!(" Viewpoints: {} axes, entropy rate h ", v.views.len())
            }
            Some(v) => format!(" {} axes, h ", v.views.len()),
            None => " Viewpoints ".into(),
        };
        let block = self.theme.block(title, self.focused);
        let inner = block.inner(area);
        block.render(area, buf);
        let Load::Ready(views) = &self.app.views else {
            let idle = match &self.app.volume {
                Load::Failed(e) => format!("cannot load the volume: {e}"),
                _ => format!("loading {}…", self.app.name),
            };
            placeholder(
                &self.app.views,
                "view search",
                &idle,
                self.theme,
                inner,
                buf,
            );
            return;
        };
        // The sphere map takes the right part of a wide pane or the bottom of a tall one.
        let (list, map) = if inner.width >= 70 {
            let [l, m] =
                Layout::horizontal([Constraint::Length(38), Constraint::Min(0)]).areas(inner);
            (l, Some(m))
        } else if inner.height >= 22 {
            let [l, m] =
                Layout::vertical([Constraint::Min(0), Constraint::Length(inner.height / 2)])
                    .areas(inner);
            (l, Some(m))
        } else {
            (inner, None)
        };
        let rows = usize::from(list.height);
        let first = self.app.view_row.saturating_sub(rows.saturating_sub(1));
        let lines: Vec<Line> = views
            .views
            .iter()
            .enumerate()
            .skip(first)
            .take(rows)
            .map(|(i, v)| {
                let current = self
                    .app
                    .axis
                    .is_some_and(|a| slabscope::view::axis_angle(a, v.axis) < 1e-6);
                let mark = match (current, i == 0) {
                    (true, _) => "●",
                    (false, true) => "*",
                    _ => " ",
                };
                let text = if list.width >= 38 {
                    format!(
                        "{mark}{:>3} {} {:.4}",
                        i + 1,
                        axis_text(v.axis),
                        v.entropy_rate
                    )
                } else {
                    let c = v.axis.map(|c| if c.abs() < 5e-3 { 0.0 } else { c });
                    format!(
                        "{mark}{:>2} [{:5.2},{:5.2},{:5.2}] {:.3}",
                        i + 1,
                        c[0],
                        c[1],
                        c[2],
                        v.entropy_rate
                    )
                };
                let mut style = if current {
                    self.theme.fg(Color::Yellow)
                } else {
                    self.theme.fg(Color::Reset)
                };
                if i == self.app.view_row && self.focused {
                    style = style.patch(self.theme.selected());
                } else if i == self.app.view_row {
                    style = style.add_modifier(Modifier::BOLD);
                }
                Line::from(Span::styled(text, style))
            })
            .collect();
        Paragraph::new(lines).render(list, buf);
        if let Some(map) = map {
            SphereMap {
                views: &views.views,
                current: self.app.axis,
                theme: self.theme,
            }
            .render(map, buf);
        }
    }
}
