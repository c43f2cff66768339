//! The render request: the exploded view of an analysis's slabs, or the strip of their faces,
//! drawn from the level the analysis partitioned.

use tiny_skia::Pixmap;

use crate::error::{Error, Result, Value};
use crate::geometry::min_spacing;
use crate::params::Scene;
use crate::partition::{Histories, Partition, Slab};
use crate::progress::Monitor;
use crate::render::{Gap, Image, Layout, Renderer, Stack, TransferChoice, slice};

use super::Analysed;

/// A picture of an analysis's slabs: what it shows and how.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderRequest {
    /// The camera, look, size and gaps of the exploded view; of it, the strip of faces takes
    /// only the size and the look.
    pub scene: Scene,
    /// Instead of the exploded view, the faces of every slab: its last slice above its first, a
    /// column a slab, fit into the size (`render --faces`).
    pub faces: bool,
}

/// What an exploded view shows: the whole volume, a partition's slabs, or the slabs of a
/// history an interactive front end steps through (the TUI's).
#[derive(Clone, Copy)]
pub enum Shown<'a> {
    /// The whole volume as one slab, seen around this axis (a unit physical direction): the
    /// picture before anything is partitioned.
    Whole([f64; 3]),
    /// A partition's slabs, the similarity gaps sized by the NMI at its boundaries.
    Partition(&'a Partition),
    /// Slabs of `histories`' stack, the similarity gaps sized by `nmi` (one per boundary) when
    /// known (a bottom-up step's), else by the NMI the histories count at their boundaries.
    Stepped {
        /// The histories the slabs are of.
        histories: &'a Histories,
        /// The slabs, in slice order.
        slabs: &'a [Slab],
        /// The NMI at each boundary, where known.
        nmi: Option<&'a [f64]>,
    },
}

impl Shown<'_> {
    /// How many slabs it shows (the whole volume: one).
    #[must_use]
    pub fn count(&self) -> usize {
        match self {
            Self::Whole(_) => 1,
            Self::Partition(p) => p.slabs.len(),
            Self::Stepped { slabs, .. } => slabs.len(),
        }
    }

    /// Its slabs pulled apart by `gap` and `spread`; the NMI at the stepped slabs' boundaries
    /// is counted only when similarity gaps need it and it is not known.
    fn layout(&self, gap: Gap, spread: f64, monitor: &Monitor) -> Result<Layout> {
        Ok(match *self {
            Self::Whole(axis) => Layout::whole(axis),
            Self::Partition(p) => Layout::exploded(p, gap, spread),
            Self::Stepped {
                histories,
                slabs,
                nmi,
            } => {
                let counted = match (nmi, gap) {
                    (None, Gap::Similarity) => Some(histories.boundary_nmi(slabs, monitor)?),
                    _ => None,
                };
                let stack = Stack::of_slices(histories.stack());
                Layout::from_slabs(&stack, slabs, nmi.or(counted.as_deref()), gap, spread)
            }
        })
    }
}

/// The room around the tiles of the strip of faces, pixels: a gap before every column and after
/// the last, and 12 in height (a gap above, between and below the two rows).
const FACES_GAP: u32 = 4;

/// The tile each face of `slabs` slabs is fit into, in a strip of `(width, height)` pixels: an
/// error about `size` when a tile would be under 8 pixels either way.
pub fn faces_tile((width, height): (u32, u32), slabs: usize) -> Result<(u32, u32)> {
    let k = u32::try_from(slabs).unwrap_or(u32::MAX);
    let tile = (
        width.saturating_sub(FACES_GAP * k.saturating_add(1)) / k.max(1),
        height.saturating_sub(3 * FACES_GAP) / 2,
    );
    if tile.0 < 8 || tile.1 < 8 {
        return Err(Error::Unfit {
            parameter: "size",
            value: Value::Size(width, height),
            problem: format!("too small for the faces of {k} slabs"),
        });
    }
    Ok(tile)
}

impl RenderRequest {
    /// The picture of `analysed`'s slabs, drawn from the level it partitioned.
    pub fn render(&self, analysed: &Analysed, monitor: &Monitor) -> Result<Pixmap> {
        self.draw(analysed.level(), &analysed.analysis.partition, monitor)
    }

    /// The picture of `part`'s slabs of `level` (the volume or pyramid level partitioned). A
    /// slab to highlight past the slabs is an error about `highlight`.
    pub fn draw(
        &self,
        level: &crate::volume::Volume,
        part: &Partition,
        monitor: &Monitor,
    ) -> Result<Pixmap> {
        let params = &self.scene.params;
        if self.faces {
            let look = TransferChoice {
                preset: params.preset,
                colormap: params.colormap,
                window: params.window,
            };
            let tile = faces_tile((params.width, params.height), part.slabs.len())?;
            monitor.check()?;
            let renderer = Renderer::new(level)?;
            let transfer = renderer.transfer(look, min_spacing(level.spacing()))?;
            return slice::faces(level, &transfer, &Stack::of(part), &part.slabs, tile);
        }
        let renderer = Renderer::new(level)?;
        Ok(self
            .exploded(&renderer, &Shown::Partition(part), monitor)?
            .pixmap)
    }

    /// The exploded view of `shown` drawn by `renderer` (made once for its level by a front end
    /// that draws many pictures of it, as the TUI does), with the colour window it used. A slab
    /// to highlight past the slabs is an error about `highlight`; [`faces`](Self::faces) is not
    /// read.
    pub fn exploded(&self, renderer: &Renderer, shown: &Shown, monitor: &Monitor) -> Result<Image> {
        let slabs = shown.count();
        if let Some(h) = self.scene.params.highlight
            && h >= slabs
        {
            return Err(Error::Unfit {
                parameter: "highlight",
                value: Value::Whole(h as u64),
                problem: format!("there are only {slabs} slabs (numbered from 0)"),
            });
        }
        let layout = shown.layout(self.scene.gap, self.scene.spread, monitor)?;
        renderer.render(&layout, &self.scene.params, monitor)
    }
}
