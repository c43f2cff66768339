//! Overlays drawn over a render with tiny-skia: each slab's outline (the two planes that bound
//! it, cut by the volume's box) where it is seen, its number, and the orientation triad.

use tiny_skia::{Paint, PathBuilder, Pixmap, Rect, Stroke, Transform};

use super::{Image, Layout, RenderParams};
use crate::geometry::{cross, dot, normalize};

/// Outline colour, and the highlighted slab's.
const LINE: [u8; 4] = [90, 200, 230, 200];
const HIGHLIGHT: [u8; 4] = [255, 210, 60, 255];

/// An axis-aligned box in physical space (voxel indices times spacing).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Aabb {
    pub lo: [f64; 3],
    pub hi: [f64; 3],
}

impl Aabb {
    /// The box `[0, extent]`.
    pub fn of(extent: [f64; 3]) -> Self {
        Self {
            lo: [0.0; 3],
            hi: extent,
        }
    }

    /// Corner `c`: bit `m` of `c` chooses the high end along axis `m`.
    pub fn corner(&self, c: usize) -> [f64; 3] {
        std::array::from_fn(|m| {
            if c >> m & 1 == 1 {
                self.hi[m]
            } else {
                self.lo[m]
            }
        })
    }
}

/// The polygon where the plane `p·axis = s` cuts `aabb`, in order around it.
pub(super) fn section(axis: [f64; 3], s: f64, aabb: &Aabb) -> Vec<[f64; 3]> {
    let corner = |c: usize| aabb.corner(c);
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
pub(super) fn draw_digits(
    pixmap: &mut Pixmap,
    text: &str,
    x: f32,
    y: f32,
    scale: f32,
    colour: [u8; 4],
) {
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
                        pixmap.fill_rect(r, &paint, Transform::identity(), None);
                    }
                }
            }
        }
    }
}

/// The range of `p·axis` over `aabb`.
fn span(axis: [f64; 3], aabb: &Aabb) -> (f64, f64) {
    (0..8)
        .map(|c: usize| dot(aabb.corner(c), axis))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), s| {
            (a.min(s), b.max(s))
        })
}

/// The slabs a render draws: all, or the highlighted one alone.
fn drawn<'a>(
    layout: &'a Layout,
    params: &'a RenderParams,
) -> impl Iterator<Item = &'a super::Placement> {
    layout.slabs.iter().filter(move |slab| {
        !(params.solo && params.highlight.is_some() && params.highlight != Some(slab.index))
    })
}

/// The two sections that bound `slab` (where its planes cut the box), where they are drawn.
fn caps(slab: &super::Placement, axis: [f64; 3], aabb: &Aabb) -> [Vec<[f64; 3]>; 2] {
    let (smin, smax) = span(axis, aabb);
    [slab.lo.max(smin), slab.hi.min(smax)].map(|s| {
        section(axis, s, aabb)
            .into_iter()
            .map(|p| std::array::from_fn(|m| p[m] + slab.offset * axis[m]))
            .collect()
    })
}

/// Points whose hull is the drawn scene: each drawn slab's bounding sections of `aabb` and the
/// corners of `aabb` inside it, where they are drawn.
pub(super) fn scene_points(layout: &Layout, aabb: &Aabb, params: &RenderParams) -> Vec<[f64; 3]> {
    let axis = layout.axis;
    let mut points = Vec::new();
    for slab in drawn(layout, params) {
        for cap in caps(slab, axis, aabb) {
            points.extend(cap);
        }
        for c in 0..8usize {
            let p = aabb.corner(c);
            let s = dot(p, axis);
            if s >= slab.lo && s <= slab.hi {
                points.push(std::array::from_fn(|m| p[m] + slab.offset * axis[m]));
            }
        }
    }
    points
}

/// Pixels between the points at which an outline is tested against the depth of the image.
const OUTLINE_PIECE: f64 = 2.0;

/// Draws every slab's outline (its sections of `aabb`) where it is seen (in front of what the
/// image shows there) and its number, the numbers moved apart where they would overlap.
pub(super) fn draw(
    image: &mut Image,
    layout: &Layout,
    aabb: &Aabb,
    params: &RenderParams,
    step: f64,
) {
    let axis = layout.axis;
    let scale = (params.height as f32 / 160.0).clamp(1.0, 3.0).round();
    let size: [f64; 3] = std::array::from_fn(|m| aabb.hi[m] - aabb.lo[m]);
    let diagonal = dot(size, size).sqrt();
    // An outline lies on the surface it bounds: it is seen unless something lies clearly in
    // front of it.
    let tolerance = 2.0 * step + 0.01 * diagonal;
    let mut numbers = Vec::new();
    for slab in drawn(layout, params) {
        let selected = params.highlight == Some(slab.index);
        let colour = if selected { HIGHLIGHT } else { LINE };
        let caps = caps(slab, axis, aabb);
        if params.outlines {
            let mut pb = PathBuilder::new();
            for cap in &caps {
                for (i, &a) in cap.iter().enumerate() {
                    visible_pieces(image, a, cap[(i + 1) % cap.len()], tolerance, &mut pb);
                }
            }
            if let Some(path) = pb.finish() {
                let mut paint = Paint::default();
                paint.set_color_rgba8(colour[0], colour[1], colour[2], colour[3]);
                paint.anti_alias = true;
                let stroke = Stroke {
                    width: if selected { 2.0 } else { 1.0 },
                    line_cap: tiny_skia::LineCap::Round,
                    ..Stroke::default()
                };
                image
                    .pixmap
                    .stroke_path(&path, &paint, &stroke, Transform::identity(), None);
            }
        }
        // The number goes left of the slab, level with the middle of its outline.
        let points: Vec<(f32, f32)> = caps
            .iter()
            .flatten()
            .map(|&p| {
                let (x, y) = image.camera.project(p);
                (x as f32, y as f32)
            })
            .collect();
        if params.labels && !points.is_empty() {
            let left = points.iter().map(|p| p.0).fold(f32::INFINITY, f32::min);
            let middle = points.iter().map(|p| p.1).sum::<f32>() / points.len() as f32;
            numbers.push((slab.index, left, middle - 2.5 * scale, colour));
        }
    }
    // Top to bottom, each number at least a line below the one above it.
    numbers.sort_by(|a, b| a.2.total_cmp(&b.2));
    let mut below = f32::NEG_INFINITY;
    for (index, left, top, colour) in numbers {
        let text = index.to_string();
        let width = text.len() as f32 * 4.0 * scale;
        let top = top.max(below);
        draw_digits(
            &mut image.pixmap,
            &text,
            (left - width - 4.0).max(1.0),
            top,
            scale,
            colour,
        );
        below = top + 7.0 * scale;
    }
}

/// Adds to `pb` the parts of the segment from `a` to `b` (world points) that are in front of
/// what the image shows, tested every couple of pixels.
fn visible_pieces(image: &Image, a: [f64; 3], b: [f64; 3], tolerance: f64, pb: &mut PathBuilder) {
    let cam = &image.camera;
    let (w, h) = (image.pixmap.width(), image.pixmap.height());
    let (pa, pb_) = (cam.project(a), cam.project(b));
    let length = (pb_.0 - pa.0).hypot(pb_.1 - pa.1);
    let pieces = ((length / OUTLINE_PIECE).ceil() as usize).clamp(1, 4096);
    let point = |f: f64| -> [f64; 3] { std::array::from_fn(|m| a[m] + f * (b[m] - a[m])) };
    let seen = |f: f64| {
        let p = point(f);
        let (x, y) = cam.project(p);
        if x < 0.0 || y < 0.0 || x >= f64::from(w) || y >= f64::from(h) {
            return true;
        }
        let z = image.depth[y as usize * w as usize + x as usize];
        cam.depth(p) <= f64::from(z) + tolerance
    };
    let mut open = false;
    for i in 0..pieces {
        let (f0, f1) = (i as f64 / pieces as f64, (i + 1) as f64 / pieces as f64);
        if seen(f64::midpoint(f0, f1)) {
            if !open {
                let (x, y) = cam.project(point(f0));
                pb.move_to(x as f32, y as f32);
                open = true;
            }
            let (x, y) = cam.project(point(f1));
            pb.line_to(x as f32, y as f32);
        } else {
            open = false;
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
        draw_digits(&mut image.pixmap, letter, lx, ly, scale, colour);
    }
}
