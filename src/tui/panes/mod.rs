//! The panes: each owns its state and renders it (`impl Widget for &Pane`).

pub mod board;
pub mod curves;
pub mod files;
pub mod heat;
pub mod help;
pub mod lesson;
pub mod preview;
pub mod slabs;
pub mod sphere;
pub mod status;
pub mod thumbs;
pub mod tour;
pub mod views;

use ratatui::buffer::Buffer;
use ratatui::layout::Rect;
use ratatui::style::Color;
use ratatui::widgets::{Gauge, Paragraph, Widget, Wrap};

use super::event::Task;
use super::theme::Theme;

/// Draws the placeholder of something not ready: a gauge naming its phase while it runs, its
/// error, or a hint.
pub fn placeholder(
    load: &Task<()>,
    what: &str,
    idle: &str,
    theme: Theme,
    area: Rect,
    buf: &mut Buffer,
) {
    match load {
        Task::Running(p) => {
            let gauge_area = Rect {
                height: area.height.min(1),
                ..area
            };
            let phase = if p.phase.is_empty() { what } else { p.phase };
            Gauge::default()
                .gauge_style(theme.fg(Color::Cyan))
                .ratio(p.fraction.clamp(0.0, 1.0))
                .label(format!("{phase} {:.0}%  (Esc cancels)", p.fraction * 100.0))
                .render(gauge_area, buf);
        }
        Task::Failed(e) => Paragraph::new(format!("{what}: {e}"))
            .style(theme.fg(Color::Red))
            .wrap(Wrap { trim: true })
            .render(area, buf),
        Task::Idle | Task::Ready(()) => Paragraph::new(idle.to_string())
            .wrap(Wrap { trim: true })
            .render(area, buf),
    }
}
