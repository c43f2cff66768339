//! The slices themselves: the cross-section of a volume on a plane perpendicular to the slab
//! axis, drawn through the colour window (or a label volume's colours), oriented as
//! radiologists read it when the volume's orientation is known, with letters on its edges; and
//! a strip of the faces of every slab.
//!
//! Orientation (when known): axial and coronal slices are seen with the patient's right on the
//! picture's left (from the feet, and from the front), anterior and superior up; sagittal ones
//! from the patient's left, anterior on the picture's left and superior up; oblique planes as the
//! anatomical plane nearest them. Unknown orientation: the first in-plane voxel axis to the
//! right, and for a slice across z, y down as image viewers show it.

use rayon::prelude::*;
use tiny_skia::{Paint, Pixmap, Rect, Transform};

use super::overlay::{Aabb, draw_digits, section};
use super::pyramid::Grid;
use super::{MAX_PIXELS, Transfer, paste_centred, pyramid_level_in, sample};
use crate::error::{Error, Result};
use crate::geometry::{cross, dot, min_spacing, normalize};
use crate::render::Stack;
use crate::volume::Volume;
use crate::volume::interpolate::Interpolator;

/// How a slice plane lies on the screen: unit physical directions (voxel indices times
/// spacing) to the right and up, and the anatomical letter at each edge when the orientation is
/// known.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SliceFrame {
    /// Unit slab axis (the plane's normal).
    pub axis: [f64; 3],
    /// Physical direction to the right on the screen.
    pub right: [f64; 3],
    /// Physical direction up on the screen.
    pub up: [f64; 3],
    /// Letters at the left, right, top and bottom edges (`R`, `L`, `A`, `P`, `S`, `I`).
    pub letters: Option<[char; 4]>,
}

/// The letter of the world direction `w` (RAS+) nearest it.
fn letter(w: [f64; 3]) -> char {
    let k = (0..3)
        .max_by(|&p, &q| w[p].abs().total_cmp(&w[q].abs()))
        .unwrap_or(0);
    let pairs = [('R', 'L'), ('A', 'P'), ('S', 'I')];
    if w[k] >= 0.0 { pairs[k].0 } else { pairs[k].1 }
}

/// The component of `v` in the plane normal to unit `n`, unit, if it has one.
fn in_plane(v: [f64; 3], n: [f64; 3]) -> Option<[f64; 3]> {
    let along = dot(v, n);
    normalize(std::array::from_fn(|m| v[m] - along * n[m]))
}

impl SliceFrame {
    /// How slices across `axis` (a physical direction) of `volume` are shown.
    pub fn new(volume: &Volume, axis: [f64; 3]) -> Result<Self> {
        let (n, _, _) = crate::geometry::frame(axis)?;
        if let Some(frame) = Self::anatomical(volume, n) {
            return Ok(frame);
        }
        // Unknown orientation: the next voxel axes after the one nearest the normal.
        let k = (0..3)
            .max_by(|&p, &q| n[p].abs().total_cmp(&n[q].abs()))
            .unwrap_or(2);
        let unit = |m: usize| -> [f64; 3] { std::array::from_fn(|c| f64::from(u8::from(c == m))) };
        let (right, up) = match k {
            2 => (unit(0), unit(1).map(|c| -c)),
            1 => (unit(0), unit(2)),
            _ => (unit(1), unit(2)),
        };
        let up = in_plane(up, n).unwrap_or(crate::geometry::frame(n)?.2);
        let right = in_plane(right, n)
            .and_then(|r| in_plane(r, up))
            .unwrap_or(cross(up, n));
        Ok(Self {
            axis: n,
            right,
            up,
            letters: None,
        })
    }

    /// The radiological frame, when the volume's orientation is known.
    fn anatomical(volume: &Volume, n: [f64; 3]) -> Option<Self> {
        let t = volume.transform();
        if !t.known {
            return None;
        }
        let spacing = volume.spacing();
        let normal = t.world_normal(n, spacing)?;
        let k = (0..3).max_by(|&p, &q| normal[p].abs().total_cmp(&normal[q].abs()))?;
        // (up, toward the viewer) in the world, RAS+.
        let (up, toward) = match k {
            2 => ([0.0, 1.0, 0.0], [0.0, 0.0, -1.0]),
            1 => ([0.0, 0.0, 1.0], [0.0, 1.0, 0.0]),
            _ => ([0.0, 0.0, 1.0], [-1.0, 0.0, 0.0]),
        };
        let right = cross(up, toward);
        let up = in_plane(t.physical_direction(up, spacing)?, n)?;
        let right = in_plane(in_plane(t.physical_direction(right, spacing)?, n)?, up)?;
        let world = |d: [f64; 3]| t.world_direction(d, spacing);
        let (r, u) = (letter(world(right)), letter(world(up)));
        let opposite = |c: char| match c {
            'R' => 'L',
            'L' => 'R',
            'A' => 'P',
            'P' => 'A',
            'S' => 'I',
            _ => 'S',
        };
        Some(Self {
            axis: n,
            right,
            up,
            letters: Some([opposite(r), r, u, opposite(u)]),
        })
    }
}

/// A drawn slice, and how its pixels map to the volume.
pub struct SliceImage {
    /// RGBA pixels.
    pub pixmap: Pixmap,
    /// How the plane lies on the screen.
    pub frame: SliceFrame,
    /// Position of the plane along the axis, mm from voxel (0, 0, 0).
    pub position: f64,
    /// Physical point at the top left corner of the image.
    corner: [f64; 3],
    /// Millimetres per pixel.
    pub pixel: f64,
    /// The pyramid level the picture read (0: every voxel; docs/design.md §5).
    pub pyramid_level: usize,
}

impl SliceImage {
    /// The physical point (voxel indices times spacing) at the centre of pixel `(x, y)`.
    pub fn point(&self, x: f64, y: f64) -> [f64; 3] {
        image_point(&self.corner, &self.frame, self.pixel, x, y)
    }

    /// The pixel (x right, y down, fractional) where physical point `p` on the plane lies.
    pub fn pixel_of(&self, p: [f64; 3]) -> (f64, f64) {
        let r: [f64; 3] = std::array::from_fn(|m| p[m] - self.corner[m]);
        (
            dot(r, self.frame.right) / self.pixel - 0.5,
            -dot(r, self.frame.up) / self.pixel - 0.5,
        )
    }
}

/// How a slice is drawn.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SliceParams {
    /// The image size the slice is scaled to fit, keeping its shape.
    pub fit: (u32, u32),
    /// Letters on the edges when the orientation is known.
    pub letters: bool,
    /// Colour outside the volume.
    pub background: [u8; 3],
}

impl Default for SliceParams {
    fn default() -> Self {
        Self {
            fit: (512, 512),
            letters: true,
            background: [0, 0, 0],
        }
    }
}

/// Letter colour on slices.
const LETTER: [u8; 4] = [255, 220, 90, 255];

/// Draws the slice of `volume` at `position` mm along `axis` (from voxel (0, 0, 0)) through
/// `transfer`'s colours.
pub fn slice(
    volume: &Volume,
    transfer: &Transfer,
    axis: [f64; 3],
    position: f64,
    params: &SliceParams,
) -> Result<SliceImage> {
    volume.require_data()?;
    let frame = SliceFrame::new(volume, axis)?;
    let spacing = volume.spacing();
    let dims = volume.dims();
    let extent: [f64; 3] = std::array::from_fn(|m| (dims[m] - 1) as f64 * spacing[m]);
    let n = frame.axis;
    // The plane's part inside the box, on the screen's axes; a plane that misses the box is
    // drawn at the box's outline seen along the axis.
    let aabb = Aabb::of(extent);
    let corners: Vec<[f64; 3]> = (0..8).map(|c| aabb.corner(c)).collect();
    let (mut u0, mut u1, mut v0, mut v1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    let hull = section(n, position, &aabb);
    for p in if hull.is_empty() { &corners } else { &hull } {
        let (u, v) = (dot(*p, frame.right), dot(*p, frame.up));
        (u0, u1, v0, v1) = (u0.min(u), u1.max(u), v0.min(v), v1.max(v));
    }
    // A plane seen edge on still gets a voxel's width.
    let native = min_spacing(spacing);
    let (fw, fh) = (
        f64::from(params.fit.0.max(1)),
        f64::from(params.fit.1.max(1)),
    );
    let (span_u, span_v) = ((u1 - u0).max(native), (v1 - v0).max(native));
    let pixel = (span_u / fw).max(span_v / fh);
    let (w, h) = (
        ((span_u / pixel).round() as u32).clamp(1, params.fit.0.max(1)),
        ((span_v / pixel).round() as u32).clamp(1, params.fit.1.max(1)),
    );
    if u64::from(w) * u64::from(h) > MAX_PIXELS {
        return Err(Error::invalid(
            "size",
            format!("{w}x{h}"),
            format!("between 1x1 and {MAX_PIXELS} pixels"),
        ));
    }
    let corner: [f64; 3] =
        std::array::from_fn(|m| position * n[m] + u0 * frame.right[m] + v1 * frame.up[m]);
    let mut pixmap = Pixmap::new(w, h)
        .ok_or_else(|| Error::invalid("size", format!("{w}x{h}"), "an image that fits"))?;
    // The picture reads the pyramid level its pixels allow (the voxel readouts of a slice
    // view read level 0 themselves).
    let pyramid_level = pyramid_level_in(pixel, (frame.right, frame.up), &volume.level_grids());
    let coarse = (pyramid_level > 0).then(|| volume.coarser(pyramid_level));
    let level = coarse.as_deref().unwrap_or(volume);
    let plane = Plane {
        corner,
        frame,
        pixel,
        extent,
        grid: Grid::of(volume, level),
    };
    plane.draw(&mut pixmap, level, transfer, params.background);
    let mut image = SliceImage {
        pixmap,
        frame,
        position,
        corner,
        pixel,
        pyramid_level,
    };
    if params.letters
        && let Some(letters) = image.frame.letters
    {
        draw_letters(&mut image.pixmap, letters);
    }
    Ok(image)
}

/// Where a slice picture lies: its top left corner, its frame and pixel size (level 0's mm), the
/// volume's box, and the grid of the pyramid level it reads.
struct Plane {
    corner: [f64; 3],
    frame: SliceFrame,
    pixel: f64,
    extent: [f64; 3],
    grid: Grid,
}

impl Plane {
    /// Fills `pixmap` with the plane's picture of `level` through `transfer`'s greys,
    /// `background` outside the box and where voxels are missing.
    fn draw(&self, pixmap: &mut Pixmap, level: &Volume, transfer: &Transfer, background: [u8; 3]) {
        let labels = transfer.is_labels();
        let (w, extent) = (pixmap.width() as usize, self.extent);
        crate::volume::with_voxels!(level.data(), |data| {
            let it = Interpolator::over(data, level.dims());
            pixmap
                .data_mut()
                .par_chunks_mut(w * 4)
                .enumerate()
                .for_each(|(y, row)| {
                    for (x, px) in row.chunks_mut(4).enumerate() {
                        let p =
                            image_point(&self.corner, &self.frame, self.pixel, x as f64, y as f64);
                        let inside = (0..3).all(|m| p[m] >= -1e-6 && p[m] <= extent[m] + 1e-6);
                        let colour = inside.then(|| {
                            let p: [f64; 3] = std::array::from_fn(|m| p[m].clamp(0.0, extent[m]));
                            let v = sample(&it, self.grid.index(p), labels);
                            if v.is_nan() {
                                return background;
                            }
                            let c = transfer.grey(v);
                            c.map(|c| (c.clamp(0.0, 1.0) * 255.0).round() as u8)
                        });
                        let c = colour.unwrap_or(background);
                        px.copy_from_slice(&[c[0], c[1], c[2], 255]);
                    }
                });
        });
    }
}

/// The physical point at the centre of pixel `(x, y)` of a slice image.
#[inline]
fn image_point(corner: &[f64; 3], f: &SliceFrame, pixel: f64, x: f64, y: f64) -> [f64; 3] {
    let (u, v) = ((x + 0.5) * pixel, (y + 0.5) * pixel);
    std::array::from_fn(|m| corner[m] + u * f.right[m] - v * f.up[m])
}

/// Letters at the middle of the left, right, top and bottom edges, on a dark backing.
fn draw_letters(pixmap: &mut Pixmap, letters: [char; 4]) {
    let (w, h) = (pixmap.width() as f32, pixmap.height() as f32);
    let scale = (w.min(h) / 90.0).clamp(1.0, 3.0).round();
    let (gw, gh) = (3.0 * scale, 5.0 * scale);
    let pad = 2.0 * scale;
    let spots = [
        (pad, (h - gh) / 2.0),
        (w - gw - pad, (h - gh) / 2.0),
        ((w - gw) / 2.0, pad),
        ((w - gw) / 2.0, h - gh - pad),
    ];
    let mut backing = Paint::default();
    backing.set_color_rgba8(0, 0, 0, 160);
    for (&c, &(x, y)) in letters.iter().zip(&spots) {
        if let Some(r) = Rect::from_xywh(x - scale, y - scale, gw + 2.0 * scale, gh + 2.0 * scale) {
            pixmap.fill_rect(r, &backing, Transform::identity(), None);
        }
        draw_digits(pixmap, &c.to_string(), x, y, scale, LETTER);
    }
}

/// The slices at the two faces of `slab`: its last (upper) and its first (lower).
pub fn face_slices((a, b): (usize, usize)) -> [usize; 2] {
    [b.saturating_sub(1).max(a), a]
}

/// Slice `index` (the middle one when `None`) of the stack across `axis` (a unit physical
/// direction) that a partition along it would cut with `stack`, drawn with `look`: what
/// `slabscope slice` writes. An index past the stack is an error naming the slices there are.
pub fn numbered(
    volume: &Volume,
    axis: [f64; 3],
    stack: &crate::partition::StackParams,
    index: Option<usize>,
    look: super::TransferChoice,
    params: &SliceParams,
) -> Result<SliceImage> {
    let (axis, slices, thickness, offset) = crate::partition::slice_geometry(volume, axis, stack)?;
    let stack = Stack {
        axis,
        slices,
        thickness,
        offset,
    };
    let index = index.unwrap_or(stack.slices / 2);
    if index >= stack.slices {
        return Err(Error::invalid(
            "index",
            index,
            format!(
                "a slice from 0 to {} (there are {} slices along this axis)",
                stack.slices - 1,
                stack.slices
            ),
        ));
    }
    let transfer = super::Renderer::new(volume)?.transfer(look, min_spacing(volume.spacing()))?;
    slice(volume, &transfer, stack.axis, stack.position(index), params)
}

/// The first and last slice of every slab, side by side: one column per slab, its upper face
/// (its last slice) above its lower face (its first), each tile fit into `tile` and numbered.
pub fn faces(
    volume: &Volume,
    transfer: &Transfer,
    stack: &Stack,
    slabs: &[(usize, usize)],
    tile: (u32, u32),
) -> Result<Pixmap> {
    let params = SliceParams {
        fit: tile,
        ..SliceParams::default()
    };
    let k = slabs.len() as u32;
    let gap = 4;
    let (tw, th) = (tile.0.max(1), tile.1.max(1));
    let (w, h) = (k * (tw + gap) + gap, 2 * (th + gap) + gap);
    if k == 0 || u64::from(w) * u64::from(h) > MAX_PIXELS {
        return Err(Error::invalid(
            "size",
            format!("{w}x{h}"),
            format!("between 1x1 and {MAX_PIXELS} pixels"),
        ));
    }
    let mut strip =
        Pixmap::new(w, h).ok_or_else(|| Error::invalid("size", format!("{w}x{h}"), "a strip"))?;
    strip.fill(tiny_skia::Color::from_rgba8(24, 24, 30, 255));
    let scale = (th as f32 / 90.0).clamp(1.0, 3.0).round();
    for (i, &slab) in slabs.iter().enumerate() {
        for (row, s) in face_slices(slab).into_iter().enumerate() {
            let image = slice(volume, transfer, stack.axis, stack.position(s), &params)?;
            let area = (
                gap + i as u32 * (tw + gap),
                gap + row as u32 * (th + gap),
                tw,
                th,
            );
            paste_centred(&mut strip, &image.pixmap, area);
        }
        let x = (gap + i as u32 * (tw + gap) + 2) as f32;
        draw_digits(
            &mut strip,
            &i.to_string(),
            x,
            (gap + 2) as f32,
            scale,
            LETTER,
        );
    }
    Ok(strip)
}
