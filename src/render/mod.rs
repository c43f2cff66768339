//! The exploded view (paper §3, step 3): a CPU ray caster for slabs pulled apart along their
//! axis, with direct volume rendering or maximum intensity projection, empty-space skipping,
//! early ray termination, optional shading, and outlines and labels drawn with tiny-skia.
//!
//! Every pixel is computed on its own from the same inputs, so images are identical whatever the
//! number of threads.

mod camera;
mod layout;
mod overlay;
mod transfer;

use rayon::prelude::*;
use serde::Serialize;
use tiny_skia::Pixmap;

pub use camera::{Camera, CameraParams};
pub use layout::{Gap, Layout, Placement, Stack};
pub use transfer::{Colormap, HISTOGRAM_BINS, Look, Preset, Transfer};

use crate::error::{Error, Result};
use crate::geometry::{dot, min_spacing};
use crate::progress::Monitor;
use crate::volume::Volume;
use crate::volume::interpolate::Interpolator;

/// How samples become pixels.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Mode {
    /// Direct volume rendering: front-to-back compositing through the transfer function.
    Dvr,
    /// Maximum intensity projection through the colour window.
    Mip,
}

/// Everything about a render but the volume and the layout.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderParams {
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// DVR or MIP.
    pub mode: Mode,
    /// Transfer function.
    pub preset: Preset,
    /// Colour map.
    pub colormap: Colormap,
    /// Grey and opacity ramp from `lo` to `hi`, replacing the preset's.
    pub window: Option<(f32, f32)>,
    /// The camera.
    pub camera: CameraParams,
    /// Gradient shading (DVR).
    pub shading: bool,
    /// Distance between samples along a ray, in units of the smallest voxel spacing.
    pub step: f64,
    /// Draw slab outlines.
    pub outlines: bool,
    /// Draw slab numbers.
    pub labels: bool,
    /// Show this slab normally and the others faint.
    pub highlight: Option<usize>,
    /// Render only the highlighted slab.
    pub solo: bool,
    /// Background colour.
    pub background: [u8; 3],
}

impl Default for RenderParams {
    fn default() -> Self {
        Self {
            width: 640,
            height: 480,
            mode: Mode::Dvr,
            preset: Preset::Auto,
            colormap: Colormap::Grey,
            window: None,
            camera: CameraParams::default(),
            shading: true,
            step: 1.0,
            outlines: true,
            labels: true,
            highlight: None,
            solo: false,
            background: [12, 12, 18],
        }
    }
}

/// The most pixels an image may have.
pub const MAX_PIXELS: u64 = 64 << 20;

/// Voxels a side of a brick of the empty-space grid.
const BRICK: usize = 8;

/// Slabs may be moved at most this many times the volume's diagonal.
const MAX_REACH: f64 = 100.0;

/// Opacity at which a ray stops.
const OPAQUE: f32 = 0.99;

/// Faint slabs keep this fraction of their colour and opacity.
const GHOST: f32 = 0.2;

/// A rendered image and the camera that made it.
pub struct Image {
    /// RGBA pixels (opaque, so premultiplied equals straight).
    pub pixmap: Pixmap,
    /// The camera, to project world points into the image.
    pub camera: Camera,
}

impl Image {
    /// The image as PNG bytes.
    pub fn png(&self) -> Result<Vec<u8>> {
        self.pixmap
            .encode_png()
            .map_err(|e| Error::Encode(format!("PNG: {e}")))
    }

    /// The image encoded as `format` asks.
    pub fn encode(&self, format: ImageOutput) -> Result<Vec<u8>> {
        match format {
            ImageOutput::Png => self.png(),
            ImageOutput::Jpeg => {
                let rgb: Vec<u8> = self
                    .pixmap
                    .data()
                    .chunks_exact(4)
                    .flat_map(|p| [p[0], p[1], p[2]])
                    .collect();
                let mut out = Vec::new();
                image::codecs::jpeg::JpegEncoder::new_with_quality(&mut out, JPEG_QUALITY)
                    .encode(
                        &rgb,
                        self.pixmap.width(),
                        self.pixmap.height(),
                        image::ExtendedColorType::Rgb8,
                    )
                    .map_err(|e| Error::Encode(format!("JPEG: {e}")))?;
                Ok(out)
            }
        }
    }
}

/// JPEG quality of [`ImageOutput::Jpeg`]: high, as a picture for a report should be.
const JPEG_QUALITY: u8 = 92;

/// The image formats renders are written in, chosen by the output's extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageOutput {
    /// `.png`: lossless.
    Png,
    /// `.jpg` or `.jpeg`.
    Jpeg,
}

impl ImageOutput {
    /// The format the name of `path` asks for; an unknown extension is an error, found before
    /// any work is done.
    pub fn for_path(path: &std::path::Path) -> Result<Self> {
        let ext = path
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase());
        match ext.as_deref() {
            Some("png") => Ok(Self::Png),
            Some("jpg" | "jpeg") => Ok(Self::Jpeg),
            _ => Err(Error::unsupported(
                path,
                "pictures are written as .png, .jpg or .jpeg, chosen by the extension",
            )),
        }
    }
}

/// Per-brick minimum and maximum of the voxels a brick's cells interpolate.
struct Bricks {
    count: [usize; 3],
    min: Vec<f32>,
    max: Vec<f32>,
}

impl Bricks {
    fn new(volume: &Volume) -> Self {
        let dims = volume.dims();
        let count = dims.map(|n| n.saturating_sub(1).max(1).div_ceil(BRICK));
        let it = Interpolator::new(volume);
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

/// What a render of one volume can reuse: the brick grid and the value histogram.
pub struct Renderer<'a> {
    volume: &'a Volume,
    bricks: Bricks,
    histogram: Vec<u64>,
}

/// Everything the per-pixel loop reads.
struct Frame<'a> {
    it: Interpolator<'a>,
    bricks: &'a Bricks,
    transparent: Vec<bool>,
    transfer: Transfer,
    layout: &'a Layout,
    params: &'a RenderParams,
    spacing: [f64; 3],
    extent: [f64; 3],
    step: f64,
}

impl<'a> Renderer<'a> {
    /// Prepares `volume` for rendering (one pass over its voxels).
    pub fn new(volume: &'a Volume) -> Result<Self> {
        volume.require_data()?;
        Ok(Self {
            volume,
            bricks: Bricks::new(volume),
            histogram: volume.histogram(HISTOGRAM_BINS)?,
        })
    }

    /// The volume being rendered.
    pub fn volume(&self) -> &Volume {
        self.volume
    }

    /// Renders `layout` with `params`; reports one unit per image row to `monitor`.
    pub fn render(
        &self,
        layout: &Layout,
        params: &RenderParams,
        monitor: &Monitor,
    ) -> Result<Image> {
        let (w, h) = (params.width, params.height);
        if w == 0 || h == 0 || u64::from(w) * u64::from(h) > MAX_PIXELS {
            return Err(Error::invalid(
                "size",
                format!("{w}x{h}"),
                format!("between 1x1 and {MAX_PIXELS} pixels"),
            ));
        }
        if !(params.step.is_finite() && params.step > 0.0) {
            return Err(Error::invalid("step", params.step, "a positive number"));
        }
        let c = &params.camera;
        if !(c.zoom.is_finite() && c.zoom > 1e-3 && c.zoom < 1e3) {
            return Err(Error::invalid(
                "zoom",
                c.zoom,
                "a number between 0.001 and 1000",
            ));
        }
        for (name, v) in [("azimuth", c.azimuth), ("elevation", c.elevation)] {
            if !v.is_finite() {
                return Err(Error::invalid(name, v, "a finite angle in degrees"));
            }
        }
        let spacing = self.volume.spacing();
        let reference = min_spacing(spacing);
        let step = params.step * reference;
        let look = Look {
            preset: params.preset,
            colormap: params.colormap,
            window: params.window,
        };
        let transfer =
            Transfer::with_histogram(self.volume.stats(), &self.histogram, look, step, reference)?;
        let transparent = self
            .bricks
            .min
            .iter()
            .zip(&self.bricks.max)
            .map(|(&lo, &hi)| lo > hi || transfer.transparent(lo, hi))
            .collect();
        let dims = self.volume.dims();
        let extent: [f64; 3] = std::array::from_fn(|m| (dims[m] - 1) as f64 * spacing[m]);
        let center = extent.map(|e| e / 2.0);
        let diagonal = dot(extent, extent).sqrt();
        if !(layout.reach().is_finite() && layout.reach() <= MAX_REACH * diagonal.max(reference)) {
            return Err(Error::invalid(
                "spread",
                layout.reach(),
                format!("slabs moved at most {MAX_REACH} times the volume's diagonal"),
            ));
        }
        let radius = diagonal / 2.0 + layout.reach() + reference;
        let t = self.volume.transform();
        let display = t.display_frame(layout.axis, spacing);
        let camera = Camera::oriented(center, radius, layout.axis, display, &params.camera, w, h)?;
        let frame = Frame {
            it: Interpolator::new(self.volume),
            bricks: &self.bricks,
            transparent,
            transfer,
            layout,
            params,
            spacing,
            extent,
            step,
        };
        let mut pixmap = Pixmap::new(w, h)
            .ok_or_else(|| Error::invalid("size", format!("{w}x{h}"), "an image that fits"))?;
        monitor.start("rendering", u64::from(h));
        let bg = params.background.map(|c| f32::from(c) / 255.0);
        pixmap
            .data_mut()
            .par_chunks_mut(w as usize * 4)
            .enumerate()
            .try_for_each(|(y, row)| {
                for (x, px) in row.chunks_mut(4).enumerate() {
                    let (o, d) = camera.ray(x as u32, y as u32);
                    let c = frame.trace(o, d);
                    for k in 0..3 {
                        px[k] =
                            ((c[k] + (1.0 - c[3]) * bg[k]).clamp(0.0, 1.0) * 255.0).round() as u8;
                    }
                    px[3] = 255;
                }
                monitor.advance(1)
            })?;
        let mut image = Image { pixmap, camera };
        if params.outlines || params.labels {
            overlay::draw(&mut image, layout, extent, params);
        }
        if params.labels && t.known {
            overlay::triad(&mut image, |w| t.physical_direction(w, spacing), params);
        }
        Ok(image)
    }
}

impl Frame<'_> {
    /// Premultiplied RGBA along the ray from `o` in direction `d` (unit), through every slab.
    fn trace(&self, o: [f64; 3], d: [f64; 3]) -> [f32; 4] {
        let ascending = dot(d, self.layout.axis) >= 0.0;
        let mut acc = [0.0f32; 4];
        // MIP starts at the window's floor: values below it all map to its colour, so bricks
        // whose maximum lies below can be skipped without changing a pixel.
        let mut mip = (self.transfer.floor(), false);
        let mut hit = false;
        let count = self.layout.slabs.len();
        for n in 0..count {
            let slab = &self.layout.slabs[if ascending { n } else { count - 1 - n }];
            let faint = self.params.highlight.is_some_and(|h| h != slab.index);
            if faint && self.params.solo {
                continue;
            }
            let origin: [f64; 3] =
                std::array::from_fn(|m| o[m] - slab.offset * self.layout.axis[m]);
            let Some((t0, t1)) = self.interval(origin, d, slab) else {
                continue;
            };
            hit = true;
            match self.params.mode {
                Mode::Dvr => {
                    self.composite((origin, d), slab, (t0, t1), faint, &mut acc);
                    if acc[3] >= OPAQUE {
                        break;
                    }
                }
                Mode::Mip => self.maximum((origin, d), slab, (t0, t1), faint, &mut mip),
            }
        }
        match self.params.mode {
            Mode::Mip if hit => {
                let c = self.transfer.grey(mip.0);
                let k = if mip.1 { GHOST } else { 1.0 };
                [c[0] * k, c[1] * k, c[2] * k, 1.0]
            }
            Mode::Mip => [0.0; 4],
            Mode::Dvr => acc,
        }
    }

    /// The parameter range where the ray lies inside the box and the slab, widened by a step so
    /// that boundary samples are decided by [`Frame::inside`] alone.
    fn interval(&self, o: [f64; 3], d: [f64; 3], slab: &Placement) -> Option<(f64, f64)> {
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
        if ds.abs() < 1e-12 {
            if s0 < slab.lo || s0 >= slab.hi {
                return None;
            }
        } else {
            let (a, b) = ((slab.lo - s0) / ds, (slab.hi - s0) / ds);
            lo = lo.max(a.min(b));
            hi = hi.min(a.max(b));
        }
        (lo <= hi).then_some((lo - self.step, hi + self.step))
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

    /// Visits the grid samples of `range` inside `slab` in order, in voxel index coordinates,
    /// jumping over bricks that `empty` rules out; stops when `visit` returns false.
    fn march(
        &self,
        (o, d): ([f64; 3], [f64; 3]),
        slab: &Placement,
        range: (f64, f64),
        empty: impl Fn(usize) -> bool,
        mut visit: impl FnMut([f64; 3]) -> bool,
    ) {
        let dir_index: [f64; 3] = std::array::from_fn(|m| d[m] / self.spacing[m]);
        let (mut n, last) = self.samples(range);
        while n <= last {
            let t = n as f64 * self.step;
            let p: [f64; 3] = std::array::from_fn(|m| o[m] + t * d[m]);
            n += 1;
            if !self.inside(p, slab) {
                continue;
            }
            let q: [f64; 3] = std::array::from_fn(|m| p[m] / self.spacing[m]);
            let b = self.bricks.index(q);
            if empty(self.bricks.linear(b)) {
                let skip = Bricks::exit(q, dir_index, b);
                n = n.max(((t + skip) / self.step).ceil() as i64);
                continue;
            }
            if !visit(q) {
                return;
            }
        }
    }

    fn composite(
        &self,
        ray: ([f64; 3], [f64; 3]),
        slab: &Placement,
        range: (f64, f64),
        faint: bool,
        acc: &mut [f32; 4],
    ) {
        let k = if faint { GHOST } else { 1.0 };
        let shading = self.params.shading;
        self.march(
            ray,
            slab,
            range,
            |b| self.transparent[b],
            |q| {
                let (v, g) = if shading {
                    self.it.sample_gradient(q)
                } else {
                    (self.it.sample(q), [0.0; 3])
                };
                let c = if v.is_nan() {
                    [0.0; 4]
                } else {
                    self.transfer.rgba(v)
                };
                if c[3] > 0.0 {
                    let light = if shading {
                        shade(g, self.spacing, ray.1)
                    } else {
                        1.0
                    };
                    let w = (1.0 - acc[3]) * k;
                    for i in 0..3 {
                        acc[i] += w * c[i] * light;
                    }
                    acc[3] += w * c[3];
                }
                acc[3] < OPAQUE
            },
        );
    }

    fn maximum(
        &self,
        ray: ([f64; 3], [f64; 3]),
        slab: &Placement,
        range: (f64, f64),
        faint: bool,
        best: &mut (f32, bool),
    ) {
        let top = std::cell::Cell::new(*best);
        self.march(
            ray,
            slab,
            range,
            |b| self.bricks.max[b] <= top.get().0,
            |q| {
                let v = self.it.sample(q);
                if v > top.get().0 {
                    top.set((v, faint));
                }
                true
            },
        );
        *best = top.get();
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
