//! A 5×7 bitmap font for the charts' titles, labels and ticks: capitals (small letters are drawn
//! as capitals), digits and the signs a chart's label needs. No font file, no dependency: the
//! glyphs are the classic 5×7 cells, one byte a row, bit 4 the left column.

use tiny_skia::{Paint, Pixmap, Rect, Transform};

/// The glyphs: the character and its seven rows, top to bottom.
const GLYPHS: [(char, [u8; 7]); 56] = [
    ('A', [14, 17, 17, 31, 17, 17, 17]),
    ('B', [30, 17, 17, 30, 17, 17, 30]),
    ('C', [14, 17, 16, 16, 16, 17, 14]),
    ('D', [30, 17, 17, 17, 17, 17, 30]),
    ('E', [31, 16, 16, 30, 16, 16, 31]),
    ('F', [31, 16, 16, 30, 16, 16, 16]),
    ('G', [14, 17, 16, 23, 17, 17, 15]),
    ('H', [17, 17, 17, 31, 17, 17, 17]),
    ('I', [14, 4, 4, 4, 4, 4, 14]),
    ('J', [7, 2, 2, 2, 2, 18, 12]),
    ('K', [17, 18, 20, 24, 20, 18, 17]),
    ('L', [16, 16, 16, 16, 16, 16, 31]),
    ('M', [17, 27, 21, 21, 17, 17, 17]),
    ('N', [17, 17, 25, 21, 19, 17, 17]),
    ('O', [14, 17, 17, 17, 17, 17, 14]),
    ('P', [30, 17, 17, 30, 16, 16, 16]),
    ('Q', [14, 17, 17, 17, 21, 18, 13]),
    ('R', [30, 17, 17, 30, 20, 18, 17]),
    ('S', [15, 16, 16, 14, 1, 1, 30]),
    ('T', [31, 4, 4, 4, 4, 4, 4]),
    ('U', [17, 17, 17, 17, 17, 17, 14]),
    ('V', [17, 17, 17, 17, 17, 10, 4]),
    ('W', [17, 17, 17, 21, 21, 21, 10]),
    ('X', [17, 17, 10, 4, 10, 17, 17]),
    ('Y', [17, 17, 17, 10, 4, 4, 4]),
    ('Z', [31, 1, 2, 4, 8, 16, 31]),
    ('0', [14, 17, 19, 21, 25, 17, 14]),
    ('1', [4, 12, 4, 4, 4, 4, 14]),
    ('2', [14, 17, 1, 2, 4, 8, 31]),
    ('3', [31, 2, 4, 2, 1, 17, 14]),
    ('4', [2, 6, 10, 18, 31, 2, 2]),
    ('5', [31, 16, 30, 1, 1, 17, 14]),
    ('6', [6, 8, 16, 30, 17, 17, 14]),
    ('7', [31, 1, 2, 4, 8, 8, 8]),
    ('8', [14, 17, 17, 14, 17, 17, 14]),
    ('9', [14, 17, 17, 15, 1, 2, 12]),
    ('.', [0, 0, 0, 0, 0, 12, 12]),
    (',', [0, 0, 0, 0, 12, 4, 8]),
    ('-', [0, 0, 0, 14, 0, 0, 0]),
    ('–', [0, 0, 0, 31, 0, 0, 0]),
    ('+', [0, 4, 4, 31, 4, 4, 0]),
    ('(', [2, 4, 8, 8, 8, 4, 2]),
    (')', [8, 4, 2, 2, 2, 4, 8]),
    ('[', [14, 8, 8, 8, 8, 8, 14]),
    (']', [14, 2, 2, 2, 2, 2, 14]),
    ('=', [0, 0, 31, 0, 31, 0, 0]),
    ('/', [1, 1, 2, 4, 8, 16, 16]),
    (':', [0, 12, 12, 0, 12, 12, 0]),
    ('%', [24, 25, 2, 4, 8, 19, 3]),
    ('Δ', [4, 4, 10, 10, 17, 17, 31]),
    ('×', [0, 17, 10, 4, 10, 17, 0]),
    ('·', [0, 0, 0, 12, 12, 0, 0]),
    ('\'', [4, 4, 8, 0, 0, 0, 0]),
    ('<', [2, 4, 8, 16, 8, 4, 2]),
    ('>', [8, 4, 2, 1, 2, 4, 8]),
    ('_', [0, 0, 0, 0, 0, 0, 31]),
];

/// The rows of `ch`'s glyph (a small letter's capital's); `None` for a space or a character
/// the font lacks, which is left blank.
fn glyph(ch: char) -> Option<&'static [u8; 7]> {
    let ch = ch.to_uppercase().next().unwrap_or(ch);
    GLYPHS.iter().find(|g| g.0 == ch).map(|g| &g.1)
}

/// The width in pixels of `text` drawn `scale` pixels a font pixel.
pub fn text_width(text: &str, scale: f32) -> f32 {
    let n = text.chars().count() as f32;
    if n == 0.0 {
        0.0
    } else {
        (n * 6.0 - 1.0) * scale
    }
}

/// Draws `text` with its top-left at `(x, y)`, `scale` pixels a font pixel, in `rgb`.
pub fn draw_text(pixmap: &mut Pixmap, text: &str, (x, y): (f32, f32), scale: f32, rgb: [u8; 3]) {
    let mut paint = Paint::default();
    paint.set_color_rgba8(rgb[0], rgb[1], rgb[2], 255);
    for (i, ch) in text.chars().enumerate() {
        let Some(rows) = glyph(ch) else { continue };
        for (row, bits) in rows.iter().enumerate() {
            for col in 0..5 {
                if bits >> (4 - col) & 1 == 1 {
                    let px = x + (i as f32 * 6.0 + col as f32) * scale;
                    let py = y + row as f32 * scale;
                    if let Some(r) = Rect::from_xywh(px, py, scale, scale) {
                        pixmap.fill_rect(r, &paint, Transform::identity(), None);
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn glyphs_are_five_wide_and_distinct() {
        for (ch, rows) in &GLYPHS {
            assert!(rows.iter().all(|r| *r < 32), "{ch}");
            let same = GLYPHS.iter().filter(|g| g.1 == *rows).count();
            assert_eq!(same, 1, "{ch} shares its glyph");
        }
        assert_eq!(glyph('a'), glyph('A'));
        assert!(glyph(' ').is_none());
    }

    #[test]
    fn text_is_drawn_where_its_pixels_are() {
        let mut p = Pixmap::new(40, 20).unwrap();
        p.fill(tiny_skia::Color::WHITE);
        // "L" at scale 2 from (3, 4): its stem is the left column, its foot the last row.
        draw_text(&mut p, "L", (3.0, 4.0), 2.0, [0, 0, 0]);
        let ink = |x, y| p.pixel(x, y).unwrap().red() == 0;
        assert!(ink(3, 4) && ink(4, 17) && ink(11, 17));
        assert!(!ink(5, 4) && !ink(11, 15) && !ink(2, 4));
        assert!((text_width("L", 2.0) - 10.0).abs() < 1e-6);
        assert!((text_width("LL", 1.0) - 11.0).abs() < 1e-6);
        assert!(text_width("", 3.0).abs() < 1e-6);
    }
}
