//! The exploded view (paper §3, step 3): a CPU ray caster for slabs pulled apart along their
//! axis, with cut faces that show the cross-section at every cut, direct volume rendering or
//! maximum intensity projection, empty-space skipping, early ray termination, optional shading,
//! a camera that frames what is drawn, and outlines (where they are seen) and labels drawn with
//! tiny-skia. [`mod@slice`] draws the cross-sections themselves.
//!
//! Every pixel is computed on its own from the same inputs, so images are identical whatever the
//! number of threads.

mod camera;
mod layout;
mod overlay;
pub mod sheet;
pub mod slice;
mod transfer;

use rayon::prelude::*;
use serde::Serialize;
use tiny_skia::Pixmap;

pub use camera::{Camera, CameraParams};
pub use layout::{DEFAULT_SPREAD, Gap, Layout, MIN_GAP, Placement, Stack};
pub use transfer::{Colormap, HISTOGRAM_BINS, Look, MAX_LABELS, Preset, Transfer, label_values};

use crate::error::{Error, Result};
use crate::geometry::{dot, min_spacing};
use crate::progress::Monitor;
use crate::volume::Volume;
use crate::volume::interpolate::Interpolator;
use overlay::Aabb;

/// How samples become pixels.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Mode {
    /// Direct volume rendering with cut faces: where a ray enters a slab through a cut, the
    /// cross-section there, through the colour window and opaque off the background, as a
    /// surface; the volume behind it where it is clear.
    Cut,
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
    /// Cut faces, DVR or MIP.
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
    /// Outline this slab in the highlight colour.
    pub highlight: Option<usize>,
    /// Draw the slabs other than the highlighted one faint.
    pub fade: bool,
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
            mode: Mode::Cut,
            preset: Preset::Auto,
            colormap: Colormap::Grey,
            window: None,
            camera: CameraParams::default(),
            shading: true,
            step: 1.0,
            outlines: true,
            labels: true,
            highlight: None,
            fade: false,
            solo: false,
            background: [12, 12, 18],
        }
    }
}

impl RenderParams {
    /// Checks what no render can do: an image too small or too large, a step, zoom or angle
    /// out of range.
    pub fn check(&self) -> Result<()> {
        let (w, h) = (self.width, self.height);
        if w == 0 || h == 0 || u64::from(w) * u64::from(h) > MAX_PIXELS {
            return Err(Error::invalid(
                "size",
                format!("{w}x{h}"),
                format!("between 1x1 and {MAX_PIXELS} pixels"),
            ));
        }
        if !(self.step.is_finite() && self.step > 0.0) {
            return Err(Error::invalid("step", self.step, "a positive number"));
        }
        let c = &self.camera;
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
        Ok(())
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

/// The light a cut face gets whatever its angle to the view (the rest grows with it).
const FACE_AMBIENT: f64 = 0.75;

/// The camera leaves this fraction of the image free on each side of the scene.
const MARGIN: f64 = 0.04;

/// And this fraction more on the left, for the slab numbers.
const LABEL_ROOM: f64 = 0.05;

/// A rendered image and the camera that made it.
pub struct Image {
    /// RGBA pixels (opaque, so premultiplied equals straight).
    pub pixmap: Pixmap,
    /// The camera, to project world points into the image.
    pub camera: Camera,
    /// Per pixel, row by row: how far along its ray the image turns half opaque, mm (infinite
    /// where it never does), to tell what is in front of what.
    pub depth: Vec<f32>,
    /// The colour window the transfer function used.
    pub window: (f32, f32),
}

impl Image {
    /// The image as PNG bytes.
    pub fn png(&self) -> Result<Vec<u8>> {
        encode(&self.pixmap, ImageOutput::Png)
    }

    /// The image encoded as `format` asks.
    pub fn encode(&self, format: ImageOutput) -> Result<Vec<u8>> {
        encode(&self.pixmap, format)
    }
}

/// `pixmap` (opaque) encoded as `format` asks.
pub fn encode(pixmap: &Pixmap, format: ImageOutput) -> Result<Vec<u8>> {
    match format {
        ImageOutput::Png => pixmap
            .encode_png()
            .map_err(|e| Error::Encode(format!("PNG: {e}"))),
        ImageOutput::Jpeg => {
            let rgb: Vec<u8> = pixmap
                .data()
                .chunks_exact(4)
                .flat_map(|p| [p[0], p[1], p[2]])
                .collect();
            let mut out = Vec::new();
            image::codecs::jpeg::JpegEncoder::new_with_quality(&mut out, JPEG_QUALITY)
                .encode(
                    &rgb,
                    pixmap.width(),
                    pixmap.height(),
                    image::ExtendedColorType::Rgb8,
                )
                .map_err(|e| Error::Encode(format!("JPEG: {e}")))?;
            Ok(out)
        }
    }
}

/// Draws `image` centred in the area `(x, y, width, height)` of `canvas` (its top left within the
/// area when it is larger); returns where its top left went.
pub fn paste_centred(
    canvas: &mut Pixmap,
    image: &Pixmap,
    (x, y, width, height): (u32, u32, u32, u32),
) -> (u32, u32) {
    let at = (
        x + width.saturating_sub(image.width()) / 2,
        y + height.saturating_sub(image.height()) / 2,
    );
    canvas.draw_pixmap(
        at.0 as i32,
        at.1 as i32,
        image.as_ref(),
        &tiny_skia::PixmapPaint::default(),
        tiny_skia::Transform::identity(),
        None,
    );
    at
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

    /// The box around the bricks that are not `transparent`, in mm: what a render shows
    /// (the whole volume when nothing is).
    fn content(&self, transparent: &[bool], spacing: [f64; 3], extent: [f64; 3]) -> Aabb {
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
        Aabb {
            lo: std::array::from_fn(|m| ((lo[m] * BRICK) as f64 * spacing[m]).min(extent[m])),
            hi: std::array::from_fn(|m| ((hi[m] * BRICK) as f64 * spacing[m]).min(extent[m])),
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

/// What a render of one volume can reuse: the brick grid, the value histogram and, for a
/// label volume, its labels.
pub struct Renderer<'a> {
    volume: &'a Volume,
    bricks: Bricks,
    histogram: Vec<u64>,
    labels: Option<Vec<(f32, u64)>>,
}

/// Everything the per-pixel loop reads.
struct Frame<'a> {
    it: Interpolator<'a>,
    bricks: &'a Bricks,
    transparent: Vec<bool>,
    transfer: Transfer,
    labels: bool,
    layout: &'a Layout,
    /// Per slab, whether its start and end cuts are exposed.
    exposed: Vec<(bool, bool)>,
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
            labels: label_values(volume),
        })
    }

    /// The labels of a label volume (integers with few distinct values), with their counts.
    pub fn labels(&self) -> Option<&[(f32, u64)]> {
        self.labels.as_deref()
    }

    /// The transfer function of `look` for samples `step` mm apart: a label volume's
    /// categorical colours when `look` is the automatic preset with no window.
    pub fn transfer(&self, look: Look, step: f64) -> Result<Transfer> {
        let reference = min_spacing(self.volume.spacing());
        match &self.labels {
            Some(labels) if look.preset == Preset::Auto && look.window.is_none() => {
                Transfer::for_labels(labels, step, reference)
            }
            _ => Transfer::with_histogram(
                self.volume.stats(),
                &self.histogram,
                look,
                step,
                reference,
            ),
        }
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
        params.check()?;
        let (w, h) = (params.width, params.height);
        let spacing = self.volume.spacing();
        let reference = min_spacing(spacing);
        let step = params.step * reference;
        let look = Look {
            preset: params.preset,
            colormap: params.colormap,
            window: params.window,
        };
        let transfer = self.transfer(look, step)?;
        let transparent: Vec<bool> = self
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
        let mut camera =
            Camera::oriented(center, radius, layout.axis, display, &params.camera, w, h)?;
        let room = if params.labels { LABEL_ROOM } else { 0.0 };
        let content = self.bricks.content(&transparent, spacing, extent);
        camera.fit(
            &overlay::scene_points(layout, &content, params),
            MARGIN,
            room,
        );
        let frame = Frame {
            it: Interpolator::new(self.volume),
            bricks: &self.bricks,
            transparent,
            labels: transfer.is_labels(),
            transfer,
            layout,
            exposed: exposed_cuts(layout, params),
            params,
            spacing,
            extent,
            step,
        };
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
                    let (c, t) = frame.trace(o, d);
                    for k in 0..3 {
                        px[k] =
                            ((c[k] + (1.0 - c[3]) * bg[k]).clamp(0.0, 1.0) * 255.0).round() as u8;
                    }
                    px[3] = 255;
                    *z = t;
                }
                monitor.advance(1)
            })?;
        let mut image = Image {
            pixmap,
            camera,
            depth,
            window: frame.transfer.window(),
        };
        if params.outlines || params.labels {
            overlay::draw(&mut image, layout, &content, params, step);
        }
        if params.labels && t.known {
            overlay::triad(&mut image, |w| t.physical_direction(w, spacing), params);
        }
        Ok(image)
    }
}

/// Per slab of `layout`, whether the cuts at its start and its end are exposed: pulled away
/// from the neighbour there, or the neighbour not drawn (the first slab's start and the last
/// one's end are the volume's, not cuts).
fn exposed_cuts(layout: &Layout, params: &RenderParams) -> Vec<(bool, bool)> {
    let slabs = &layout.slabs;
    let shown = |j: usize| !params.solo || params.highlight.is_none_or(|h| h == j);
    (0..slabs.len())
        .map(|i| {
            let apart = |j: usize| !shown(j) || (slabs[j].offset - slabs[i].offset).abs() > 1e-9;
            (i > 0 && apart(i - 1), i + 1 < slabs.len() && apart(i + 1))
        })
        .collect()
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

impl Frame<'_> {
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
            if !visit(q, t) {
                return;
            }
        }
    }

    /// The cut face where the ray enters a slab at parameter `t`: the section there through
    /// the face colours, lit as a surface facing the axis.
    fn face(&self, (o, d): ([f64; 3], [f64; 3]), t: f64, k: f32, ray: &mut Ray) {
        let q: [f64; 3] = std::array::from_fn(|m| {
            ((o[m] + t * d[m]).clamp(0.0, self.extent[m])) / self.spacing[m]
        });
        let c = self.transfer.face(self.value(q));
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
                        shade(g, self.spacing, ray.1)
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
pub(crate) fn sample(it: &Interpolator, q: [f64; 3], labels: bool) -> f32 {
    if labels {
        it.data[it.nearest(q)]
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
