//! Charts with axes for slides: line and bar charts (ticks, their numbers, both axes labelled, a
//! legend, marks across the plot such as slab boundaries) and a heat map with its colour scale,
//! drawn dark on white with tiny-skia and a bitmap font of their own. `tour --export` draws the
//! lessons' histograms, ΔI of every cut, the curves along the axis and a merge's joint histogram
//! with them; the library knows nothing of where they go.

mod font;
mod heat;
mod ticks;

use tiny_skia::{Paint, PathBuilder, Pixmap, Rect, Stroke, StrokeDash, Transform};

use crate::error::{Error, Result};

pub use font::{draw_text, text_width};
pub use heat::{HeatMap, draw_heat_map};
pub use ticks::{label as tick_label, ticks};

/// Ink for text, axes and ticks.
const INK: [u8; 3] = [30, 30, 30];
/// The faint grid behind the plot.
const GRID: [u8; 3] = [225, 225, 225];

/// One axis of a chart: its label and range.
#[derive(Clone, Debug, PartialEq)]
pub struct Scale {
    /// What it measures, with its unit (`ΔI (bits)`).
    pub label: String,
    /// The low end.
    pub lo: f64,
    /// The high end.
    pub hi: f64,
    /// Ticks only at whole numbers (slices, bins).
    pub whole: bool,
}

/// How a series is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Style {
    /// Points joined by a line.
    Line,
    /// A bar at each point (bars of several series side by side).
    Bars,
}

/// Values to plot.
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    /// Its name in the legend (none when empty).
    pub name: String,
    /// Line or bars.
    pub style: Style,
    /// Its colour.
    pub colour: [u8; 3],
    /// `[x, y]` points, x increasing.
    pub points: Vec<[f64; 2]>,
}

/// A vertical line across the plot at `x` (a slab boundary, the cut taken).
#[derive(Clone, Debug, PartialEq)]
pub struct Mark {
    /// Where.
    pub x: f64,
    /// Its colour.
    pub colour: [u8; 3],
    /// Its name in the legend (marks of one name are listed once; none when empty).
    pub name: String,
}

/// A chart: a title, two axes, series and marks.
#[derive(Clone, Debug, PartialEq)]
pub struct Chart {
    /// Above the plot.
    pub title: String,
    /// The horizontal axis.
    pub x: Scale,
    /// The vertical axis.
    pub y: Scale,
    /// What is plotted, drawn in order.
    pub series: Vec<Series>,
    /// The vertical lines.
    pub marks: Vec<Mark>,
}

/// The rectangle of a chart's plot on the picture and how values map into it.
#[derive(Clone, Copy, Debug)]
struct Plot {
    left: f32,
    top: f32,
    right: f32,
    bottom: f32,
    x: (f64, f64),
    y: (f64, f64),
}

impl Plot {
    fn px(&self, x: f64) -> f32 {
        let t = (x - self.x.0) / (self.x.1 - self.x.0).max(1e-300);
        self.left + (self.right - self.left) * t as f32
    }

    fn py(&self, y: f64) -> f32 {
        let t = (y - self.y.0) / (self.y.1 - self.y.0).max(1e-300);
        self.bottom - (self.bottom - self.top) * t as f32
    }
}

fn paint(rgb: [u8; 3]) -> Paint<'static> {
    let mut p = Paint::default();
    p.set_color_rgba8(rgb[0], rgb[1], rgb[2], 255);
    p.anti_alias = true;
    p
}

/// A line from `a` to `b`, `width` pixels wide, dashed when `dash` is given.
fn line(pixmap: &mut Pixmap, a: (f32, f32), b: (f32, f32), width: f32, rgb: [u8; 3], dash: f32) {
    let mut pb = PathBuilder::new();
    pb.move_to(a.0, a.1);
    pb.line_to(b.0, b.1);
    let Some(path) = pb.finish() else { return };
    let stroke = Stroke {
        width,
        dash: (dash > 0.0)
            .then(|| StrokeDash::new(vec![dash, dash], 0.0))
            .flatten(),
        ..Stroke::default()
    };
    pixmap.stroke_path(&path, &paint(rgb), &stroke, Transform::identity(), None);
}

fn fill(pixmap: &mut Pixmap, (x, y, w, h): (f32, f32, f32, f32), rgb: [u8; 3]) {
    if let Some(r) = Rect::from_xywh(x, y, w.max(0.5), h.max(0.5)) {
        pixmap.fill_rect(r, &paint(rgb), Transform::identity(), None);
    }
}

/// A white `width × height` picture.
fn page(width: u32, height: u32) -> Result<Pixmap> {
    let mut pixmap = Pixmap::new(width, height)
        .ok_or_else(|| Error::Encode(format!("a chart of {width}×{height} pixels")))?;
    pixmap.fill(tiny_skia::Color::WHITE);
    Ok(pixmap)
}

/// The font's scale for a panel `height` pixels high.
fn font_scale(height: u32) -> f32 {
    (height / 120).clamp(1, 4) as f32
}

/// `charts` drawn one above the other on a white `width × height` picture, each with its own
/// axes.
pub fn draw_charts(charts: &[Chart], width: u32, height: u32) -> Result<Pixmap> {
    let mut pixmap = page(width, height)?;
    let n = charts.len().max(1) as u32;
    let panel = height / n;
    for (i, chart) in charts.iter().enumerate() {
        let area = (0.0, (i as u32 * panel) as f32, width as f32, panel as f32);
        draw_chart(&mut pixmap, chart, area, font_scale(panel));
    }
    Ok(pixmap)
}

/// Where `chart`'s plot stands in `area` (x, y, width, height), `s` pixels a font pixel: room
/// above for the title and the y axis's label, left for the y ticks' numbers, below for the x
/// ticks' numbers and the x axis's label.
fn plot_of(chart: &Chart, area: (f32, f32, f32, f32), s: f32) -> Plot {
    let (x0, y0, w, h) = area;
    let y_ticks = ticks(chart.y.lo, chart.y.hi, 5, chart.y.whole);
    let y_step = tick_step(&y_ticks);
    let widest = y_ticks
        .iter()
        .map(|&v| text_width(&tick_label(v, y_step), s))
        .fold(0.0, f32::max);
    let line_h = 7.0 * s;
    Plot {
        left: x0 + widest.max(text_width("0", s)) + 8.0 * s,
        top: y0 + 4.0 * s + 2.0 * (line_h + 4.0 * s),
        right: x0 + w - 8.0 * s,
        bottom: y0 + h - (2.0 * line_h + 12.0 * s),
        x: (chart.x.lo, chart.x.hi),
        y: (chart.y.lo, chart.y.hi),
    }
}

/// One chart in `area` (x, y, width, height) of `pixmap`, `s` pixels a font pixel.
fn draw_chart(pixmap: &mut Pixmap, chart: &Chart, area: (f32, f32, f32, f32), s: f32) {
    let (x0, y0, w, _) = area;
    let plot = plot_of(chart, area, s);
    let y_ticks = ticks(chart.y.lo, chart.y.hi, 5, chart.y.whole);
    let line_h = 7.0 * s;
    let title_w = text_width(&chart.title, s);
    draw_text(
        pixmap,
        &chart.title,
        (x0 + (w - title_w) / 2.0, y0 + 4.0 * s),
        s,
        INK,
    );
    draw_text(
        pixmap,
        &chart.y.label,
        (x0 + 2.0 * s, plot.top - line_h - 4.0 * s),
        s,
        INK,
    );
    if plot.right - plot.left < 10.0 || plot.bottom - plot.top < 10.0 {
        return;
    }
    axes(pixmap, chart, &plot, &y_ticks, s);
    let bars: Vec<&Series> = chart
        .series
        .iter()
        .filter(|c| c.style == Style::Bars)
        .collect();
    for (k, series) in bars.iter().enumerate() {
        draw_bars(pixmap, series, &plot, (k, bars.len()));
    }
    for series in chart.series.iter().filter(|c| c.style == Style::Line) {
        let pts: Vec<(f32, f32)> = series
            .points
            .iter()
            .map(|p| (plot.px(p[0]), plot.py(p[1])))
            .collect();
        for pair in pts.windows(2) {
            line(pixmap, pair[0], pair[1], s.max(1.5), series.colour, 0.0);
        }
    }
    for m in &chart.marks {
        let x = plot.px(m.x);
        if (plot.left..=plot.right).contains(&x) {
            line(
                pixmap,
                (x, plot.top),
                (x, plot.bottom),
                s.max(1.0),
                m.colour,
                3.0 * s,
            );
        }
    }
    legend(pixmap, chart, &plot, s);
}

/// The step between the first two ticks (1 with fewer).
fn tick_step(t: &[f64]) -> f64 {
    match t {
        [a, b, ..] => b - a,
        _ => 1.0,
    }
}

/// The grid, both axes, their ticks and numbers, and the x axis's label.
fn axes(pixmap: &mut Pixmap, chart: &Chart, plot: &Plot, y_ticks: &[f64], s: f32) {
    let y_step = tick_step(y_ticks);
    for &v in y_ticks {
        let y = plot.py(v);
        line(pixmap, (plot.left, y), (plot.right, y), 1.0, GRID, 0.0);
        line(
            pixmap,
            (plot.left - 3.0 * s, y),
            (plot.left, y),
            s,
            INK,
            0.0,
        );
        let text = tick_label(v, y_step);
        let tw = text_width(&text, s);
        draw_text(
            pixmap,
            &text,
            (plot.left - 5.0 * s - tw, y - 3.5 * s),
            s,
            INK,
        );
    }
    let most = ((plot.right - plot.left) / (40.0 * s)).max(2.0) as usize;
    let x_ticks = ticks(chart.x.lo, chart.x.hi, most, chart.x.whole);
    let x_step = tick_step(&x_ticks);
    for &v in &x_ticks {
        let x = plot.px(v);
        line(
            pixmap,
            (x, plot.bottom),
            (x, plot.bottom + 3.0 * s),
            s,
            INK,
            0.0,
        );
        let text = tick_label(v, x_step);
        let tw = text_width(&text, s);
        draw_text(pixmap, &text, (x - tw / 2.0, plot.bottom + 5.0 * s), s, INK);
    }
    line(
        pixmap,
        (plot.left, plot.top),
        (plot.left, plot.bottom),
        s,
        INK,
        0.0,
    );
    line(
        pixmap,
        (plot.left, plot.bottom),
        (plot.right, plot.bottom),
        s,
        INK,
        0.0,
    );
    let lw = text_width(&chart.x.label, s);
    let at = ((plot.left + plot.right - lw) / 2.0, plot.bottom + 15.0 * s);
    draw_text(pixmap, &chart.x.label, at, s, INK);
}

/// `series` as bars, the `k`th of `of` bar series sharing each x.
fn draw_bars(pixmap: &mut Pixmap, series: &Series, plot: &Plot, (k, of): (usize, usize)) {
    let gap = series
        .points
        .windows(2)
        .map(|p| p[1][0] - p[0][0])
        .fold(f64::INFINITY, f64::min);
    let slot = if gap.is_finite() { gap } else { 1.0 };
    let width = (plot.px(slot) - plot.px(0.0)).abs() * 0.8 / of as f32;
    let base = plot.py(plot.y.0.max(0.0).min(plot.y.1));
    for p in &series.points {
        let x = plot.px(p[0]) - width * of as f32 / 2.0 + width * k as f32;
        let y = plot.py(p[1].clamp(plot.y.0, plot.y.1));
        fill(
            pixmap,
            (x, y.min(base), width, (base - y).abs()),
            series.colour,
        );
    }
}

/// The names of the series and marks inside the plot, each beside its colour, in the corner
/// where their box covers the fewest pixels already drawn (curves, bars, marks; the grid counts
/// as empty), top right on ties.
fn legend(pixmap: &mut Pixmap, chart: &Chart, plot: &Plot, s: f32) {
    let mut entries: Vec<(&str, [u8; 3])> = Vec::new();
    let named = chart
        .series
        .iter()
        .map(|c| (c.name.as_str(), c.colour))
        .chain(chart.marks.iter().map(|m| (m.name.as_str(), m.colour)));
    for (name, colour) in named {
        if !name.is_empty() && !entries.iter().any(|e| e.0 == name) {
            entries.push((name, colour));
        }
    }
    if entries.is_empty() {
        return;
    }
    let widest = entries
        .iter()
        .map(|e| text_width(e.0, s))
        .fold(0.0, f32::max);
    let (w, h) = (widest + 15.0 * s, entries.len() as f32 * 10.0 * s);
    let (left, right) = (plot.left + 4.0 * s, plot.right - w - 2.0 * s);
    let (top, bottom) = (plot.top + s, plot.bottom - h - 2.0 * s);
    let corners = [(right, top), (left, top), (right, bottom), (left, bottom)];
    let (x0, y0) = corners
        .into_iter()
        .map(|c| (covered(pixmap, (c.0, c.1, w, h)), c))
        .fold(
            None,
            |best: Option<(usize, (f32, f32))>, (n, c)| match best {
                Some((b, _)) if b <= n => best,
                _ => Some((n, c)),
            },
        )
        .map_or(corners[0], |(_, c)| c);
    fill(pixmap, (x0, y0, w, h), [255, 255, 255]);
    for (i, (name, colour)) in entries.iter().enumerate() {
        let (x, y) = (x0 + 2.0 * s, y0 + s + i as f32 * 10.0 * s);
        fill(pixmap, (x, y, 8.0 * s, 7.0 * s), *colour);
        draw_text(pixmap, name, (x + 11.0 * s, y), s, INK);
    }
}

/// The pixels in `area` (x, y, width, height) of `pixmap` neither white nor the grid's (its
/// anti-aliased lines are greys between the two).
fn covered(pixmap: &Pixmap, (x, y, w, h): (f32, f32, f32, f32)) -> usize {
    let xs = x.max(0.0) as u32..(x + w).max(0.0) as u32;
    let ys = y.max(0.0) as u32..(y + h).max(0.0) as u32;
    ys.flat_map(|py| xs.clone().map(move |px| (px, py)))
        .filter_map(|(px, py)| pixmap.pixel(px, py))
        .filter(|c| {
            let grey = c.red() == c.green() && c.green() == c.blue();
            !(grey && c.red() >= GRID[0])
        })
        .count()
}

#[cfg(test)]
mod tests;
