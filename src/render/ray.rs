//! The ray loop: every pixel's ray traced through the slabs, front to back, with the cut faces,
//! compositing or maximum intensity, and the brick grid that lets rays skip empty space.

use rayon::prelude::*;
use tiny_skia::Pixmap;

use super::overlay::Aabb;
use super::pyramid::Grid;
use super::{Camera, Layout, Mode, Placement, RenderParams, Transfer};
use crate::error::{Error, Result};
use crate::geometry::dot;
use crate::progress::Monitor;
use crate::volume::interpolate::Interpolator;
use crate::volume::{Volume, Voxel};

/// Voxels a side of a brick of the empty-space grid.
const BRICK: usize = 8;

/// Opacity at which a ray stops.
const OPAQUE: f32 = 0.99;

/// Faint slabs keep this fraction of their colour and opacity.
const GHOST: f32 = 0.2;

/// The light a cut face gets whatever its angle to the view (the rest grows with it).
const FACE_AMBIENT: f64 = 0.75;

/// Per-brick minimum and maximum of the voxels a brick's cells interpolate, over one pyramid
/// level's voxels.
pub(super) struct Bricks {
    count: [usize; 3],
    min: Vec<f32>,
    max: Vec<f32>,
}

impl Bricks {
    pub(super) fn new(volume: &Volume) -> Self {
        crate::volume::with_voxels!(volume.data(), |data| Self::of(data, volume.dims()))
    }

    /// The bricks of voxels `data` of dimensions `dims`.
    fn of<T: Voxel>(data: &[T], dims: [usize; 3]) -> Self {
        let count = dims.map(|n| n.saturating_sub(1).max(1).div_ceil(BRICK));
        let it = Interpolator::over(data, dims);
        let cells: Vec<(f32, f32)> = (0..count[0] * count[1] * count[2])
            .into_par_iter()
            .map(|b| {
                let c = [
                    b % count[0],
                    (b / count[0]) % count[1],
                    b / (count[0] * count[1]),
                ];
                let range = |m: usize| c[m] * BRICK..=((c[m] + 1) * BRICK).min(dims[m] - 1);
                let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
                for z in range(2) {
                    for y in range(1) {
                        for x in range(0) {
                            let v = it.voxel(x, y, z);
                            if v.is_finite() {
                                lo = lo.min(v);
                                hi = hi.max(v);
                            }
                        }
                    }
                }
                (lo, hi)
            })
            .collect();
        let (min, max) = cells.into_iter().unzip();
        Self { count, min, max }
    }

    /// Per brick, whether `transfer` leaves every value in it clear (or it holds none).
    pub(super) fn transparent(&self, transfer: &Transfer) -> Vec<bool> {
        self.min
            .iter()
            .zip(&self.max)
            .map(|(&lo, &hi)| lo > hi || transfer.transparent(lo, hi))
            .collect()
    }

    /// The box around the bricks that are not `transparent`, in level 0's mm (the bricks lie
    /// on `grid`; the outer ones reach the box `[0, extent]`): what a render shows (the whole
    /// volume when nothing is).
    pub(super) fn content(&self, transparent: &[bool], grid: &Grid, extent: [f64; 3]) -> Aabb {
        let (mut lo, mut hi) = ([usize::MAX; 3], [0; 3]);
        for (b, _) in transparent.iter().enumerate().filter(|(_, t)| !**t) {
            let c = [
                b % self.count[0],
                (b / self.count[0]) % self.count[1],
                b / (self.count[0] * self.count[1]),
            ];
            for m in 0..3 {
                lo[m] = lo[m].min(c[m]);
                hi[m] = hi[m].max(c[m] + 1);
            }
        }
        if lo[0] == usize::MAX {
            return Aabb::of(extent);
        }
        // A brick edge in mm: the outer edges are the box's, which a coarse level's grid
        // does not reach (at level 0 they are where the grid puts them anyway).
        let edge = |m: usize, b: usize| match b {
            0 => 0.0,
            b if b == self.count[m] => extent[m],
            b => grid.position(m, (b * BRICK) as f64).min(extent[m]),
        };
        Aabb {
            lo: std::array::from_fn(|m| edge(m, lo[m])),
            hi: std::array::from_fn(|m| edge(m, hi[m])),
        }
    }

    #[inline]
    fn index(&self, p: [f64; 3]) -> [usize; 3] {
        std::array::from_fn(|m| ((p[m].max(0.0) as usize) / BRICK).min(self.count[m] - 1))
    }

    #[inline]
    fn linear(&self, b: [usize; 3]) -> usize {
        b[0] + self.count[0] * (b[1] + self.count[1] * b[2])
    }

    /// The parameter where the ray leaves the brick around index point `p`.
    fn exit(p: [f64; 3], dir_index: [f64; 3], b: [usize; 3]) -> f64 {
        let mut t = f64::INFINITY;
        for m in 0..3 {
            let (lo, hi) = ((b[m] * BRICK) as f64, ((b[m] + 1) * BRICK) as f64);
            if dir_index[m] > 1e-12 {
                t = t.min((hi - p[m]) / dir_index[m]);
            } else if dir_index[m] < -1e-12 {
                t = t.min((lo - p[m]) / dir_index[m]);
            }
        }
        t.max(0.0)
    }
}

/// Everything the per-pixel loop reads.
pub(super) struct Frame<'a, T> {
    pub(super) it: Interpolator<'a, T>,
    pub(super) bricks: &'a Bricks,
    pub(super) transparent: Vec<bool>,
    pub(super) transfer: Transfer,
    pub(super) labels: bool,
    pub(super) layout: &'a Layout,
    /// Per slab, whether its start and end cuts are exposed.
    pub(super) exposed: Vec<(bool, bool)>,
    pub(super) params: &'a RenderParams,
    /// The grid of the pyramid level `it` reads, in level 0's mm.
    pub(super) grid: Grid,
    /// Level 0's box, mm.
    pub(super) extent: [f64; 3],
    /// Distance between samples along a ray, mm.
    pub(super) step: f64,
}

/// Where a ray crosses one slab: the parameter range inside the box and the slab, and the
/// parameter where it enters through a cut, if it does.
struct Crossing {
    range: (f64, f64),
    cut: Option<f64>,
}

/// What a ray has gathered so far: premultiplied colour, and the parameter where it turned half
/// opaque.
struct Ray {
    acc: [f32; 4],
    depth: f32,
}

impl Ray {
    /// Composites `c` (premultiplied) behind what is there, at parameter `t`.
    #[inline]
    fn add(&mut self, c: [f32; 4], light: f32, k: f32, t: f64) {
        let w = (1.0 - self.acc[3]) * k;
        for i in 0..3 {
            self.acc[i] += w * c[i] * light;
        }
        self.acc[3] += w * c[3];
        if self.acc[3] >= 0.5 && self.depth.is_infinite() {
            self.depth = t as f32;
        }
    }
}

impl<T: Voxel> Frame<'_, T> {
    /// The image of this frame through `camera`, on `params`' background, with each pixel's
    /// depth: rows in parallel, one progress unit per row to `monitor`.
    pub(super) fn cast(
        &self,
        camera: &Camera,
        params: &RenderParams,
        monitor: &Monitor,
    ) -> Result<(Pixmap, Vec<f32>)> {
        let (w, h) = (params.width, params.height);
        let mut pixmap = Pixmap::new(w, h)
            .ok_or_else(|| Error::invalid("size", format!("{w}x{h}"), "an image that fits"))?;
        monitor.start("rendering", u64::from(h));
        let bg = params.background.map(|c| f32::from(c) / 255.0);
        let mut depth = vec![f32::INFINITY; w as usize * h as usize];
        pixmap
            .data_mut()
            .par_chunks_mut(w as usize * 4)
            .zip(depth.par_chunks_mut(w as usize))
            .enumerate()
            .try_for_each(|(y, (row, depths))| {
                for (x, (px, z)) in row.chunks_mut(4).zip(depths).enumerate() {
                    let (o, d) = camera.ray(x as u32, y as u32);
                    let (c, t) = self.trace(o, d);
                    for k in 0..3 {
                        px[k] =
                            ((c[k] + (1.0 - c[3]) * bg[k]).clamp(0.0, 1.0) * 255.0).round() as u8;
                    }
                    px[3] = 255;
                    *z = t;
                }
                monitor.advance(1)
            })?;
        Ok((pixmap, depth))
    }

    /// Premultiplied RGBA along the ray from `o` in direction `d` (unit), through every slab,
    /// and the parameter where it turned half opaque (infinite if it did not).
    fn trace(&self, o: [f64; 3], d: [f64; 3]) -> ([f32; 4], f32) {
        let ascending = dot(d, self.layout.axis) >= 0.0;
        let mut ray = Ray {
            acc: [0.0; 4],
            depth: f32::INFINITY,
        };
        // MIP starts at the window's floor: values below it all map to the background, so
        // bricks whose maximum lies below can be skipped without changing a pixel.
        let mut mip = (self.transfer.floor(), false, f64::INFINITY);
        let count = self.layout.slabs.len();
        for n in 0..count {
            let i = if ascending { n } else { count - 1 - n };
            let slab = &self.layout.slabs[i];
            let other = self.params.highlight.is_some_and(|h| h != slab.index);
            if other && self.params.solo {
                continue;
            }
            let faint = other && self.params.fade;
            let origin: [f64; 3] =
                std::array::from_fn(|m| o[m] - slab.offset * self.layout.axis[m]);
            let Some(crossing) = self.crossing(origin, d, slab, self.exposed[i]) else {
                continue;
            };
            let k = if faint { GHOST } else { 1.0 };
            match self.params.mode {
                Mode::Cut | Mode::Dvr => {
                    if self.params.mode == Mode::Cut
                        && let Some(t) = crossing.cut
                    {
                        self.face((origin, d), t, k, &mut ray);
                    }
                    if ray.acc[3] < OPAQUE {
                        self.composite((origin, d), slab, crossing.range, k, &mut ray);
                    }
                    if ray.acc[3] >= OPAQUE {
                        break;
                    }
                }
                Mode::Mip => self.maximum((origin, d), slab, crossing.range, faint, &mut mip),
            }
        }
        match self.params.mode {
            // On a clean background: only what rises above the window's floor shows.
            Mode::Mip if mip.0 > self.transfer.floor() => {
                let c = self.transfer.mip_grey(mip.0);
                let k = if mip.1 { GHOST } else { 1.0 };
                ([c[0] * k, c[1] * k, c[2] * k, k], mip.2 as f32)
            }
            Mode::Mip => ([0.0; 4], f32::INFINITY),
            Mode::Cut | Mode::Dvr => (ray.acc, ray.depth),
        }
    }

    /// Where the ray crosses the box and the slab, widened by a step so that boundary samples
    /// are decided by [`Frame::inside`] alone; and where it enters through a cut plane of the
    /// slab that is `exposed` (at its start, at its end).
    fn crossing(
        &self,
        o: [f64; 3],
        d: [f64; 3],
        slab: &Placement,
        exposed: (bool, bool),
    ) -> Option<Crossing> {
        let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
        for m in 0..3 {
            if d[m].abs() < 1e-12 {
                if o[m] < 0.0 || o[m] > self.extent[m] {
                    return None;
                }
                continue;
            }
            let (a, b) = ((0.0 - o[m]) / d[m], (self.extent[m] - o[m]) / d[m]);
            lo = lo.max(a.min(b));
            hi = hi.min(a.max(b));
        }
        let (s0, ds) = (dot(o, self.layout.axis), dot(d, self.layout.axis));
        let mut cut = None;
        if ds.abs() < 1e-12 {
            if s0 < slab.lo || s0 >= slab.hi {
                return None;
            }
        } else {
            let (a, b) = ((slab.lo - s0) / ds, (slab.hi - s0) / ds);
            let enter = a.min(b);
            // Rays going up the axis enter through the start, rays going down through the end.
            let open = if ds > 0.0 { exposed.0 } else { exposed.1 };
            if open && enter.is_finite() && enter >= lo {
                cut = Some(enter);
            }
            lo = lo.max(enter);
            hi = hi.min(a.max(b));
        }
        (lo <= hi).then_some(Crossing {
            range: (lo - self.step, hi + self.step),
            cut,
        })
    }

    /// Whether the volume-space point `p` is inside the box and the slab.
    #[inline]
    fn inside(&self, p: [f64; 3], slab: &Placement) -> bool {
        let s = dot(p, self.layout.axis);
        s >= slab.lo
            && s < slab.hi
            && (0..3).all(|m| p[m] >= -1e-9 && p[m] <= self.extent[m] + 1e-9)
    }

    /// Samples `t = n·step` for integers n with `t` in `range`, so that slabs share one grid.
    fn samples(&self, (t0, t1): (f64, f64)) -> (i64, i64) {
        (
            (t0 / self.step).ceil() as i64,
            (t1 / self.step).floor() as i64,
        )
    }

    /// The value at voxel index point `q`.
    #[inline]
    fn value(&self, q: [f64; 3]) -> f32 {
        sample(&self.it, q, self.labels)
    }

    /// Visits the grid samples of `range` inside `slab` in order, in voxel index coordinates
    /// with their parameter, jumping over bricks that `empty` rules out; stops when `visit`
    /// returns false.
    fn march(
        &self,
        (o, d): ([f64; 3], [f64; 3]),
        slab: &Placement,
        range: (f64, f64),
        empty: impl Fn(usize) -> bool,
        mut visit: impl FnMut([f64; 3], f64) -> bool,
    ) {
        let dir_index: [f64; 3] = std::array::from_fn(|m| d[m] / self.grid.spacing[m]);
        let (mut n, last) = self.samples(range);
        while n <= last {
            let t = n as f64 * self.step;
            let p: [f64; 3] = std::array::from_fn(|m| o[m] + t * d[m]);
            n += 1;
            if !self.inside(p, slab) {
                continue;
            }
            let q = self.grid.index(p);
            let b = self.bricks.index(q);
            if empty(self.bricks.linear(b)) {
                let skip = Bricks::exit(q, dir_index, b);
                n = n.max(((t + skip) / self.step).ceil() as i64);
                continue;
            }
            if !visit(q, t) {
                return;
            }
        }
    }

    /// The cut face where the ray enters a slab at parameter `t`: the section there through
    /// the face colours, lit as a surface facing the axis.
    fn face(&self, (o, d): ([f64; 3], [f64; 3]), t: f64, k: f32, ray: &mut Ray) {
        let p: [f64; 3] = std::array::from_fn(|m| (o[m] + t * d[m]).clamp(0.0, self.extent[m]));
        let c = self.transfer.face(self.value(self.grid.index(p)));
        if c[3] > 0.0 {
            // Faces are read, not sculpted: mostly flat light, a little from the angle.
            let light =
                (FACE_AMBIENT + (1.0 - FACE_AMBIENT) * dot(d, self.layout.axis).abs()) as f32;
            ray.add(c, light, k, t);
        }
    }

    fn composite(
        &self,
        ray: ([f64; 3], [f64; 3]),
        slab: &Placement,
        range: (f64, f64),
        k: f32,
        out: &mut Ray,
    ) {
        let shading = self.params.shading;
        self.march(
            ray,
            slab,
            range,
            |b| self.transparent[b],
            |q, t| {
                let (v, g) = if shading {
                    self.it.sample_gradient(q)
                } else {
                    (self.it.sample(q), [0.0; 3])
                };
                let v = if self.labels { self.value(q) } else { v };
                let c = if v.is_nan() {
                    [0.0; 4]
                } else {
                    self.transfer.rgba(v)
                };
                if c[3] > 0.0 {
                    let light = if shading {
                        shade(g, self.grid.spacing, ray.1)
                    } else {
                        1.0
                    };
                    out.add(c, light, k, t);
                }
                out.acc[3] < OPAQUE
            },
        );
    }

    fn maximum(
        &self,
        ray: ([f64; 3], [f64; 3]),
        slab: &Placement,
        range: (f64, f64),
        faint: bool,
        best: &mut (f32, bool, f64),
    ) {
        let top = std::cell::Cell::new(*best);
        self.march(
            ray,
            slab,
            range,
            |b| self.bricks.max[b] <= top.get().0,
            |q, t| {
                let v = self.value(q);
                if v > top.get().0 {
                    top.set((v, faint, t));
                }
                true
            },
        );
        *best = top.get();
    }
}

/// The value at voxel index point `q`: interpolated, or with `labels` the nearest voxel's
/// (interpolated labels are not labels).
#[inline]
pub(crate) fn sample<T: Voxel>(it: &Interpolator<T>, q: [f64; 3], labels: bool) -> f32 {
    if labels {
        it.at(it.nearest(q))
    } else {
        it.sample(q)
    }
}

/// Two-sided diffuse shading with a headlight: 0.35 ambient plus 0.65 |n·l|.
#[inline]
fn shade(g: [f32; 3], spacing: [f64; 3], d: [f64; 3]) -> f32 {
    let g: [f64; 3] = std::array::from_fn(|m| f64::from(g[m]) / spacing[m]);
    let len = dot(g, g).sqrt();
    if len < 1e-12 {
        return 1.0;
    }
    (0.35 + 0.65 * (dot(g, d) / len).abs()) as f32
}
