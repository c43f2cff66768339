//! The exploded view (paper §3, step 3): a CPU ray caster for slabs pulled apart along their
//! axis, with cut faces that show the cross-section at every cut, direct volume rendering or
//! maximum intensity projection, empty-space skipping, early ray termination, optional shading,
//! a camera that frames what is drawn, and outlines (where they are seen) and labels drawn with
//! tiny-skia. [`mod@slice`] draws the cross-sections themselves; [`chart`] draws charts with axes
//! and heat maps with colour scales for slides.
//!
//! Every pixel is computed on its own from the same inputs, so images are identical whatever the
//! number of threads.

mod camera;
pub mod chart;
mod figure;
mod layout;
mod output;
mod overlay;
mod pyramid;
mod ray;
pub mod sheet;
pub mod slice;
mod transfer;

use std::sync::{Arc, OnceLock};

use serde::Serialize;

pub use camera::{Camera, CameraParams};
pub use figure::draw_figure;
pub use layout::{DEFAULT_SPREAD, Gap, Layout, MIN_GAP, Placement, Stack};
pub use output::{Image, ImageOutput, encode, paste_centred};
pub use pyramid::{VOXELS_PER_PIXEL, halving_grids, pyramid_level, pyramid_level_in};
pub use transfer::{
    Colormap, HISTOGRAM_BINS, MAX_LABELS, Preset, Transfer, TransferChoice, label_values,
};

use crate::error::{Error, Result};
use crate::geometry::{DisplayFrame, dot, min_spacing};
use crate::progress::Monitor;
use crate::volume::Volume;
use crate::volume::interpolate::Interpolator;
use overlay::Aabb;
use pyramid::Grid;
pub(crate) use ray::sample;
use ray::{Bricks, Frame};

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

/// Slabs may be moved at most this many times the volume's diagonal.
const MAX_REACH: f64 = 100.0;

/// The camera leaves this fraction of the image free on each side of the scene.
const MARGIN: f64 = 0.04;

/// And this fraction more on the left, for the slab numbers.
const LABEL_ROOM: f64 = 0.05;

/// What a render of one volume can reuse: per pyramid level, its voxels and brick grid (made
/// when a render first reads that level); level 0's value histogram and, for a label volume,
/// its labels, which every level is coloured by.
pub struct Renderer<'a> {
    volume: &'a Volume,
    levels: Vec<OnceLock<Level>>,
    histogram: Vec<u64>,
    labels: Option<Vec<(f32, u64)>>,
}

/// A pyramid level a render reads: the level's volume (none for level 0, the renderer's own)
/// and its bricks.
struct Level {
    volume: Option<Arc<Volume>>,
    bricks: Bricks,
}

/// One pyramid level's way of drawing a render: the level's voxels, bricks and grid, the sample
/// step there, the transfer function for that step, the bricks it leaves clear, the box of what
/// is not (level 0's mm), the camera that frames it and the coarsest pyramid level that
/// camera's pixels allow.
struct Scene<'r> {
    level: usize,
    volume: &'r Volume,
    bricks: &'r Bricks,
    grid: Grid,
    step: f64,
    transfer: Transfer,
    transparent: Vec<bool>,
    content: Aabb,
    camera: Camera,
    allows: usize,
}

impl<'a> Renderer<'a> {
    /// Prepares `volume` for rendering (one pass over its voxels, for the histogram; the bricks
    /// of a pyramid level are made when a render first reads it).
    pub fn new(volume: &'a Volume) -> Result<Self> {
        volume.require_data()?;
        Ok(Self {
            volume,
            levels: (0..=volume.coarser_levels())
                .map(|_| OnceLock::new())
                .collect(),
            histogram: volume.histogram(HISTOGRAM_BINS)?,
            labels: volume.labels().map(<[_]>::to_vec),
        })
    }

    /// Pyramid level `k`'s volume and bricks, made the first time they are asked for.
    fn level(&self, k: usize) -> (&Volume, &Bricks) {
        let level = self.levels[k].get_or_init(|| {
            let volume = (k > 0).then(|| self.volume.coarser(k));
            let bricks = Bricks::new(volume.as_deref().unwrap_or(self.volume));
            Level { volume, bricks }
        });
        (
            level.volume.as_deref().unwrap_or(self.volume),
            &level.bricks,
        )
    }

    /// The labels of a label volume (integers with few distinct values), with their counts.
    pub fn labels(&self) -> Option<&[(f32, u64)]> {
        self.labels.as_deref()
    }

    /// The transfer function of `look` for samples `step` mm apart: a label volume's
    /// categorical colours when `look` is the automatic preset with no window.
    pub fn transfer(&self, look: TransferChoice, step: f64) -> Result<Transfer> {
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

    /// Renders `layout` with `params`; reports one unit per image row to `monitor`. The
    /// render reads pyramid level k only where level k − 1 gives at least
    /// [`VOXELS_PER_PIXEL`] voxels per pixel along both screen axes ([`pyramid_level`]); the
    /// image says which it read.
    pub fn render(
        &self,
        layout: &Layout,
        params: &RenderParams,
        monitor: &Monitor,
    ) -> Result<Image> {
        self.render_with(layout, params, None, monitor)
    }

    /// As [`render`](Self::render), reading pyramid level `k` (at most the last) whatever the
    /// pixels allow: the same framing, for comparing levels.
    pub fn render_at(
        &self,
        layout: &Layout,
        params: &RenderParams,
        k: usize,
        monitor: &Monitor,
    ) -> Result<Image> {
        self.render_with(layout, params, Some(k.min(self.levels.len() - 1)), monitor)
    }

    fn render_with(
        &self,
        layout: &Layout,
        params: &RenderParams,
        level: Option<usize>,
        monitor: &Monitor,
    ) -> Result<Image> {
        params.check()?;
        let look = TransferChoice {
            preset: params.preset,
            colormap: params.colormap,
            window: params.window,
        };
        let scene = match level {
            Some(k) => self.scene(k, layout, params, look)?,
            None => self.choose(layout, params, look)?,
        };
        let Scene {
            level,
            volume,
            bricks,
            grid,
            step,
            transfer,
            transparent,
            content,
            camera,
            ..
        } = scene;
        let extent = self.extent();
        let (labels, window) = (transfer.is_labels(), transfer.window());
        let exposed = exposed_cuts(layout, params);
        let dims = volume.dims();
        let (pixmap, depth) = crate::volume::with_voxels!(volume.data(), |data| {
            Frame {
                it: Interpolator::over(data, dims),
                bricks,
                transparent,
                labels,
                transfer,
                layout,
                exposed,
                params,
                grid,
                extent,
                step,
            }
            .cast(&camera, params, monitor)
        })?;
        let mut image = Image {
            pixmap,
            camera,
            depth,
            window,
            pyramid_level: level,
        };
        self.draw_overlays(&mut image, layout, &content, params, step);
        Ok(image)
    }

    /// The scene of the pyramid level the render reads. The camera that frames the whole box
    /// has pixels at least as large as one that frames less, so the level its pixels allow is
    /// where the search starts; it then comes down, level by level where needed, until the
    /// camera framing what that level shows allows it. Levels are read only once chosen, so a
    /// render that reads a coarse level never makes level 0's bricks.
    fn choose(
        &self,
        layout: &Layout,
        params: &RenderParams,
        look: TransferChoice,
    ) -> Result<Scene<'_>> {
        let extent = self.extent();
        let (_, mut level) = self.camera(layout, params, &Aabb::of(extent))?;
        loop {
            let scene = self.scene(level, layout, params, look)?;
            if scene.allows >= level {
                return Ok(scene);
            }
            level = scene.allows;
        }
    }

    /// The scene of pyramid level `k`.
    fn scene(
        &self,
        k: usize,
        layout: &Layout,
        params: &RenderParams,
        look: TransferChoice,
    ) -> Result<Scene<'_>> {
        let (volume, bricks) = self.level(k);
        let grid = Grid::of(self.volume, volume);
        let step = params.step * min_spacing(grid.spacing);
        let transfer = self.transfer(look, step)?;
        let transparent = bricks.transparent(&transfer);
        let extent = self.extent();
        let content = bricks.content(&transparent, &grid, extent);
        let (camera, allows) = self.camera(layout, params, &content)?;
        Ok(Scene {
            level: k,
            volume,
            bricks,
            grid,
            step,
            transfer,
            transparent,
            content,
            camera,
            allows,
        })
    }

    /// Level 0's box, mm from voxel (0, 0, 0) to the last (as [`framed`] puts it).
    fn extent(&self) -> [f64; 3] {
        let (dims, spacing) = (self.volume.dims(), self.volume.spacing());
        std::array::from_fn(|m| (dims[m] - 1) as f64 * spacing[m])
    }

    /// The camera of `params` around this volume with `layout`'s slabs moved, fitted to
    /// `content`, and the coarsest pyramid level its pixels allow (see [`framed`]).
    fn camera(
        &self,
        layout: &Layout,
        params: &RenderParams,
        content: &Aabb,
    ) -> Result<(Camera, usize)> {
        let grids = self.volume.level_grids();
        let display = (self.volume.transform()).display_frame(layout.axis, self.volume.spacing());
        framed((&grids, display), layout, params, content)
    }

    /// Draws what `params` asks over `image`: outlines and slab numbers, and the orientation
    /// triad when the volume's orientation is known.
    fn draw_overlays(
        &self,
        image: &mut Image,
        layout: &Layout,
        content: &Aabb,
        params: &RenderParams,
        step: f64,
    ) {
        if params.outlines || params.labels {
            overlay::draw(image, layout, content, params, step);
        }
        let t = self.volume.transform();
        if params.labels && t.known {
            let spacing = self.volume.spacing();
            overlay::triad(image, |w| t.physical_direction(w, spacing), params);
        }
    }
}

/// The camera of `params` around a volume whose pyramid levels have the dimensions and spacing
/// `grids` (level 0's first; shown in the frame `display` when its orientation is known) with
/// `layout`'s slabs moved, fitted to what is drawn: `content` (the box of what is not clear, mm)
/// and the labels' room; and the coarsest pyramid level its pixels allow ([`pyramid_level_in`],
/// at the scene's nearest depth for a perspective camera). Slabs moved absurdly far are an error.
fn framed(
    (grids, display): (&[pyramid::LevelGrid], Option<DisplayFrame>),
    layout: &Layout,
    params: &RenderParams,
    content: &Aabb,
) -> Result<(Camera, usize)> {
    let (dims, spacing) = grids[0];
    let extent: [f64; 3] = std::array::from_fn(|m| (dims[m] - 1) as f64 * spacing[m]);
    let reference = min_spacing(spacing);
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
    let (w, h) = (params.width, params.height);
    let mut camera = Camera::oriented(center, radius, layout.axis, display, &params.camera, w, h)?;
    let room = if params.labels { LABEL_ROOM } else { 0.0 };
    let points = overlay::scene_points(layout, content, params);
    camera.fit(&points, MARGIN, room);
    let pixel = camera.pixel_size(&points);
    let level = pyramid_level_in(pixel, camera.axes(), grids);
    Ok((camera, level))
}

#[cfg(test)]
mod tests;

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
