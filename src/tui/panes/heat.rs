//! The merge lesson's joint histogram as a heat map, its bins ticked and a colour scale; and the
//! rows of ticks under the lesson's charts ([`tick_line`]).

use ratatui::buffer::Buffer;
use ratatui::layout::Rect;
use ratatui::style::{Color, Style};
use ratatui::text::{Line, Span};
use ratatui::widgets::{Paragraph, Widget};
use slabscope::explain::MergeLesson;

use crate::tui::theme::Theme;

/// The joint histogram, x (the first slab's bin) down and y across, two rows of bins a line
/// (half blocks), bins grouped where the area is smaller; shades without colours. X's bins are
/// ticked on the left, Y's under the map, and a colour scale from one count to the most ends it.
pub(super) fn heat_map(m: &MergeLesson, bins: usize, theme: Theme, area: Rect, buf: &mut Buffer) {
    // The title in one line where the area is wide, else in two.
    let titled: u16 = if area.width >= WIDE { 1 } else { 2 };
    if area.height < titled + 3 || area.width < 16 {
        return;
    }
    let rows = usize::from(area.height - titled - 2) * 2;
    let cols = usize::from(area.width) - TICKS;
    let group = bins.div_ceil(rows).max(bins.div_ceil(cols)).max(1);
    let n = bins.div_ceil(group);
    let mut cells = vec![0u64; n * n];
    for &[x, y, c] in &m.joint {
        cells[x as usize / group * n + y as usize / group] += c;
    }
    let top = cells.iter().copied().max().unwrap_or(1).max(1);
    let level = |c: u64| {
        if c == 0 {
            0.0
        } else {
            (1.0 + (c as f64).ln()) / (1.0 + (top as f64).ln())
        }
    };
    let bins = if group == 1 { "bin" } else { "bins" };
    let title = if titled == 1 {
        vec![Line::from(format!(
            "joint histogram: X's bin down, Y's across, log counts, {group} {bins} a cell"
        ))]
    } else {
        vec![
            Line::from("joint histogram, log counts:"),
            Line::from(format!("X down, Y across, {group} {bins} a cell")),
        ]
    };
    Paragraph::new(title).render(
        Rect {
            height: titled,
            ..area
        },
        buf,
    );
    let mut lines = Vec::new();
    for r in 0..n.div_ceil(2) {
        // Every other line says the X bin of its upper row.
        let tick = if r % 2 == 0 {
            format!("{:>4} ", 2 * r * group)
        } else {
            " ".repeat(TICKS)
        };
        let mut spans = vec![Span::raw(tick)];
        for y in 0..n {
            let lower = (2 * r + 1 < n).then(|| cells[(2 * r + 1) * n + y]);
            spans.push(heat_cell(
                level(cells[2 * r * n + y]),
                lower.map_or(0.0, level),
                theme,
            ));
        }
        lines.push(Line::from(spans));
    }
    // Y's bins under the map: its first, middle and last cell.
    let at = [0, n / 2, n - 1].map(|c| (c, c * group));
    lines.push(Line::from(tick_line(
        "",
        TICKS,
        &at,
        usize::from(area.width),
    )));
    let mut scale = vec![Span::raw("   1 ")];
    // From one count's shade (not the empty cells') to the most's.
    let one = level(1);
    scale.extend((0..=8).map(|i| {
        let v = one + (1.0 - one) * f64::from(i) / 8.0;
        heat_cell(v, v, theme)
    }));
    scale.push(Span::raw(format!(" {top} counts")));
    lines.push(Line::from(scale));
    Paragraph::new(lines).render(
        Rect {
            y: area.y + titled,
            height: area.height - titled,
            ..area
        },
        buf,
    );
}

/// The narrowest area whose title takes one line.
const WIDE: u16 = 70;

/// The columns a heat map beside text takes: 2 bins a cell of 32 and its ticks, and its colour
/// scale with a count of six digits.
pub(super) const BESIDE: u16 = 32;

/// The rows the heat map of `bins` bins takes at `group` bins a cell in an area of `width`
/// columns: its title, a line for two rows of cells, the ticks and the colour scale.
pub(super) fn rows(bins: usize, group: usize, width: u16) -> u16 {
    let titled = if width >= WIDE { 1 } else { 2 };
    u16::try_from(bins.div_ceil(group).div_ceil(2) + 2 + titled).unwrap_or(u16::MAX)
}

/// Columns the X ticks take left of the heat map.
const TICKS: usize = 5;

/// One cell of the heat map: its upper and lower bins' levels (0 to 1).
fn heat_cell(upper: f64, lower: f64, theme: Theme) -> Span<'static> {
    let shade = |v: f64| Color::Rgb((40.0 + 215.0 * v) as u8, (30.0 + 120.0 * v) as u8, 60);
    if theme.color {
        Span::styled("▀", Style::default().fg(shade(upper)).bg(shade(lower)))
    } else {
        const SHADES: [&str; 5] = [" ", "░", "▒", "▓", "█"];
        Span::raw(SHADES[(upper.max(lower) * 4.0).round() as usize])
    }
}

/// A row of ticks under a chart: `name` right-aligned in the `label` columns left of the chart,
/// then each value at its column of the chart (one that would touch the one before, or not fit
/// in `width`, is left out).
pub(super) fn tick_line(name: &str, label: usize, at: &[(usize, usize)], width: usize) -> String {
    let mut line = format!("{name:>w$} ", w = label.saturating_sub(1));
    for &(column, value) in at {
        let text = value.to_string();
        let start = label + column;
        let taken = line.chars().count();
        if start + text.len() <= width && (start > taken || taken == label) {
            line.push_str(&" ".repeat(start - taken));
            line.push_str(&text);
        }
    }
    line
}

#[cfg(test)]
mod tests {
    use super::tick_line;

    #[test]
    fn ticks_stand_at_their_columns_and_never_touch() {
        assert_eq!(
            tick_line("bin", 6, &[(0, 0), (4, 16), (9, 31)], 40),
            "  bin 0   16   31"
        );
        // 30 would touch 18: left out, as a tick past the width.
        assert_eq!(
            tick_line("", 5, &[(0, 0), (3, 18), (5, 30)], 40),
            "     0  18"
        );
        assert_eq!(tick_line("", 5, &[(0, 0), (30, 99)], 20), "     0");
    }
}
