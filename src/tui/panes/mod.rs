//! The panes, each a widget over the app's state.

pub mod curves;
pub mod help;
pub mod preview;
pub mod slabs;
pub mod sphere;
pub mod status;
pub mod views;

use ratatui::buffer::Buffer;
use ratatui::layout::Rect;
use ratatui::widgets::{Gauge, Paragraph, Widget, Wrap};

use super::app::Load;
use super::ui::Theme;

/// Draws the placeholder of something not ready: a gauge while it runs, its error, or a hint.
pub fn placeholder<T>(
    load: &Load<T>,
    what: &str,
    idle: &str,
    theme: Theme,
    area: Rect,
    buf: &mut Buffer,
) {
    match load {
        Load::Running(f) => {
            let gauge_area = Rect {
                height: area.height.min(1),
                ..area
            };
            Gauge::default()
                .gauge_style(theme.fg(ratatui::style::Color::Cyan))
                .ratio(f.clamp(0.0, 1.0))
                .label(format!("{what} {:.0}%  (Esc cancels)", f * 100.0))
                .render(gauge_area, buf);
        }
        Load::Failed(e) => Paragraph::new(format!("{what}: {e}"))
            .style(theme.fg(ratatui::style::Color::Red))
            .wrap(Wrap { trim: true })
            .render(area, buf),
        Load::Idle | Load::Ready(_) => Paragraph::new(idle.to_string())
            .wrap(Wrap { trim: true })
            .render(area, buf),
    }
}

/// `[ 0.526, -0.851,  0.000] (x)`, compact.
pub fn axis_text(axis: [f64; 3]) -> String {
    let c = axis.map(|c| if c.abs() < 5e-4 { 0.0 } else { c });
    let name = slabscope::partition::coordinate_axis(axis).map_or("", |m| [" x", " y", " z"][m]);
    format!("[{:6.3},{:6.3},{:6.3}]{name}", c[0], c[1], c[2])
}

/// Slices `[a, b)` for people: `12` for one slice, `12–40` for several (inclusive).
pub fn slices_text((a, b): (usize, usize)) -> String {
    if b - a == 1 {
        a.to_string()
    } else {
        format!("{a}–{}", b - 1)
    }
}
