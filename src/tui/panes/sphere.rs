//! A latitude-longitude map of the viewpoint sphere, each cell coloured by the score of the
//! nearest axis (antipodes alike: the mean entropy rate over phases, or the paper's), with the
//! current axis marked and a legend of the colours below it.

use ratatui::buffer::Buffer;
use ratatui::layout::Rect;
use ratatui::style::{Color, Style};
use ratatui::widgets::Widget;
use slabscope::geometry::dot;
use slabscope::view::{AxisEntropy, score};

use crate::tui::theme::Theme;

/// The sphere map.
pub struct SphereMap<'a> {
    /// The axes.
    pub views: &'a [AxisEntropy],
    /// Colour by the mean partition gain (high is good: drawn as low) instead of the score.
    pub by_gain: bool,
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
                (a.min(self.value(v)), b.max(self.value(v)))
            });
        let span = (hi - lo).max(1e-12);
        // The last row is the legend.
        let map = Rect {
            height: area.height - 1,
            ..area
        };
        let (w, h) = (map.width, map.height);
        for y in 0..h {
            for x in 0..w {
                let d = direction(x, y, w, h);
                let nearest = self
                    .views
                    .iter()
                    .max_by(|a, b| dot(a.axis, d).abs().total_cmp(&dot(b.axis, d).abs()));
                let Some(v) = nearest else { continue };
                self.shade(
                    &mut buf[(map.x + x, map.y + y)],
                    (self.value(v) - lo) / span,
                );
            }
        }
        if let Some(a) = self.current {
            for d in [a, a.map(|c| -c)] {
                let (x, y) = cell_of(d, w, h);
                let style = if self.theme.color {
                    Style::default().fg(Color::White).bg(Color::Black)
                } else {
                    Style::default()
                };
                buf[(map.x + x, map.y + y)].set_char('◆').set_style(style);
            }
        }
        // The legend reads the gain itself, highest (the colour of the lowest value) first.
        let (left, right) = if self.by_gain { (-lo, -hi) } else { (lo, hi) };
        self.legend(
            Rect::new(area.x, area.bottom() - 1, area.width, 1),
            left,
            right,
            buf,
        );
    }
}

impl SphereMap<'_> {
    /// What a cell's colour shows of its axis, low for the best: the score, or the gain negated.
    fn value(&self, v: &AxisEntropy) -> f64 {
        match (self.by_gain, v.gain_phases) {
            (true, Some(g)) => -g.mean,
            _ => score(v),
        }
    }

    /// A cell of the map at `t` (0 for the lowest score, 1 for the highest).
    fn shade(&self, cell: &mut ratatui::buffer::Cell, t: f64) {
        if self.theme.color {
            cell.set_char(' ')
                .set_style(Style::default().bg(thermal(t)));
        } else {
            cell.set_char(SHADES[(t * 4.0).round() as usize]);
        }
    }

    /// `0.105 ░▒▓█ 0.246 (◆ axis)`: the colours from the lowest score to the highest.
    fn legend(&self, area: Rect, lo: f64, hi: f64, buf: &mut Buffer) {
        let (left, right) = (format!("{lo:.3} "), format!(" {hi:.3} ◆ axis"));
        let ramp = area
            .width
            .saturating_sub((left.chars().count() + right.chars().count()) as u16)
            .min(12);
        buf.set_string(area.x, area.y, &left, Style::default());
        let x0 = area.x + left.chars().count() as u16;
        for i in 0..ramp {
            let t = f64::from(i) / f64::from(ramp.max(2) - 1);
            self.shade(&mut buf[(x0 + i, area.y)], t);
        }
        buf.set_string(x0 + ramp, area.y, &right, Style::default());
    }
}

/// The map cell of direction `d` in a `w × h` map.
fn cell_of(d: [f64; 3], w: u16, h: u16) -> (u16, u16) {
    let lon = d[1].atan2(d[0]).to_degrees();
    let lat = d[2].clamp(-1.0, 1.0).asin().to_degrees();
    let x = ((lon + 180.0) / 360.0 * f64::from(w))
        .floor()
        .clamp(0.0, f64::from(w - 1)) as u16;
    let y = ((90.0 - lat) / 180.0 * f64::from(h))
        .floor()
        .clamp(0.0, f64::from(h - 1)) as u16;
    (x, y)
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
