//! Overlays drawn over a render with tiny-skia: each slab's outline (the two planes that bound
//! it, cut by the volume's box) and its number.

use tiny_skia::{Paint, PathBuilder, Rect, Stroke, Transform};

use super::{Image, Layout, RenderParams};
use crate::geometry::{cross, dot, normalize};

/// Outline colour, and the highlighted slab's.
const LINE: [u8; 4] = [90, 200, 230, 200];
const HIGHLIGHT: [u8; 4] = [255, 210, 60, 255];

/// The polygon where the plane `p·axis = s` cuts the box `[0, extent]`, in order around it.
fn section(axis: [f64; 3], s: f64, extent: [f64; 3]) -> Vec<[f64; 3]> {
    let corner = |c: usize| -> [f64; 3] {
        std::array::from_fn(|m| if c >> m & 1 == 1 { extent[m] } else { 0.0 })
    };
    let mut points = Vec::new();
    for a in 0..8usize {
        for m in 0..3 {
            if a >> m & 1 == 1 {
                continue;
            }
            let (p, q) = (corner(a), corner(a | 1 << m));
            let (sp, sq) = (dot(p, axis), dot(q, axis));
            if (sp - s) * (sq - s) <= 0.0 && (sp - sq).abs() > 1e-12 {
                let t = (s - sp) / (sq - sp);
                points.push(std::array::from_fn(|k| p[k] + t * (q[k] - p[k])));
            }
        }
    }
    if points.len() < 3 {
        return Vec::new();
    }
    let n = points.len() as f64;
    let c: [f64; 3] = std::array::from_fn(|k| points.iter().map(|p| p[k]).sum::<f64>() / n);
    let u = normalize(std::array::from_fn(|k| points[0][k] - c[k])).unwrap_or([1.0, 0.0, 0.0]);
    let v = cross(axis, u);
    points.sort_by(|a, b| {
        let angle = |p: &[f64; 3]| {
            let r: [f64; 3] = std::array::from_fn(|k| p[k] - c[k]);
            dot(r, v).atan2(dot(r, u))
        };
        angle(a).total_cmp(&angle(b))
    });
    points
}

/// 3x5 glyphs of digits and of the anatomical letters, rows top to bottom, 3 bits a row (bit 2
/// is the left column).
const DIGITS: [[u8; 5]; 10] = [
    [7, 5, 5, 5, 7],
    [2, 6, 2, 2, 7],
    [7, 1, 7, 4, 7],
    [7, 1, 7, 1, 7],
    [5, 5, 7, 1, 1],
    [7, 4, 7, 1, 7],
    [7, 4, 7, 5, 7],
    [7, 1, 1, 1, 1],
    [7, 5, 7, 5, 7],
    [7, 5, 7, 1, 7],
];

const LETTERS: [(char, [u8; 5]); 6] = [
    ('R', [6, 5, 6, 5, 5]),
    ('L', [4, 4, 4, 4, 7]),
    ('A', [2, 5, 7, 5, 5]),
    ('P', [6, 5, 6, 4, 4]),
    ('S', [3, 4, 2, 1, 6]),
    ('I', [7, 2, 2, 2, 7]),
];

fn glyph(ch: char) -> Option<&'static [u8; 5]> {
    match ch.to_digit(10) {
        Some(d) => Some(&DIGITS[d as usize]),
        None => LETTERS.iter().find(|l| l.0 == ch).map(|l| &l.1),
    }
}

/// Draws `text` (digits and the letters R, L, A, P, S, I) with its top-left at `(x, y)`,
/// `scale` pixels per font pixel.
fn draw_digits(image: &mut Image, text: &str, x: f32, y: f32, scale: f32, colour: [u8; 4]) {
    let mut paint = Paint::default();
    paint.set_color_rgba8(colour[0], colour[1], colour[2], colour[3]);
    for (i, ch) in text.chars().enumerate() {
        let Some(g) = glyph(ch) else { continue };
        for (row, bits) in g.iter().enumerate() {
            for col in 0..3 {
                if bits >> (2 - col) & 1 == 1 {
                    let px = x + (i as f32 * 4.0 + col as f32) * scale;
                    let py = y + row as f32 * scale;
                    if let Some(r) = Rect::from_xywh(px, py, scale, scale) {
                        image
                            .pixmap
                            .fill_rect(r, &paint, Transform::identity(), None);
                    }
                }
            }
        }
    }
}

/// Draws every slab's outline and number.
pub(super) fn draw(image: &mut Image, layout: &Layout, extent: [f64; 3], params: &RenderParams) {
    let axis = layout.axis;
    let corners = (0..8).map(|c: usize| -> f64 {
        dot(
            std::array::from_fn(|m| if c >> m & 1 == 1 { extent[m] } else { 0.0 }),
            axis,
        )
    });
    let (smin, smax) = corners.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), s| {
        (a.min(s), b.max(s))
    });
    let scale = (params.height as f32 / 160.0).clamp(1.0, 3.0).round();
    for slab in &layout.slabs {
        let selected = params.highlight == Some(slab.index);
        if params.solo && params.highlight.is_some() && !selected {
            continue;
        }
        let colour = if selected { HIGHLIGHT } else { LINE };
        let caps: Vec<Vec<(f32, f32)>> = [slab.lo.max(smin), slab.hi.min(smax)]
            .iter()
            .map(|&s| {
                section(axis, s, extent)
                    .into_iter()
                    .map(|p| {
                        let q = std::array::from_fn(|m| p[m] + slab.offset * axis[m]);
                        let (x, y) = image.camera.project(q);
                        (x as f32, y as f32)
                    })
                    .collect()
            })
            .collect();
        if params.outlines {
            let mut paint = Paint::default();
            paint.set_color_rgba8(colour[0], colour[1], colour[2], colour[3]);
            paint.anti_alias = true;
            let stroke = Stroke {
                width: if selected { 2.0 } else { 1.0 },
                ..Stroke::default()
            };
            for cap in &caps {
                let mut pb = PathBuilder::new();
                for (i, &(x, y)) in cap.iter().enumerate() {
                    if i == 0 {
                        pb.move_to(x, y);
                    } else {
                        pb.line_to(x, y);
                    }
                }
                pb.close();
                if let Some(path) = pb.finish() {
                    image
                        .pixmap
                        .stroke_path(&path, &paint, &stroke, Transform::identity(), None);
                }
            }
        }
        // The number goes left of the slab, level with the middle of its outline.
        let points: Vec<(f32, f32)> = caps.into_iter().flatten().collect();
        if params.labels && !points.is_empty() {
            let left = points.iter().map(|p| p.0).fold(f32::INFINITY, f32::min);
            let middle = points.iter().map(|p| p.1).sum::<f32>() / points.len() as f32;
            let text = slab.index.to_string();
            let width = text.len() as f32 * 4.0 * scale;
            draw_digits(
                image,
                &text,
                (left - width - 4.0).max(1.0),
                middle - 2.5 * scale,
                scale,
                colour,
            );
        }
    }
}

/// The world axes' colours, as Slicer and ITK-SNAP draw them: R red, A green, S blue.
const AXIS_COLOURS: [[u8; 4]; 3] = [[235, 80, 70, 255], [90, 200, 90, 255], [90, 140, 255, 255]];

/// An orientation triad in the lower left corner: the world's R, A and S directions as the
/// camera sees them, each an arrow from a common origin with its letter at the tip, faint when
/// it points away from the viewer. `physical` takes a world direction to the render's space.
pub(super) fn triad(
    image: &mut Image,
    physical: impl Fn([f64; 3]) -> Option<[f64; 3]>,
    params: &RenderParams,
) {
    let (w, h) = (params.width as f32, params.height as f32);
    let scale = (params.height as f32 / 160.0).clamp(1.0, 3.0).round();
    let length = (0.08 * w.min(h)).max(10.0);
    let origin = (4.0 * scale + length, h - 4.0 * scale - length);
    for (k, letter) in ["R", "A", "S"].iter().enumerate() {
        let mut world = [0.0; 3];
        world[k] = 1.0;
        let Some(d) = physical(world) else { continue };
        let (x, y, toward) = image.camera.screen_direction(d);
        let mut colour = AXIS_COLOURS[k];
        if toward < -0.1 {
            colour[3] = 120;
        }
        let tip = (origin.0 + length * x as f32, origin.1 - length * y as f32);
        let mut paint = Paint::default();
        paint.set_color_rgba8(colour[0], colour[1], colour[2], colour[3]);
        paint.anti_alias = true;
        let mut pb = PathBuilder::new();
        pb.move_to(origin.0, origin.1);
        pb.line_to(tip.0, tip.1);
        let stroke = Stroke {
            width: scale.max(1.5),
            ..Stroke::default()
        };
        if let Some(path) = pb.finish() {
            image
                .pixmap
                .stroke_path(&path, &paint, &stroke, Transform::identity(), None);
        }
        // The letter beyond the tip, centred on the arrow's line.
        let reach = 3.5 * scale;
        let (lx, ly) = (
            tip.0 + reach * x as f32 - 1.5 * scale,
            tip.1 - reach * y as f32 - 2.5 * scale,
        );
        draw_digits(image, letter, lx, ly, scale, colour);
    }
}
