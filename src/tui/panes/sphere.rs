//! A latitude-longitude map of the viewpoint sphere, each cell coloured by the entropy rate of
//! the nearest axis (antipodes alike), with the current axis marked.

use ratatui::buffer::Buffer;
use ratatui::layout::Rect;
use ratatui::style::{Color, Style};
use ratatui::widgets::Widget;
use slabscope::geometry::dot;
use slabscope::view::AxisEntropy;

use crate::tui::theme::Theme;

/// The sphere map.
pub struct SphereMap<'a> {
    /// The axes.
    pub views: &'a [AxisEntropy],
    /// The axis being partitioned.
    pub current: Option<[f64; 3]>,
    /// Colours.
    pub theme: Theme,
}

/// Shades for a map without colours, low to high.
const SHADES: [char; 5] = [' ', '░', '▒', '▓', '█'];

/// Blue (low, structured) through green and yellow to red (high).
fn thermal(t: f64) -> Color {
    let stops = [
        (0.0, (40, 60, 200)),
        (0.35, (30, 180, 200)),
        (0.6, (80, 200, 80)),
        (0.8, (230, 200, 40)),
        (1.0, (220, 50, 40)),
    ];
    let t = t.clamp(0.0, 1.0);
    let i = stops
        .iter()
        .rposition(|s| s.0 <= t)
        .unwrap_or(0)
        .min(stops.len() - 2);
    let (a, b) = (stops[i], stops[i + 1]);
    let f = (t - a.0) / (b.0 - a.0);
    let mix = |x: u8, y: u8| (f64::from(x) + f * (f64::from(y) - f64::from(x))).round() as u8;
    Color::Rgb(mix(a.1.0, b.1.0), mix(a.1.1, b.1.1), mix(a.1.2, b.1.2))
}

/// The direction at the centre of map cell `(x, y)` of a `w × h` map.
fn direction(x: u16, y: u16, w: u16, h: u16) -> [f64; 3] {
    let lon = ((f64::from(x) + 0.5) / f64::from(w) * 360.0 - 180.0).to_radians();
    let lat = (90.0 - (f64::from(y) + 0.5) / f64::from(h) * 180.0).to_radians();
    [lat.cos() * lon.cos(), lat.cos() * lon.sin(), lat.sin()]
}

impl Widget for SphereMap<'_> {
    fn render(self, area: Rect, buf: &mut Buffer) {
        if self.views.is_empty() || area.width < 8 || area.height < 4 {
            return;
        }
        let (lo, hi) = self
            .views
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
                (a.min(v.entropy_rate), b.max(v.entropy_rate))
            });
        let span = (hi - lo).max(1e-12);
        let (w, h) = (area.width, area.height);
        let cell_of = |d: [f64; 3]| -> Option<(u16, u16)> {
            let lon = d[1].atan2(d[0]).to_degrees();
            let lat = d[2].clamp(-1.0, 1.0).asin().to_degrees();
            let x = ((lon + 180.0) / 360.0 * f64::from(w))
                .floor()
                .clamp(0.0, f64::from(w - 1)) as u16;
            let y = ((90.0 - lat) / 180.0 * f64::from(h))
                .floor()
                .clamp(0.0, f64::from(h - 1)) as u16;
            Some((x, y))
        };
        for y in 0..h {
            for x in 0..w {
                let d = direction(x, y, w, h);
                let nearest = self
                    .views
                    .iter()
                    .max_by(|a, b| dot(a.axis, d).abs().total_cmp(&dot(b.axis, d).abs()));
                let Some(v) = nearest else { continue };
                let t = (v.entropy_rate - lo) / span;
                let cell = &mut buf[(area.x + x, area.y + y)];
                if self.theme.color {
                    cell.set_char(' ')
                        .set_style(Style::default().bg(thermal(t)));
                } else {
                    cell.set_char(SHADES[(t * 4.0).round() as usize]);
                }
            }
        }
        if let Some(a) = self.current {
            for d in [a, a.map(|c| -c)] {
                if let Some((x, y)) = cell_of(d) {
                    let style = if self.theme.color {
                        Style::default().fg(Color::White).bg(Color::Black)
                    } else {
                        Style::default()
                    };
                    buf[(area.x + x, area.y + y)].set_char('◆').set_style(style);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn map_cells_cover_the_sphere() {
        let up = direction(5, 0, 10, 10);
        assert!(up[2] > 0.98, "the top row looks up");
        let front = direction(5, 5, 10, 10);
        assert!(front[0] > 0.9, "the centre looks along +x");
        assert_eq!(thermal(0.0), Color::Rgb(40, 60, 200));
        assert_eq!(thermal(1.0), Color::Rgb(220, 50, 40));
    }
}
