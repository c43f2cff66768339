//! A joint histogram as a heat map: a cell a pair of bins, its colour the count on a logarithmic
//! scale (an empty cell white), bin ticks on both axes, the diagonal (equal bins) dashed, and the
//! colour scale beside it with its counts.

use tiny_skia::Pixmap;

use super::{INK, draw_text, fill, font_scale, line, page, text_width, tick_label, ticks};
use crate::error::Result;

/// A `bins × bins` table of counts to draw.
#[derive(Clone, Debug, PartialEq)]
pub struct HeatMap {
    /// Above the map.
    pub title: String,
    /// What the columns are (`bin in slabs 0–12`).
    pub x_label: String,
    /// What the rows are.
    pub y_label: String,
    /// Bins along each side.
    pub bins: usize,
    /// The non-zero cells: `[x, y, count]`.
    pub cells: Vec<[u64; 3]>,
}

/// The colour of a cell at `t` of the scale (0 the fewest counted, 1 the most): pale yellow
/// through orange and red to dark red, readable on a white slide.
pub fn heat_colour(t: f64) -> [u8; 3] {
    const ANCHORS: [[f64; 3]; 4] = [
        [255.0, 237.0, 160.0],
        [253.0, 141.0, 60.0],
        [227.0, 26.0, 28.0],
        [128.0, 0.0, 38.0],
    ];
    let t = t.clamp(0.0, 1.0) * (ANCHORS.len() - 1) as f64;
    let i = (t.floor() as usize).min(ANCHORS.len() - 2);
    let f = t - i as f64;
    std::array::from_fn(|k| (ANCHORS[i][k] + (ANCHORS[i + 1][k] - ANCHORS[i][k]) * f).round() as u8)
}

/// Where `count` stands on the scale up to `most`: `ln(count) / ln(most)`, 1 alone at 0.
pub fn heat_level(count: u64, most: u64) -> f64 {
    if most <= 1 {
        return 1.0;
    }
    (count.max(1) as f64).ln() / (most as f64).ln()
}

/// `map` on a white `width × height` picture.
pub fn draw_heat_map(map: &HeatMap, width: u32, height: u32) -> Result<Pixmap> {
    let mut pixmap = page(width, height)?;
    let s = font_scale(height / 2);
    let w = width as f32;
    let line_h = 7.0 * s;
    let tw = text_width(&map.title, s);
    draw_text(&mut pixmap, &map.title, ((w - tw) / 2.0, 4.0 * s), s, INK);
    let bins = map.bins.max(1);
    let Some((left, bottom, cell)) = square(map, width, height) else {
        return Ok(pixmap);
    };
    let side = cell * bins as f32;
    let most = map.cells.iter().map(|c| c[2]).max().unwrap_or(0);
    for &[x, y, count] in &map.cells {
        if count == 0 || x as usize >= bins || y as usize >= bins {
            continue;
        }
        let at = (
            left + x as f32 * cell,
            bottom - (y as f32 + 1.0) * cell,
            cell,
            cell,
        );
        fill(&mut pixmap, at, heat_colour(heat_level(count, most)));
    }
    line(
        &mut pixmap,
        (left, bottom),
        (left + side, bottom - side),
        s.max(1.0),
        [120, 120, 120],
        3.0 * s,
    );
    frame(&mut pixmap, (left, bottom - side, side, side), s);
    bin_ticks(&mut pixmap, bins, (left, bottom, cell), s);
    let yl = (2.0 * s, bottom - side - line_h - 4.0 * s);
    draw_text(&mut pixmap, &map.y_label, yl, s, INK);
    let xw = text_width(&map.x_label, s);
    let xl = (left + (side - xw) / 2.0, bottom + 15.0 * s);
    draw_text(&mut pixmap, &map.x_label, xl, s, INK);
    colour_scale(
        &mut pixmap,
        most,
        (left + side + 12.0 * s, bottom - side, side),
        s,
    );
    Ok(pixmap)
}

/// The map's bottom-left corner and its cells' side on a `width × height` picture (`None`
/// when there is no room).
pub(super) fn square(map: &HeatMap, width: u32, height: u32) -> Option<(f32, f32, f32)> {
    let s = font_scale(height / 2);
    let (w, h) = (width as f32, height as f32);
    let line_h = 7.0 * s;
    let bins = map.bins.max(1);
    let tick_w = text_width(&tick_label((bins - 1) as f64, 1.0), s);
    let top = 4.0 * s + 2.0 * (line_h + 4.0 * s);
    let bottom = h - (2.0 * line_h + 12.0 * s);
    let left = tick_w + 8.0 * s;
    let side = (bottom - top).min(w - left - 70.0 * s);
    (side >= 10.0).then(|| (left, bottom, side / bins as f32))
}

/// The outline of `(x, y, w, h)`.
fn frame(pixmap: &mut Pixmap, (x, y, w, h): (f32, f32, f32, f32), s: f32) {
    let corners = [(x, y), (x + w, y), (x + w, y + h), (x, y + h), (x, y)];
    for pair in corners.windows(2) {
        line(pixmap, pair[0], pair[1], s, INK, 0.0);
    }
}

/// The bins' ticks below and left of the map whose bottom-left corner is `(left, bottom)`.
fn bin_ticks(pixmap: &mut Pixmap, bins: usize, (left, bottom, cell): (f32, f32, f32), s: f32) {
    let most = ((cell * bins as f32) / (30.0 * s)).max(2.0) as usize;
    for b in ticks(0.0, (bins - 1) as f64, most, true) {
        let text = tick_label(b, 1.0);
        let tw = text_width(&text, s);
        let centre = (b as f32 + 0.5) * cell;
        let x = left + centre;
        line(pixmap, (x, bottom), (x, bottom + 3.0 * s), s, INK, 0.0);
        draw_text(pixmap, &text, (x - tw / 2.0, bottom + 5.0 * s), s, INK);
        let y = bottom - centre;
        line(pixmap, (left - 3.0 * s, y), (left, y), s, INK, 0.0);
        draw_text(pixmap, &text, (left - 5.0 * s - tw, y - 3.5 * s), s, INK);
    }
}

/// The colour scale: a bar from 1 to `most` counts at `(x, top, height)`, its counts beside it
/// at powers of ten.
fn colour_scale(pixmap: &mut Pixmap, most: u64, (x, top, height): (f32, f32, f32), s: f32) {
    let bar = 8.0 * s;
    let steps = height.max(1.0) as usize;
    for i in 0..steps {
        let t = 1.0 - i as f64 / steps as f64;
        fill(pixmap, (x, top + i as f32, bar, 1.0), heat_colour(t));
    }
    frame(pixmap, (x, top, bar, height), s);
    draw_text(pixmap, "COUNT", (x, top - 13.0 * s), s, INK);
    let mut marks: Vec<u64> = std::iter::successors(Some(1u64), |p| p.checked_mul(10))
        .take_while(|&p| p <= most)
        .collect();
    if most > 1 && marks.last() != Some(&most) {
        marks.push(most);
    }
    for (i, &m) in marks.iter().enumerate() {
        // The largest power of ten is left out when it would stand on the count at the top.
        let y = top + height * (1.0 - heat_level(m, most)) as f32;
        if i + 2 == marks.len() && (y - top) < 14.0 * s {
            continue;
        }
        line(pixmap, (x + bar, y), (x + bar + 3.0 * s, y), s, INK, 0.0);
        draw_text(
            pixmap,
            &tick_label(m as f64, (m as f64).min(1e5)),
            (x + bar + 5.0 * s, y - 3.5 * s),
            s,
            INK,
        );
    }
}
